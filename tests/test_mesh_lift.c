/* The quality back end and the limits of issue 44: CGAL's tetrahedral
 * remeshing (bs_shim_tet_remesh, bs__tets_lift) on a zero-volume tet and on
 * a thin slab with a long thin wall, the meshing time budget (a named
 * error, not a hang), and the size chosen for a surface given none (the
 * armadillo scan, when data/meshes has it). */
#define _GNU_SOURCE

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "mesh_internal.h"

/* An octahedron (a square at z = 0, apexes at z = +-1) as two pyramids whose
 * bases are split along different diagonals, made conforming by the flat
 * tet of the four square corners: 4 tets and 1 of zero volume. */
static const double octa_x[6 * 3] = {1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
static const int32_t octa_t[5 * 4] = {0, 1, 2, 4, 0, 2, 3, 4, 1, 2, 3, 5, 1, 3, 0, 5, 0, 1, 2, 3};

Test(mesh_lift, zero_volume_tet_is_remeshed_not_an_error) {
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  cr_expect_eq(bs_mesh_create(6, octa_x, 5, octa_t, 0, NULL, &m, &err), BS_EINPUT, "the flat tet is refused raw");
  bs_mesh_destroy(&m);
  bs_error_clear(&err);
  bs_shim_tet_remesh_out r;
  cr_assert_eq(bs__tets_lift("octahedron", 6, octa_x, 5, octa_t, NULL, 0.0, BS_MESH_MIN_DIHEDRAL, 1, &r, &err), BS_OK,
               "%s", err.msg);
  cr_log_info("lift: %lld tets, dihedral %.2f -> %.2f in %d rounds", (long long)r.n_tets, r.dihedral_in, r.dihedral,
              r.rounds);
  bs_shim_free(r.x), bs_shim_free(r.tets), bs_shim_free(r.subdomain);
  cr_assert_eq(bs__mesh_default_groups("octahedron", 6, octa_x, 5, octa_t, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_log_info("octahedron: %d tets, min dihedral %.2f, volume %.9g", m->n_tets, q.dihedral_min, bs_mesh_volume(m));
  cr_expect_eq(q.n_inverted, 0);
  cr_expect_float_eq(bs_mesh_volume(m), 4.0 / 3.0, 1e-9);
  cr_expect_gt(q.dihedral_min, 1.0);
  bs_mesh_destroy(&m);
}

/* A tet, a flat tet on its face z = 0 (its fourth vertex in that plane, so
 * three of its faces are on the boundary) and a second tet that touches the
 * first at its apex only: the remesher refuses the pinch, so the flat tet is
 * removed instead (the volume stays, no zero-volume error); the pinch is
 * left for the manifold check (bs__boundary_manifold names it). */
Test(mesh_lift, flat_boundary_tet_removed_when_the_remesher_cannot_take_the_mesh) {
  static const double x[8 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 0, 0, 0, 2, 1, 0, 2, 0, 1, 2};
  static const int32_t t[3 * 4] = {0, 1, 2, 3, 0, 1, 2, 4, 3, 5, 6, 7};
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  cr_expect_eq(bs_mesh_create(8, x, 3, t, 0, NULL, &m, &err), BS_EINPUT, "the flat tet is refused raw");
  bs_mesh_destroy(&m);
  bs_error_clear(&err);
  cr_assert_eq(bs__mesh_default_groups("pinched", 8, x, 3, t, &m, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(m->n_tets, 2);
  cr_expect_float_eq(bs_mesh_volume(m), 2.0 / 6.0, 1e-12);
  cr_expect_eq(bs__boundary_manifold(m, "pinched", 0, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "1 vertices where two parts of the body touch") != NULL, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* A box of 3 x 3 x 3 cells whose inner vertex (1, 1, 1) is pushed down to
 * z = 0.08, almost onto the bottom face: flat tets, far under the gate. The lift (boundary kept) passes the gate
 * with the same volume and the box's groups. */
Test(mesh_lift, slivers_lifted_groups_kept) {
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  cr_assert_eq(bs_mesh_create_box((double[3]){0, 0, 0}, (double[3]){3, 3, 3}, 3, 3, 3, &m, &err), BS_OK, "%s",
               err.msg);
  for (int32_t v = 0; v < m->n_vertices; v++) {
    double *p = m->x + 3 * v;
    if (p[0] == 1 && p[1] == 1 && p[2] == 1) p[2] = 0.08;
  }
  bs_mesh_quality q0, q1;
  bs_mesh_quality_compute(m, NULL, &q0);
  cr_assert_eq(q0.n_inverted, 0, "the moved vertex stays inside its star");
  const int32_t xmin0 = bs_mesh_group(m, "xmin")->n_elems;
  double t0 = bs_seconds();
  cr_assert_eq(bs__mesh_lift("box", &m, 1.0, BS_MESH_MIN_DIHEDRAL, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality_compute(m, NULL, &q1);
  cr_log_info("box with slivers: min dihedral %.2f -> %.2f, %d tets, %.2f s", q0.dihedral_min, q1.dihedral_min,
              m->n_tets, bs_seconds() - t0);
  cr_expect_lt(q0.dihedral_min, 5.0);
  cr_expect_geq(q1.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_float_eq(bs_mesh_volume(m), 27.0, 1e-9);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  cr_assert_not_null(bs_mesh_group(m, "xmin"));
  cr_expect_eq(bs_mesh_group(m, "xmin")->n_elems, xmin0, "the boundary triangles are kept");
  cr_expect_eq(bs_mesh_group(m, "body")->n_elems, m->n_tets);
  bs_mesh_destroy(&m);
}

/* A 5 x 5 x 2 box of unit cells with a square hole through it (the cells
 * (2, 2, *) left out: a ring, its boundary a torus), Kuhn-split, its inner
 * vertex (1, 1, 1) pushed down to z = 0.05: slivers. The remesher took only
 * tets whose boundary is one sphere (the Euler relation of CGAL's validity
 * check, which the shim asked of the whole triangulation): it refused this
 * one ("not a valid triangulation"); it lifts it now, boundary kept. */
Test(mesh_lift, a_part_with_a_hole_through_it_is_lifted) {
  enum { N = 5, NZ = 2 };
  double x[3 * (N + 1) * (N + 1) * (NZ + 1)];
  int32_t t[4 * 6 * N * N * NZ], nt = 0;
  static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
  for (int k = 0; k <= NZ; k++)
    for (int j = 0; j <= N; j++)
      for (int i = 0; i <= N; i++) {
        double *p = x + 3 * (i + (N + 1) * (j + (N + 1) * k));
        p[0] = i, p[1] = j, p[2] = (i == 1 && j == 1 && k == 1) ? 0.05 : k;
      }
  for (int k = 0; k < NZ; k++)
    for (int j = 0; j < N; j++)
      for (int i = 0; i < N; i++) {
        if (i == 2 && j == 2) continue;
        int32_t c[8];
        for (int b = 0; b < 8; b++)
          c[b] = (i + (b & 1)) + (N + 1) * ((j + (b >> 1 & 1)) + (N + 1) * (k + (b >> 2 & 1)));
        for (int s = 0; s < 6; s++, nt++)
          for (int a = 0; a < 4; a++) t[4 * nt + a] = c[kuhn[s][a]];
      }
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  cr_assert_eq(bs__mesh_default_groups("ring", (N + 1) * (N + 1) * (NZ + 1), x, nt, t, &m, &err), BS_OK, "%s",
               err.msg);
  bs_mesh_quality q0, q1;
  bs_mesh_quality_compute(m, NULL, &q0);
  cr_assert_eq(bs__mesh_lift("ring", &m, 1.0, BS_MESH_MIN_DIHEDRAL, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality_compute(m, NULL, &q1);
  cr_log_info("ring with slivers: min dihedral %.2f -> %.2f, %d tets", q0.dihedral_min, q1.dihedral_min, m->n_tets);
  cr_expect_lt(q0.dihedral_min, 5.0);
  cr_expect_geq(q1.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_float_eq(bs_mesh_volume(m), N * N * NZ - NZ, 1e-9);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* Two tets that touch at one vertex only are still refused by name. */
Test(mesh_lift, tets_touching_at_a_vertex_are_refused) {
  static const double x[7 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 2, 1, 0, 2, 0, 1, 2};
  static const int32_t t[2 * 4] = {0, 1, 2, 3, 3, 4, 5, 6};
  bs_error err;
  bs_error_clear(&err);
  bs_shim_tet_remesh_opts o = {.size = 1, .target_dihedral = 60};
  bs_shim_tet_remesh_out r;
  cr_expect_eq(bs_shim_tet_remesh("pinch", x, 7, t, 2, NULL, &o, &r, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "not form a valid triangulation") != NULL, "%s", err.msg);
  cr_expect_null(r.x);
}

/* ---- an edge collapse whose stars are not a ball ------------------------ */

/* tests/data/tet/thin_collapse.tets (its header says what it is) into
 * malloc'ed arrays. */
static void read_tets(const char *path, double **x, int32_t *nv, int32_t **t, int32_t *nt) {
  FILE *f = fopen(path, "r");
  cr_assert_not_null(f, "%s", path);
  char line[256];
  long pos = 0;
  while (fgets(line, sizeof line, f) && line[0] == '#') pos = ftell(f);
  fseek(f, pos, SEEK_SET);
  cr_assert_eq(fscanf(f, "%d %d", nv, nt), 2);
  *x = malloc(3 * (size_t)*nv * sizeof **x);
  *t = malloc(4 * (size_t)*nt * sizeof **t);
  cr_assert(*x && *t);
  for (int32_t k = 0; k < 3 * *nv; k++) cr_assert_eq(fscanf(f, "%lf", *x + k), 1);
  for (int32_t k = 0; k < 4 * *nt; k++) cr_assert_eq(fscanf(f, "%d", *t + k), 1);
  fclose(f);
}

/* A thin part of femur.off's mesh (every vertex on the boundary) where CGAL
 * 5.5's remesher, with the boundary remeshed, tries to collapse an edge
 * whose two vertex stars do not make a valid triangulation (they touch at
 * a third vertex only): CGAL then used an uninitialised flag and crashed
 * (SIGSEGV; bigstep mesh info femur.off --size D/25 exited without a word;
 * whether it crashes depends on the stack's garbage). The collapse is
 * refused instead (counted: the shim's fix is in effect), and the remeshing
 * returns valid tets. */
Test(mesh_lift, collapse_of_an_edge_whose_stars_touch_at_a_vertex) {
  double *x = NULL;
  int32_t *t = NULL, nv = 0, nt = 0;
  read_tets(BS_SOURCE_DIR "/tests/data/tet/thin_collapse.tets", &x, &nv, &t, &nt);
  bs_error err;
  bs_error_clear(&err);
  bs_shim_tet_remesh_opts o = {.size = 0.045131187, .protect = BS_SHIM_TET_PROTECT_FEATURES, .feature_angle = 60,
                               .target_dihedral = BS_MESH_MIN_DIHEDRAL, .iterations = BS_LIFT_ROUNDS};
  bs_shim_tet_remesh_out r;
  cr_assert_eq(bs_shim_tet_remesh("thin part", x, nv, t, nt, NULL, &o, &r, &err), BS_OK, "%s", err.msg);
  cr_log_info("thin part: %d tets, %.2f -> %.2f degrees in %d rounds, volume %.6g -> %.6g, %lld collapses refused",
              nt, r.dihedral_in, r.dihedral, r.rounds, r.volume_in, r.volume, (long long)r.collapses_refused);
  cr_expect_geq(r.collapses_refused, 1, "the input makes the remesher try such a collapse");
  bs_mesh *m = NULL;
  cr_assert_eq(bs_mesh_create((int32_t)r.n_vertices, r.x, (int32_t)r.n_tets, r.tets, 0, NULL, &m, &err), BS_OK, "%s",
               err.msg);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  cr_expect_geq(r.dihedral, r.dihedral_in);
  cr_expect_leq(fabs(r.volume - r.volume_in), 0.05 * r.volume_in, "volume %g -> %g", r.volume_in, r.volume);
  bs_mesh_destroy(&m);
  bs_shim_free(r.x), bs_shim_free(r.tets), bs_shim_free(r.subdomain);
  free(x), free(t);
}

/* ---- a thin slab with a long thin wall ------------------------------------ */

static void box_tris(FILE *f, int base, const double lo[3], const double hi[3]) {
  (void)lo, (void)hi;
  static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int k = 0; k < 6; k++)
    fprintf(f, "3 %d %d %d\n3 %d %d %d\n", base + q[k][0], base + q[k][1], base + q[k][2], base + q[k][0],
            base + q[k][2], base + q[k][3]);
}

/* The slab [0, 1] x [0, 1] x [0, 0.1] and the wall [0.49, 0.51] x [0, 1] x
 * [0.05, 0.6] as two overlapping boxes (the repair makes their union):
 * volume 0.1 + 0.02 x 0.5 = 0.11. */
static void write_slab_wall(const char *path) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  const double box[2][2][3] = {{{0, 0, 0}, {1, 1, 0.1}}, {{0.49, 0, 0.05}, {0.51, 1, 0.6}}};
  fprintf(f, "OFF\n16 24 0\n");
  for (int b = 0; b < 2; b++)
    for (int i = 0; i < 8; i++)
      fprintf(f, "%.17g %.17g %.17g\n", box[b][i & 1][0], box[b][(i >> 1) & 1][1], box[b][(i >> 2) & 1][2]);
  for (int b = 0; b < 2; b++) box_tris(f, 8 * b, box[b][0], box[b][1]);
  fclose(f);
}

Test(mesh_lift, thin_slab_with_a_long_thin_wall) {
  char path[96];
  snprintf(path, sizeof path, "/tmp/bs_test_lift_%d_slab.off", (int)getpid());
  write_slab_wall(path);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  bs_surface_report rep = {0};
  double t0 = bs_seconds();
  bs_mesh_read_opts o = {.size = 0.05, .report = &rep};
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const double v = bs_mesh_volume(m);
  cr_log_info("slab with wall at h 0.05: %d tets, min dihedral %.2f, volume %.6g vs 0.11 (%+.2f%%), wrapped %d, "
              "tet remeshing %d (%.2f -> %.2f), %.1f s",
              m->n_tets, q.dihedral_min, v, 100 * (v - 0.11) / 0.11, rep.wrapped, rep.lifted, rep.lift_dihedral_in,
              rep.lift_dihedral, bs_seconds() - t0);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_eq(bs__boundary_manifold(m, path, 0, &err), BS_OK, "%s", err.msg);
  cr_expect_leq(fabs(v - 0.11), 0.04 * 0.11, "volume %g", v);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* The same part as CAD (OpenCASCADE boxes fused in a .geo) through Gmsh at
 * a size larger than the wall's thickness: Gmsh's mesh and optimisers, then
 * the tetrahedral remeshing when still under the gate; the CAD surface
 * groups are kept. */
Test(mesh_lift, thin_wall_cad_through_gmsh) {
  char path[96];
  snprintf(path, sizeof path, "/tmp/bs_test_lift_%d_wall.geo", (int)getpid());
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  fprintf(f, "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 0.1};\nBox(2) = {0.49, 0, 0.1, 0.02, 1, 0.5};\n"
             "BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }\n");
  fclose(f);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  bs_surface_report rep = {0};
  cr_assert_eq(bs_mesh_read(path, &(bs_mesh_read_opts){.size = 0.05, .report = &rep}, &m, &err), BS_OK, "%s",
               err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const double v = bs_mesh_volume(m);
  cr_log_info("CAD slab with wall at h 0.05: %d tets, min dihedral %.2f, volume %.6g vs 0.11, %d groups, tet "
              "remeshing %d (%.2f -> %.2f), %.1f s",
              m->n_tets, q.dihedral_min, v, m->n_groups, rep.lifted, rep.lift_dihedral_in, rep.lift_dihedral,
              bs_seconds() - t0);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_leq(fabs(v - 0.11), 1e-6, "volume %.9g", v);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  int surfaces = 0;
  for (int g = 0; g < m->n_groups; g++) surfaces += m->groups[g].dim == 2;
  cr_expect_geq(surfaces, 10, "%d surface groups", surfaces);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* A washer (a disc with a through hole) whose top outer edge carries a
 * chamfer of 0.008 m, thinner than the size 0.05: Gmsh's mesh misses the
 * gate at the chamfer, and the tetrahedral remeshing cannot take it (a
 * boundary of genus 1 is no triangulation for CGAL's remesher); its
 * boundary is meshed again by the surface path, groups carried over. */
static const char *const washer_geo =
    "SetFactory(\"OpenCASCADE\");\n"
    "Cylinder(1) = {0, 0, 0, 0, 0, 0.192, 0.5};\n"
    "Cone(2) = {0, 0, 0.192, 0, 0, 0.008, 0.5, 0.492};\n"
    "Cylinder(3) = {0, 0, -0.1, 0, 0, 0.4, 0.2};\n"
    "BooleanUnion(4) = { Volume{1}; Delete; }{ Volume{2}; Delete; };\n"
    "BooleanDifference(5) = { Volume{4}; Delete; }{ Volume{3}; Delete; };\n"
    "Physical Volume(\"washer\", 7) = {5};\n"
    "Physical Surface(\"hole\", 8) = {Surface In BoundingBox{-0.21, -0.21, -0.01, 0.21, 0.21, 0.21}};\n";

/* The washer's exact volume: the disc, the chamfer's frustum, minus the hole. */
static double washer_volume(void) {
  const double r1 = 0.5, r2 = 0.492, h = 0.008;
  return M_PI * (r1 * r1 * 0.192 + h / 3 * (r1 * r1 + r1 * r2 + r2 * r2) - 0.2 * 0.2 * 0.2);
}

/* The washer written to path (n bytes) and read with o, asserted. */
static bs_mesh *read_washer(char *path, size_t n, bs_mesh_read_opts o) {
  snprintf(path, n, "/tmp/bs_test_lift_%d_washer.geo", (int)getpid());
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  fputs(washer_geo, f);
  fclose(f);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), BS_OK, "%s", err.msg);
  return m;
}

/* The step itself, on Gmsh's mesh read without a gate. */
Test(mesh_lift, cad_with_a_hole_meshed_again_from_its_boundary) {
  char path[96];
  bs_mesh *m = read_washer(path, sizeof path, (bs_mesh_read_opts){.size = 0.05, .min_dihedral = -1});
  bs_error err;
  bs_error_clear(&err);
  const double v0 = bs_mesh_volume(m);
  int n2 = 0;
  for (int g = 0; g < m->n_groups; g++) n2 += m->groups[g].dim == 2;
  bs_error_set(&err, BS_EINPUT, "the gate's message");
  cr_assert_eq(bs__mesh_cad_by_surface(path, &m, 0.05, NULL, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const double v = bs_mesh_volume(m);
  cr_log_info("washer from its boundary: %d tets, min dihedral %.2f, volume %.6g (Gmsh's %.6g, exact %.6g)", m->n_tets,
              q.dihedral_min, v, v0, washer_volume());
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_leq(fabs(v - v0) / v0, BS_FROM_BOUNDARY_VOLUME_TOL);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  /* the groups: the named volume with every tet; the hole's group holds exactly the boundary triangles on the
     hole's cylinder (vertices at radius 0.2 within the facets' sag h^2 / 8r = 1.6e-3, normal horizontal) */
  const bs_group *w = bs_mesh_group(m, "washer"), *hole = bs_mesh_group(m, "hole");
  cr_assert(w && hole);
  cr_expect_eq(w->n_elems, m->n_tets);
  int n2b = 0;
  for (int g = 0; g < m->n_groups; g++) n2b += m->groups[g].dim == 2;
  cr_expect_eq(n2b, n2);
  int32_t on_hole = 0;
  for (int32_t f = 0; f < m->n_faces; f++) {
    const double *p[3];
    int on = 1;
    for (int k = 0; k < 3; k++) {
      p[k] = m->x + 3 * (size_t)m->faces[3 * (size_t)f + k];
      on &= fabs(hypot(p[k][0], p[k][1]) - 0.2) < 2e-3;
    }
    const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]},
                 v[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const double nz = u[0] * v[1] - u[1] * v[0], nx = u[1] * v[2] - u[2] * v[1], ny = u[2] * v[0] - u[0] * v[2];
    on_hole += on && fabs(nz) < 0.5 * sqrt(nx * nx + ny * ny + nz * nz);
  }
  cr_expect_eq(hole->n_elems, on_hole, "the hole's group has %d triangles, %d lie on the hole", hole->n_elems, on_hole);
  for (int32_t k = 0; k < hole->n_vertices; k++) {
    const double *p = m->x + 3 * (size_t)hole->vertices[k];
    cr_expect_float_eq(hypot(p[0], p[1]), 0.2, 2e-3, "hole vertex %d at radius %g", hole->vertices[k], hypot(p[0], p[1]));
  }
  bs_mesh_destroy(&m);
  unlink(path);
}

/* Through bs_mesh_read at the size: whatever path Gmsh's mesh takes (its
 * optimisers do not give the same mesh twice), the result passes the gate
 * and holds the washer's volume. */
Test(mesh_lift, cad_with_a_hole_and_a_thin_chamfer_passes_the_gate) {
  char path[96];
  bs_surface_report rep = {0};
  bs_mesh *m = read_washer(path, sizeof path, (bs_mesh_read_opts){.size = 0.05, .report = &rep});
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const double v = bs_mesh_volume(m), ve = washer_volume();
  cr_log_info("washer at h 0.05: %d tets, min dihedral %.2f, volume %.6g vs %.6g (%+.3f%%); lifted %d, from its "
              "boundary %d (Gmsh's %.2f degrees)",
              m->n_tets, q.dihedral_min, v, ve, 100 * (v - ve) / ve, rep.lifted, rep.from_boundary,
              rep.from_boundary_dihedral_in);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_leq(fabs(v - ve) / ve, 0.01);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* ---- the time budget ------------------------------------------------------- */

Test(mesh_lift, time_budget_gives_the_named_error) {
  char path[96];
  snprintf(path, sizeof path, "/tmp/bs_test_lift_%d_budget.off", (int)getpid());
  write_slab_wall(path);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  bs_mesh_read_opts o = {.size = 0.02, .time_budget = 1e-6};
  cr_expect_eq(bs_mesh_read(path, &o, &m, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "time budget of 1e-06 s") != NULL, "%s", err.msg);
  cr_log_info("budget 1e-6 s: stopped after %.3f s: %s", bs_seconds() - t0, err.msg);
  cr_expect_null(m);
  unlink(path);
}

/* No budget given is the default one (no read runs unbounded); a negative
 * one is none. */
Test(mesh_lift, time_budget_default_and_none) {
  bs_mesh_read_opts o = {0};
  const double t0 = bs_seconds();
  bs__budget_begin(&o);
  const double d = bs__budget_deadline();
  bs__budget_end();
  cr_expect(d >= t0 + BS_MESH_TIME_BUDGET && d <= bs_seconds() + BS_MESH_TIME_BUDGET, "deadline %.3f, now %.3f", d,
            bs_seconds());
  o.time_budget = -1;
  bs__budget_begin(&o);
  cr_expect_eq(bs__budget_deadline(), 0.0, "a negative budget is none");
  bs__budget_end();
  o.time_budget = 5;
  bs__budget_begin(&o);
  cr_expect_leq(bs__budget_deadline(), bs_seconds() + 5);
  bs__budget_end();
}

/* A budget that runs out while the volume is meshed (Mesh_3's refinement,
 * then its optimisers, which get the time left): the read ends with the
 * budget's error, whichever stage it ran out in. */
Test(mesh_lift, time_budget_during_meshing) {
  char path[96];
  snprintf(path, sizeof path, "/tmp/bs_test_lift_%d_budget2.off", (int)getpid());
  write_slab_wall(path);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  bs_mesh_read_opts o = {.size = 0.03, .time_budget = 0.3};
  const int rc = bs_mesh_read(path, &o, &m, &err);
  cr_log_info("budget 0.3 s at h 0.03: rc %d after %.2f s: %s", rc, bs_seconds() - t0, err.msg);
  cr_expect_eq(rc, BS_EINPUT);
  cr_expect(strstr(err.msg, "time budget") && strstr(err.msg, "0.3 s"), "%s", err.msg);
  cr_expect_null(m);
  unlink(path);
}

/* Mesh_3's refinement itself is stopped at the deadline (its stop flag, set
 * by the shim's watchdog thread): an icosahedron of circumradius 1 at h =
 * 0.02 asks for about 7e5 tets (many seconds of refinement); with 0.3 s
 * left, the error names the refinement and where it stopped. Had the
 * refinement run to its end, the budget would be found spent only after
 * it (in the optimisers, another message). */
Test(mesh_lift, time_budget_stops_mesh3_refinement) {
  const double g = (1 + sqrt(5.0)) / 2, r = 1 / sqrt(1 + g * g);
  const double x[12 * 3] = {-r, g * r, 0, r, g * r, 0, -r, -g * r, 0, r, -g * r, 0, 0, -r, g * r, 0, r, g * r,
                            0, -r, -g * r, 0, r, -g * r, g * r, 0, -r, g * r, 0, r, -g * r, 0, -r, -g * r, 0, r};
  static const int32_t t[20 * 3] = {0, 11, 5, 0, 5, 1,  0, 1, 7,  0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,
                                    11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2,   3, 2, 6,   3, 6, 8, 3, 8, 9,
                                    4, 9, 5,  2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  bs_error err;
  bs_error_clear(&err);
  bs_shim_mesh3_opts o = {.size = 0.02, .deadline = bs_seconds() + 0.3};
  bs_shim_mesh3_out out;
  const int rc = bs_shim_mesh_surface("icosahedron", x, 12, t, 20, &o, &out, &err);
  cr_log_info("icosahedron at h 0.02, 0.3 s left: rc %d: %s", rc, err.msg);
  cr_expect_eq(rc, BS_EINPUT);
  cr_expect(strstr(err.msg, "time budget was exceeded during Mesh_3's refinement (stopped at ") != NULL, "%s",
            err.msg);
  cr_expect_null(out.x);
  cr_expect_null(out.tets);
}

/* mpi.off (CGAL's data/meshes: the letters MPI as non-planar polygons) as the
 * repair leaves it: 27 points, 50 triangles, two sharp edges leaving point 1
 * at 7e-5 degrees apart. Mesh_3's protection of such a corner shrinks its
 * balls without end (528 s, millions of balls, past a 20 s budget: CGAL
 * checks no stop flag there); the surface is meshed as a smooth one
 * instead. */
static const double mpi_x[27 * 3] = {
    -10.0402, -10.0402, -10.0402, -10, 10, 10, 10, 10, 10,
    -9.9999199999999995, 10.040100000000001, -9.9999199999999995,
    -1.9999866667293342, 10.010683303213094, 4.6666799664602578,
    -1.1410339540811094, 3.3261159707677077, 6.8871644837482933,
    -7.337029247025991, 3.7408533525438634, 7.3747364897239311,
    -6.0192422547121467, -6.0048964457634879, 8.0205019087228919,
    -10.007999999999999, 6.0240600000000004, 5.0200500000000003, -6.0240600000000004, -10.012, 4.0160400000000003,
    -10.013999999999999, 0, 3.0120300000000002, 10, 6, 10, 10.02, 0, -1.9999899999999999,
    -10.02, 0, -2.0080200000000001, -6.0116300000000003, -2.0038800000000001, 0.33143699999999998,
    -10.0219, -0.92678099999999997, -0.92678099999999997, -9.9999400000000005, -6.0172100000000004, 10.0321,
    -9.9999800000000008, 5.9965700000000002, 10.007999999999999, -6.0240499999999999, -9.9999400000000005, 10.0321,
    -9.9999199999999995, -9.9999199999999995, 10.040100000000001,
    10.0219, -0.92307300000000003, -0.92307300000000003, 10.019399999999999, -2.00387, 0.33785900000000002,
    -5.9999599999999997, 10.0321, -5.9999599999999997, -5.9999599999999997, 10.0321, -9.9999400000000005,
    -10.007999999999999, 6.0240600000000004, -10.007999999999999, -6.0192600000000001, -6.0192600000000001, 10.0321,
    10, 10, -10
};
static const int32_t mpi_t[50 * 3] = {
    0, 19, 16, 16, 10, 0, 10, 17, 0, 0, 17, 1, 0, 1, 15, 23, 22, 13, 24, 23, 13, 26, 12, 22, 12, 13, 22, 8, 24, 13,
    2, 26, 4, 0, 9, 18, 0, 18, 19, 22, 4, 26, 1, 17, 4, 5, 11, 4, 17, 5, 4, 25, 7, 6, 21, 5, 14, 5, 7, 14, 9, 14, 7,
    5, 6, 7, 17, 10, 6, 4, 22, 1, 2, 4, 11, 16, 25, 6, 15, 13, 12, 15, 12, 20, 15, 20, 21, 15, 21, 14, 11, 5, 21,
    6, 5, 17, 16, 6, 10, 18, 7, 25, 24, 8, 3, 3, 8, 1, 1, 8, 15, 8, 13, 15, 7, 18, 9, 3, 22, 23, 24, 3, 23,
    26, 20, 12, 26, 2, 20, 1, 22, 3, 11, 20, 2, 11, 21, 20, 14, 9, 0, 15, 14, 0, 19, 18, 25, 16, 19, 25
};

Test(mesh_lift, sharp_edges_at_a_hairline_corner_are_not_protected) {
  bs_error err;
  bs_error_clear(&err);
  bs_shim_mesh3_opts o = {.size = 1.39, .feature_angle = BS_MESH_FEATURE_ANGLE, .smoother = BS_SHIM_SMOOTH_ODT,
                          .smooth_iterations = 10, .perturb = 1, .exude = 1, .target_dihedral = 10, .max_rounds = 3};
  bs_shim_mesh3_out out;
  cr_assert_eq(bs_shim_mesh_surface("mpi", mpi_x, 27, mpi_t, 50, &o, &out, &err), BS_OK, "%s", err.msg);
  cr_log_info("mpi at h 1.39: %lld tets, %lld feature chains, %.2f degrees", (long long)out.n_tets,
              (long long)out.n_features, out.dihedral);
  cr_expect_eq(out.n_features, 0);
  cr_expect_gt(out.n_tets, 1000);
  bs_shim_free(out.x), bs_shim_free(out.tets);
  /* a box's corners (90 degrees) keep their sharp edges */
  static const double bx[8 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
  static const int32_t bt[12 * 3] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                     2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  o.size = 0.25;
  cr_assert_eq(bs_shim_mesh_surface("box", bx, 8, bt, 12, &o, &out, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(out.n_features, 12, "%lld chains", (long long)out.n_features);
  bs_shim_free(out.x), bs_shim_free(out.tets);
}

/* Inside the wrap's loop: a deadline already past stops it by name. */
Test(mesh_lift, time_budget_inside_the_alpha_wrap) {
  static const double x[8 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
  static const int32_t t[12 * 3] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                    2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  bs_error err;
  bs_error_clear(&err);
  bs_shim_wrap_opts o = {.size = 0.01, .deadline = bs_seconds() - 1.0};
  bs_shim_wrap_out w;
  cr_expect_eq(bs_shim_alpha_wrap("cube", x, 8, t, 12, &o, &w, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "time budget was exceeded during the alpha wrap") != NULL, "%s", err.msg);
  cr_expect_null(w.points);
}

/* ---- no size given ---------------------------------------------------------- */

Test(mesh_lift, no_size_on_a_scan_passes_the_gate) {
  char path[1024];
  snprintf(path, sizeof path, "%s/data/meshes/armadillo.off", BS_SOURCE_DIR);
  if (access(path, R_OK)) cr_skip_test("%s missing (bash setup.sh build extracts it)", path);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  bs_surface_report rep = {0};
  cr_assert_eq(bs_mesh_read(path, &(bs_mesh_read_opts){.report = &rep}, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_log_info("armadillo without a size: size chosen %g, %d tets, min dihedral %.2f, tet remeshing %d (%.2f -> "
              "%.2f), %.1f s",
              m->auto_size, m->n_tets, q.dihedral_min, rep.lifted, rep.lift_dihedral_in, rep.lift_dihedral,
              bs_seconds() - t0);
  cr_expect_gt(m->auto_size, 0);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}
