/* 00_smoke — the smallest program against an installed bigstep: a box mesh
 * of 2 x 3 x 4 cells, its vertex count, and its release.
 *
 *   cc main.c $(pkg-config --cflags --libs bigstep)
 */
#include <stdio.h>

#include <bigstep/bigstep.h>

int main(void) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  bs_mesh *mesh = NULL;
  bs_error err;
  bs_error_clear(&err);
  if (bs_mesh_create_box(lo, hi, 2, 3, 4, &mesh, &err) != BS_OK) {
    fprintf(stderr, "00_smoke: %s\n", err.msg);
    return 1;
  }
  printf("bigstep %s: box mesh with %d vertices\n", BIGSTEP_VERSION, (int)mesh->n_vertices);
  bs_mesh_destroy(&mesh);
  return 0;
}
