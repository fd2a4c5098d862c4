/* fuzz_pvd.c — .pvd bytes through bs_pvd_read. */
#include <stdio.h>

#include "bs_vtu_read.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  fuzz_write_temp(data, size, ".pvd", path, sizeof path);
  bs_pvd *p = NULL;
  bs_error err = {0};
  int rc = bs_pvd_read(path, &p, &err);
  remove(path);
  fuzz_check("pvd", rc, &err);
  bs_pvd_destroy(&p);
  return 0;
}
