/* fuzz_vtu.c — .vtu bytes through bs_vtu_read. */
#include <stdio.h>

#include "bs_vtu_read.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  fuzz_write_temp(data, size, ".vtu", path, sizeof path);
  bs_vtu *v = NULL;
  bs_error err = {0};
  int rc = bs_vtu_read(path, &v, &err);
  remove(path);
  fuzz_check("vtu", rc, &err);
  bs_vtu_destroy(&v);
  return 0;
}
