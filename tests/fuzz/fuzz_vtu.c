/* fuzz_vtu.c — .vtu bytes through bs_vtu_read. */
#include "bs_vtu_read.h"
#include "fuzz_util.h"

static int read_vtu(const char *path, bs_error *err) {
  bs_vtu *v = NULL;
  int rc = bs_vtu_read(path, &v, err);
  bs_vtu_destroy(&v);
  return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_file(data, size, ".vtu", "vtu", read_vtu);
  return 0;
}
