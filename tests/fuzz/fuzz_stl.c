/* fuzz_stl.c — .stl bytes through bs_shim_read_surface. */
#include <stdio.h>

#include "bs_shim.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  fuzz_write_temp(data, size, ".stl", path, sizeof path);
  double *pts = NULL;
  int32_t *tris = NULL;
  int64_t np = 0, nt = 0;
  bs_error err = {0};
  int rc = bs_shim_read_surface(path, &pts, &np, &tris, &nt, &err);
  remove(path);
  fuzz_check("stl", rc, &err);
  bs_shim_free(pts);
  bs_shim_free(tris);
  return 0;
}
