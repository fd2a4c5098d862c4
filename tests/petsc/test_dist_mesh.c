/* test_dist_mesh: distributed meshes (bs_dmesh.h) against the serial reader
 * on 1 and 2 ranks: the structured box (same vertices, groups, volume), a
 * .msh with physical groups (same groups, vertex counts and volume), uniform
 * refinement (groups kept, volume kept, 8x the tets), and bad input. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_dmesh.h"
#include "dist_check.h"

/* Group names, dimensions, global vertex counts and cell counts of d equal m's;
 * so do the total volume, cell and vertex counts. */
static void same_as_serial(const bs_dmesh *d, const bs_mesh *m, const char *what) {
  bs_error err = {0};
  double vol = 0;
  CHECK_OK(bs_dmesh_volume(d, &vol, &err), err);
  CHECK_REL(vol, bs_mesh_volume(m), 1e-12, what);
  CHECK(d->n_global_cells == m->n_tets, "%s: %lld cells, serial %d", what, (long long)d->n_global_cells, m->n_tets);
  CHECK(d->n_global_vertices == m->n_vertices, "%s: %lld vertices, serial %d", what, (long long)d->n_global_vertices,
        m->n_vertices);
  CHECK(d->n_groups == m->n_groups, "%s: %d groups, serial %d", what, d->n_groups, m->n_groups);
  for (int i = 0; i < m->n_groups; i++) {
    const bs_group *g = &m->groups[i];
    const bs_dgroup *dg = bs_dmesh_group(d, g->name);
    CHECK(dg != NULL, "%s: group \"%s\" missing", what, g->name);
    if (!dg) continue;
    CHECK(dg->dim == g->dim && dg->tag == g->tag, "%s: group \"%s\" is (%d, %d), serial (%d, %d)", what, g->name,
          dg->dim, dg->tag, g->dim, g->tag);
    int64_t n = -1;
    if (g->dim == 3) {
      CHECK_OK(bs_dmesh_group_cells(d, dg, &n, &err), err);
      CHECK(n == g->n_elems, "%s: group \"%s\": %lld cells, serial %d", what, g->name, (long long)n, g->n_elems);
    } else {
      CHECK_OK(bs_dmesh_group_count(d, dg, &n, &err), err);
      CHECK(n == g->n_vertices, "%s: group \"%s\": %lld vertices, serial %d", what, g->name, (long long)n,
            g->n_vertices);
    }
  }
}

/* Every local vertex, owned or ghost, is in a boundary group of the box
 * [lo, hi] exactly when it lies on that face (xmin: x = lo[0], ...). */
