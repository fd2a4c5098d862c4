/* fuzz_msh.c — .msh bytes through bs_mesh_read (the .msh pre-check, then Gmsh).
 * Odd-sized inputs are read with merge_coincident = 1. */
#include <stdio.h>

#include "bs_mesh.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char path[64];
  fuzz_write_temp(data, size, ".msh", path, sizeof path);
  bs_mesh_read_opts opts = {.merge_coincident = (int)(size & 1)};
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, &opts, &m, &err);
  remove(path);
  fuzz_check("msh", rc, &err);
  bs_mesh_destroy(&m);
  return 0;
}
