/* fuzz_bsls.c — .bsls bytes through bs_levelset_grid_load. */
#include <stdio.h>

#include "bs_levelset.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  fuzz_write_temp(data, size, ".bsls", path, sizeof path);
  bs_levelset *ls = NULL;
  bs_error err = {0};
  int rc = bs_levelset_grid_load(path, &ls, &err);
  remove(path);
  fuzz_check("bsls", rc, &err);
  bs_levelset_destroy(&ls);
  return 0;
}
