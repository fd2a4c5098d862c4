/* fuzz_pvd.c — .pvd bytes through bs_pvd_read. */
#include "bs_vtu_read.h"
#include "fuzz_util.h"

static int read_pvd(const char *path, bs_error *err) {
  bs_pvd *p = NULL;
  int rc = bs_pvd_read(path, &p, err);
  bs_pvd_destroy(&p);
  return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_file(data, size, ".pvd", "pvd", read_pvd);
  return 0;
}