static void faces_match(const bs_dmesh *d, const double lo[3], const double hi[3]) {
  static const char *faces[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (int f = 0; f < 6; f++) {
    const bs_dgroup *g = bs_dmesh_group(d, faces[f]);
    CHECK(g != NULL, "no group %s", faces[f]);
    if (!g) continue;
    int wrong = 0;
    for (int32_t v = 0, k = 0; v < d->n_vertices; v++) {
      int in = k < g->n_vertices && g->vertices[k] == v;
      k += in;
      int on = d->x[3 * v + f / 2] == (f % 2 ? hi[f / 2] : lo[f / 2]);
      wrong += in != on;
    }
    CHECK(wrong == 0, "group %s: %d local vertices in it but not on its face, or the reverse", faces[f], wrong);
  }
}

/* The same on the 12^3 cube of cube_stretch, whose partitions have ghost
 * vertices that touch a face through no local face of it. */
static void cube_faces_on_ghosts(void) {
  bs_error err = {0};
  bs_dmesh *d = NULL;
  CHECK_OK(bs_dmesh_load("box:12x12x12:1x1x1", 0, &d, &err), err);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  if (d) faces_match(d, lo, hi);
  bs_dmesh_destroy(&d);
}

/* The box on the ranks is the serial box: its vertices are the serial ones
 * (orig_id gives back the same position exactly), its groups too. */
static void box_matches_serial(void) {
  bs_error err = {0};
  bs_dmesh *d = NULL;
  CHECK_OK(bs_dmesh_load("box:6x3x2:1.2x0.6x0.4", 0, &d, &err), err);
  bs_mesh *m = NULL;
  const double lo[3] = {0, 0, 0}, hi[3] = {1.2, 0.6, 0.4};
  CHECK_OK(bs_mesh_create_box(lo, hi, 6, 3, 2, &m, &err), err);
  if (!d || !m) return;
  same_as_serial(d, m, "box");
  int bad = 0;
  for (int32_t i = 0; i < d->n_vertices; i++) {
    int64_t o = d->orig_id[i];
    if (o < 0 || o >= m->n_vertices || memcmp(d->x + 3 * i, m->x + 3 * o, 3 * sizeof(double))) bad++;
  }
  CHECK(bad == 0, "%d of %d local vertices are not at their serial vertex's position", bad, d->n_vertices);
  CHECK(d->local->n_tets > 0 && d->local->n_tets <= m->n_tets, "%d owned tets", d->local->n_tets);
  faces_match(d, lo, hi);
  bs_dmesh_destroy(&d);
  bs_dmesh_destroy(&d); /* NULL accepted */
  bs_mesh_destroy(&m);
}

/* A .msh written by rank 0 from data/geo/box_hole.geo (two volumes, two
 * surface groups), at a path every rank knows. */
static const char *box_hole_msh(void) {
  static char path[256];
  long pid = getpid();
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  snprintf(path, sizeof path, "/tmp/bs_test_dist_mesh_%ld.msh", pid);
  int rc = 0;
  if (bs_dist_rank() == 0) {
    bs_error err = {0};
    bs_mesh_read_opts opts = {.size = 0.2};
    bs_mesh *m = NULL;
    rc = bs_mesh_read("data/geo/box_hole.geo", &opts, &m, &err);
    if (!rc) rc = bs_mesh_write_msh(m, NULL, path, &err);
    CHECK_OK(rc, err);
    bs_mesh_destroy(&m);
  }
  MPI_Bcast(&rc, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return rc ? NULL : path;
}

static void msh_groups_match_serial(void) {
  const char *path = box_hole_msh();
  if (!path) return;
  bs_error err = {0};
  bs_mesh *m = NULL;
  bs_dmesh *d = NULL;
  CHECK_OK(bs_mesh_read(path, NULL, &m, &err), err);
  CHECK_OK(bs_dmesh_read_msh(path, 0, &d, &err), err);
  if (m && d) same_as_serial(d, m, "box_hole.msh");
  if (d) CHECK(d->orig_id[0] == -1, "a .msh read by PETSc has no serial ids");
  /* Refinement keeps the groups and the volume, 8x the cells. */
  bs_dmesh *f = NULL;
  bs_mesh *mf = NULL;
  CHECK_OK(bs_dmesh_read_msh(path, 1, &f, &err), err);
  if (m) CHECK_OK(bs_mesh_refine(m, &mf, &err), err);
  if (f && mf) same_as_serial(f, mf, "box_hole.msh refined");
  bs_dmesh_destroy(&f);
  bs_mesh_destroy(&mf);
  bs_dmesh_destroy(&d);
  bs_mesh_destroy(&m);
  MPI_Barrier(MPI_COMM_WORLD);
  if (bs_dist_rank() == 0) remove(path);
}

/* Two refinements of the box: 64x the tets, the serial refinement's groups. */
static void box_refined_twice(void) {
  bs_error err = {0};
  bs_dmesh *d = NULL;
  CHECK_OK(bs_dmesh_load("box:3x2x2:1x0.5x0.5", 2, &d, &err), err);
  bs_mesh *m = NULL;
  const int cells[3] = {3, 2, 2};
  const double size[3] = {1, 0.5, 0.5};
  CHECK_OK(bs_mesh_create_box_refined(size, cells, 2, &m, &err), err);
  if (d && m) same_as_serial(d, m, "box refined twice");
  if (d) CHECK(d->n_global_cells == 64 * 72, "%lld cells", (long long)d->n_global_cells);
  bs_dmesh_destroy(&d);
  bs_mesh_destroy(&m);
}

static void bad_input(void) {
  bs_error err = {0};
  bs_dmesh *d = NULL;
  int rc = bs_dmesh_load("/nonexistent/mesh.msh", 0, &d, &err);
  CHECK(rc == BS_EIO && strstr(err.msg, "/nonexistent/mesh.msh"), "status %d: %s", rc, err.msg);
  CHECK(d == NULL, "a mesh came back");
  rc = bs_dmesh_load("box:0x2x2", 0, &d, &err);
  CHECK(rc == BS_EINPUT && strstr(err.msg, "box:0x2x2"), "status %d: %s", rc, err.msg);
  rc = bs_dmesh_load("box:2x2x2", -1, &d, &err);
  CHECK(rc == BS_EINPUT && strstr(err.msg, "refine"), "status %d: %s", rc, err.msg);
}

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"box_matches_serial", box_matches_serial},
                                    {"cube_faces_on_ghosts", cube_faces_on_ghosts},
                                    {"msh_groups_match_serial", msh_groups_match_serial},
                                    {"box_refined_twice", box_refined_twice},
                                    {"bad_input", bad_input}};
  return dist_check_main(argc, argv, tests, 5);
}
