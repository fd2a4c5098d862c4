/* fuzz_msh.c — .msh bytes through bs_mesh_read (the .msh pre-check, then
 * Gmsh). Odd-sized inputs are read with merge_coincident = 1. */
#include "bs_mesh.h"
#include "fuzz_util.h"

static int merge;

static int read_msh(const char *path, bs_error *err) {
  bs_mesh_read_opts opts = {.merge_coincident = merge};
  bs_mesh *m = NULL;
  int rc = bs_mesh_read(path, &opts, &m, err);
  bs_mesh_destroy(&m);
  return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  merge = (int)(size & 1);
  fuzz_file(data, size, ".msh", "msh", read_msh);
  return 0;
}
