/* fuzz_bsls.c — .bsls bytes through bs_levelset_grid_load. */
#include "bs_levelset.h"
#include "fuzz_util.h"

static int read_bsls(const char *path, bs_error *err) {
  bs_levelset *ls = NULL;
  int rc = bs_levelset_grid_load(path, &ls, err);
  bs_levelset_destroy(&ls);
  return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_file(data, size, ".bsls", "bsls", read_bsls);
  return 0;
}
