/* Reading meshes through Gmsh (bs_mesh_read) and writing .msh
 * (bs_mesh_write_msh): every data/geo input, every file format, the default
 * groups, options, the error paths (each message must name its culprit), the
 * library's silence, concurrent reads, the caller's OpenMP thread count kept,
 * and the write/read round trip. */
#define _POSIX_C_SOURCE 200809L

#include <criterion/criterion.h>
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gmshc.h>
#include <omp.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "mesh_internal.h"

#define PI 3.14159265358979323846

/* ---- helpers ------------------------------------------------------------ */

static char tmpdir[256];

static void make_tmpdir(void) {
  snprintf(tmpdir, sizeof tmpdir, "/tmp/bs_test_mesh_read_XXXXXX");
  cr_assert_not_null(mkdtemp(tmpdir), "mkdtemp failed");
}

static void remove_tmpdir(void) {
  DIR *d = opendir(tmpdir);
  if (!d) return;
  struct dirent *e;
  char p[512];
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
      snprintf(p, sizeof p, "%s/%s", tmpdir, e->d_name);
      remove(p);
    }
  closedir(d);
  rmdir(tmpdir);
}

static const char *tmp_path(const char *name) {
  static char buf[4][512];
  static int k;
  k = (k + 1) % 4;
  snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
  return buf[k];
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f, "cannot write %s", path);
  fputs(text, f);
  fclose(f);
}

static bs_mesh *read_ok(const char *path, const bs_mesh_read_opts *opts) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, opts, &m, &err);
  cr_assert_eq(rc, BS_OK, "reading %s failed: %s", path, err.msg);
  cr_assert_not_null(m);
  return m;
}

/* bs_mesh_read must fail with `code` and a message containing every string
 * of `needles` (NULL-terminated). */
static void read_fails(const char *path, const bs_mesh_read_opts *opts, int code, const char *const *needles) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, opts, &m, &err);
  cr_assert_eq(rc, code, "reading %s: expected status %d, got %d (%s)", path, code, rc, err.msg);
  cr_assert_null(m);
  for (; *needles; needles++)
    cr_assert_not_null(strstr(err.msg, *needles), "message \"%s\" does not name \"%s\"", err.msg, *needles);
}

/* The invariants every read mesh satisfies. */
static void check_mesh(const bs_mesh *m, const char *what) {
  bs_error err = {0};
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s: bs_mesh_check: %s", what, err.msg);
  double v = bs_mesh_volume(m), vb = bs_mesh_boundary_volume(m);
  cr_assert_gt(v, 0.0, "%s: volume %g", what, v);
  cr_assert_lt(fabs(vb - v), 1e-12 * v, "%s: boundary volume %.17g vs volume %.17g", what, vb, v);
  for (int32_t t = 0; t < m->n_tets; t++) cr_assert_gt(bs_mesh_tet_volume(m, m->x, t), 0.0, "%s: tet %d", what, t);
}

static const bs_group *group_ok(const bs_mesh *m, const char *name, int dim) {
  const bs_group *g = bs_mesh_group(m, name);
  cr_assert_not_null(g, "no group \"%s\"", name);
  cr_assert_eq(g->dim, dim, "group \"%s\" has dim %d, expected %d", name, g->dim, dim);
  cr_assert_gt(g->n_elems, 0, "group \"%s\" is empty", name);
  cr_assert_gt(g->n_vertices, 0, "group \"%s\" has no vertices", name);
  return g;
}

/* Every vertex of group g satisfies |coordinate k - value| <= tol. */
static void group_on_plane(const bs_mesh *m, const char *name, int k, double value) {
  const bs_group *g = group_ok(m, name, 2);
  for (int32_t i = 0; i < g->n_vertices; i++) {
    double c = m->x[3 * g->vertices[i] + k];
    cr_assert_lt(fabs(c - value), 1e-9, "group \"%s\": vertex %d has coordinate %d = %g, expected %g", name,
                 g->vertices[i], k, c, value);
  }
}

static void rel_close(double got, double want, double rel, const char *what) {
  cr_assert_lt(fabs(got - want), rel * fabs(want), "%s: %.10g vs %.10g (relative tolerance %g)", what, got, want, rel);
}

static void bbox(const bs_mesh *m, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
  for (int32_t v = 0; v < m->n_vertices; v++)
    for (int k = 0; k < 3; k++) {
      double c = m->x[3 * v + k];
      if (c < lo[k]) lo[k] = c;
      if (c > hi[k]) hi[k] = c;
    }
}

/* Gmsh driven directly by the test (to produce inputs in other formats). */
static void gmsh_test_begin(void) {
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  cr_assert_eq(ierr, 0);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
}

static void gmsh_test_call(int ierr, const char *what) {
  if (!ierr) return;
  char *msg = NULL;
  int e2 = 0;
  gmshLoggerGetLastError(&msg, &e2);
  cr_assert_fail("Gmsh failed to %s: %s", what, msg ? msg : "");
}

/* Closed surfaces as text. */
static const char *octahedron_off = "OFF\n"
                                    "6 8 0\n"
                                    "1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
                                    "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n"
                                    "3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n";

/* Unit cube as six quadrilaterals (the shim splits them into triangles). */
static const char *cube_obj = "# unit cube\n"
                              "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                              "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

/* ---- the data/geo inputs -------------------------------------------------- */

Test(mesh_read, cube_geo) {
  bs_mesh *m = read_ok("data/geo/cube.geo", NULL);
  check_mesh(m, "cube.geo");
  cr_assert_eq(m->n_dropped, 0);
  rel_close(bs_mesh_volume(m), 1.0, 1e-12, "cube volume");
  const bs_group *body = group_ok(m, "body", 3);
  cr_assert_eq(body->n_elems, m->n_tets);
  for (int32_t t = 0; t < m->n_tets; t++) cr_assert_eq(m->material[t], body->tag);
  group_on_plane(m, "left", 0, 0.0);
  group_on_plane(m, "right", 0, 1.0);
  group_on_plane(m, "bottom", 1, 0.0);
  group_on_plane(m, "top", 1, 1.0);
  group_on_plane(m, "front", 2, 1.0);
  group_on_plane(m, "back", 2, 0.0);
  /* Every boundary face lies in one of the six groups. */
  for (int32_t f = 0; f < m->n_faces; f++) cr_assert_gt(m->boundary[f], 0, "boundary face %d has no id", f);
  bs_mesh_destroy(&m);
  cr_assert_null(m);
}

Test(mesh_read, beam_geo) {
  bs_mesh *m = read_ok("data/geo/beam.geo", NULL);
  check_mesh(m, "beam.geo");
  rel_close(bs_mesh_volume(m), 0.01, 1e-12, "beam volume");
  group_ok(m, "body", 3);
  group_on_plane(m, "clamp", 0, 0.0);
  group_on_plane(m, "tip", 0, 1.0);
  double lo[3], hi[3];
  bbox(m, lo, hi);
  rel_close(hi[0] - lo[0], 1.0, 1e-12, "beam length");
  rel_close(hi[1] - lo[1], 0.1, 1e-12, "beam height");
  rel_close(hi[2] - lo[2], 0.1, 1e-12, "beam width");
  bs_mesh_destroy(&m);
}

Test(mesh_read, sphere_geo) {
  bs_mesh *m = read_ok("data/geo/sphere.geo", NULL);
  check_mesh(m, "sphere.geo");
  double exact = 4.0 / 3.0 * PI * 0.125, v = bs_mesh_volume(m);
  rel_close(v, exact, 0.05, "sphere volume");
  cr_assert_lt(v, exact, "the inscribed polyhedron is smaller than the ball");
  group_ok(m, "body", 3);
  const bs_group *s = group_ok(m, "surface", 2);
  for (int32_t i = 0; i < s->n_vertices; i++) {
    const double *p = m->x + 3 * s->vertices[i];
    rel_close(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 0.5, 1e-9, "surface vertex radius");
  }
  cr_assert_eq(s->n_elems, m->n_faces, "the surface group is the whole boundary");
  bs_mesh_destroy(&m);
}

Test(mesh_read, torus_geo) {
  bs_mesh *m = read_ok("data/geo/torus.geo", NULL);
  check_mesh(m, "torus.geo");
  rel_close(bs_mesh_volume(m), 2.0 * PI * PI * 0.5 * 0.2 * 0.2, 0.05, "torus volume");
  group_ok(m, "body", 3);
  const bs_group *s = group_ok(m, "surface", 2);
  cr_assert_eq(s->n_elems, m->n_faces);
  bs_mesh_destroy(&m);
}

/* Gmsh sets the OpenMP thread count from General.NumThreads (1); the caller's
 * must come back, or every parallel region after a mesh read runs on one
 * thread. */
Test(mesh_read, keeps_the_callers_openmp_thread_count) {
  omp_set_num_threads(3);
  bs_mesh *m = read_ok("data/geo/torus.geo", NULL);
  cr_assert_eq(omp_get_max_threads(), 3, "bs_mesh_read left the OpenMP thread count at %d", omp_get_max_threads());
  int team = 0;
#pragma omp parallel
#pragma omp single
  team = omp_get_num_threads();
  cr_assert_eq(team, 3, "a parallel region after bs_mesh_read ran on %d threads", team);
  bs_mesh_destroy(&m);
}

Test(mesh_read, two_spheres_geo) {
  bs_mesh *m = read_ok("data/geo/two_spheres.geo", NULL);
  check_mesh(m, "two_spheres.geo");
  rel_close(bs_mesh_volume(m), 2.0 * 4.0 / 3.0 * PI * 0.125, 0.05, "two spheres volume");
  const bs_group *a = group_ok(m, "sphere_a", 3), *b = group_ok(m, "sphere_b", 3);
  cr_assert_eq(a->n_elems + b->n_elems, m->n_tets);
  cr_assert_neq(a->tag, b->tag);
  for (int32_t e = 0; e < a->n_elems; e++) cr_assert_eq(m->material[a->elems[e]], a->tag);
  for (int32_t e = 0; e < b->n_elems; e++) cr_assert_eq(m->material[b->elems[e]], b->tag);
  group_ok(m, "surface_a", 2);
  group_ok(m, "surface_b", 2);
  bs_mesh_destroy(&m);
}

Test(mesh_read, box_hole_geo) {
  bs_mesh *m = read_ok("data/geo/box_hole.geo", NULL);
  check_mesh(m, "box_hole.geo");
  double plate = 1.6 * 1.6 * 0.1 - PI * 0.3 * 0.3 * 0.1, torus = 2.0 * PI * PI * 0.25 * 0.1 * 0.1;
  const bs_group *p = group_ok(m, "plate", 3), *t = group_ok(m, "torus", 3);
  cr_assert_eq(p->n_elems + t->n_elems, m->n_tets);
  double vp = 0, vt = 0;
  for (int32_t e = 0; e < p->n_elems; e++) vp += bs_mesh_tet_volume(m, m->x, p->elems[e]);
  for (int32_t e = 0; e < t->n_elems; e++) vt += bs_mesh_tet_volume(m, m->x, t->elems[e]);
  rel_close(vp, plate, 0.02, "plate volume");
  rel_close(vt, torus, 0.05, "torus volume");
  const bs_group *h = group_ok(m, "hole_wall", 2);
  for (int32_t i = 0; i < h->n_vertices; i++) {
    const double *q = m->x + 3 * h->vertices[i];
    rel_close(sqrt(q[0] * q[0] + q[2] * q[2]), 0.3, 1e-9, "hole wall radius");
  }
  group_ok(m, "torus_surface", 2);
  bs_mesh_destroy(&m);
}

static const double bracket_volume = 0.10 * 0.01 * 0.06 + 0.01 * 0.08 * 0.06 - 0.01 * 0.01 * 0.06 /* L */
                                     + (1.0 - PI / 4.0) * 0.01 * 0.01 * 0.06                      /* fillet */
                                     - PI * 0.008 * 0.008 * 0.01;                                  /* hole */

Test(mesh_read, bracket_step_default_groups) {
  bs_mesh *m = read_ok("data/geo/bracket.step", NULL);
  check_mesh(m, "bracket.step");
  rel_close(bs_mesh_volume(m), bracket_volume, 0.03, "bracket volume");
  double lo[3], hi[3];
  bbox(m, lo, hi);
  rel_close(hi[0] - lo[0], 0.10, 1e-6, "bracket length in metres (STEP in mm)");
  rel_close(hi[1] - lo[1], 0.08, 1e-6, "bracket height in metres");
  /* No physical groups in a STEP file: "body" (3, 1), one group per face. */
  const bs_group *body = group_ok(m, "body", 3);
  cr_assert_eq(body->tag, 1);
  cr_assert_eq(body->n_elems, m->n_tets);
  int n_surf = 0;
  int32_t n_tri = 0;
  for (int g = 0; g < m->n_groups; g++) {
    const bs_group *gr = &m->groups[g];
    if (gr->dim != 2) continue;
    char want[64];
    snprintf(want, sizeof want, "surface_%d", gr->tag);
    cr_assert_str_eq(gr->name, want);
    n_surf++;
    n_tri += gr->n_elems;
  }
  cr_assert_geq(n_surf, 10, "an L bracket with a fillet and a hole has at least 10 faces, got %d", n_surf);
  cr_assert_eq(n_tri, m->n_faces, "the face groups cover the boundary");
  for (int32_t f = 0; f < m->n_faces; f++) cr_assert_gt(m->boundary[f], 0);
  bs_mesh_destroy(&m);
}

Test(mesh_read, bracket_geo) {
  bs_mesh *m = read_ok("data/geo/bracket.geo", NULL);
  check_mesh(m, "bracket.geo");
  rel_close(bs_mesh_volume(m), bracket_volume, 0.03, "bracket volume");
  group_ok(m, "body", 3); /* no physical groups in bracket.geo either */
  bs_mesh_destroy(&m);
}

/* ---- options ---------------------------------------------------------------- */

Test(mesh_read, refine_gives_eight_times_the_tets) {
  bs_mesh *coarse = read_ok("data/geo/cube.geo", NULL);
  bs_mesh_read_opts opts = {.size = 0, .refine = 1};
  bs_mesh *fine = read_ok("data/geo/cube.geo", &opts);
  check_mesh(fine, "refined cube");
  cr_assert_eq(fine->n_tets, 8 * coarse->n_tets);
  rel_close(bs_mesh_volume(fine), 1.0, 1e-12, "refined cube volume");
  const bs_group *l = group_ok(fine, "left", 2), *lc = group_ok(coarse, "left", 2);
  cr_assert_eq(l->n_elems, 4 * lc->n_elems);
  bs_mesh_destroy(&coarse);
  bs_mesh_destroy(&fine);
}

Test(mesh_read, size_overrides_the_file) {
  bs_mesh_read_opts big = {.size = 0.5}, small = {.size = 0.125};
  bs_mesh *a = read_ok("data/geo/cube.geo", &big), *b = read_ok("data/geo/cube.geo", &small);
  check_mesh(a, "cube size 0.5");
  check_mesh(b, "cube size 0.125");
  cr_assert_gt(b->n_tets, 4 * a->n_tets, "size 0.125: %d tets, size 0.5: %d tets", b->n_tets, a->n_tets);
  group_on_plane(b, "left", 0, 0.0);
  bs_mesh_destroy(&a);
  bs_mesh_destroy(&b);
}

/* ---- formats ---------------------------------------------------------------- */

Test(mesh_read, msh_versions_and_encodings) {
  make_tmpdir();
  static const struct {
    const char *name;
    double version;
    int binary;
  } fmt[4] = {{"v2_ascii.msh", 2.2, 0}, {"v2_binary.msh", 2.2, 1}, {"v4_ascii.msh", 4.1, 0}, {"v4_binary.msh", 4.1, 1}};
  int ierr = 0;
  gmsh_test_begin();
  gmshOpen("data/geo/cube.geo", &ierr);
  gmsh_test_call(ierr, "open cube.geo");
  gmshModelMeshGenerate(3, &ierr);
  gmsh_test_call(ierr, "mesh cube.geo");
  for (int i = 0; i < 4; i++) {
    gmshOptionSetNumber("Mesh.MshFileVersion", fmt[i].version, &ierr);
    gmshOptionSetNumber("Mesh.Binary", fmt[i].binary, &ierr);
    gmshWrite(tmp_path(fmt[i].name), &ierr);
    gmsh_test_call(ierr, "write a .msh");
  }
  gmshFinalize(&ierr);

  bs_mesh *ref = read_ok("data/geo/cube.geo", NULL);
  for (int i = 0; i < 4; i++) {
    bs_mesh *m = read_ok(tmp_path(fmt[i].name), NULL);
    check_mesh(m, fmt[i].name);
    cr_assert_eq(m->n_vertices, ref->n_vertices, "%s", fmt[i].name);
    cr_assert_eq(m->n_tets, ref->n_tets, "%s", fmt[i].name);
    cr_assert_eq(m->n_faces, ref->n_faces, "%s", fmt[i].name);
    cr_assert_eq(m->n_groups, ref->n_groups, "%s", fmt[i].name);
    for (int g = 0; g < ref->n_groups; g++) {
      const bs_group *a = &ref->groups[g], *b = bs_mesh_group(m, a->name);
      cr_assert_not_null(b, "%s: group %s", fmt[i].name, a->name);
      cr_assert_eq(b->dim, a->dim);
      cr_assert_eq(b->tag, a->tag);
      cr_assert_eq(b->n_elems, a->n_elems, "%s: group %s", fmt[i].name, a->name);
    }
    rel_close(bs_mesh_volume(m), 1.0, 1e-12, fmt[i].name);
    bs_mesh_destroy(&m);
  }
  bs_mesh_destroy(&ref);
  remove_tmpdir();
}

Test(mesh_read, brep_and_stl) {
  make_tmpdir();
  int ierr = 0;
  gmsh_test_begin();
  gmshOpen("data/geo/sphere.geo", &ierr);
  gmsh_test_call(ierr, "open sphere.geo");
  gmshWrite(tmp_path("sphere.brep"), &ierr); /* the OpenCASCADE shape */
  gmsh_test_call(ierr, "write sphere.brep");
  gmshModelMeshGenerate(2, &ierr);
  gmsh_test_call(ierr, "mesh the sphere's surface");
  gmshWrite(tmp_path("sphere.stl"), &ierr);
  gmsh_test_call(ierr, "write sphere.stl");
  gmshFinalize(&ierr);

  double exact = 4.0 / 3.0 * PI * 0.125;
  bs_mesh_read_opts opts = {.size = 0.15};
  bs_mesh *b = read_ok(tmp_path("sphere.brep"), &opts);
  check_mesh(b, "sphere.brep");
  rel_close(bs_mesh_volume(b), exact, 0.05, "brep sphere volume");
  group_ok(b, "body", 3);
  bs_mesh_destroy(&b);

  /* The STL surface kept as is: the volume mesh's boundary is its triangles. */
  bs_mesh *s = read_ok(tmp_path("sphere.stl"), NULL);
  check_mesh(s, "sphere.stl");
  rel_close(bs_mesh_volume(s), exact, 0.05, "stl sphere volume");
  group_ok(s, "body", 3);
  const bs_group *surf = group_ok(s, "surface_1", 2);
  cr_assert_eq(surf->n_elems, s->n_faces);
  for (int32_t i = 0; i < s->n_vertices; i++) {
    const double *p = s->x + 3 * i;
    cr_assert_leq(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 0.5 + 1e-6);
  }
  /* Remeshed at a given size: more tets, same shape. */
  bs_mesh_read_opts fine = {.size = 0.06};
  bs_mesh *r = read_ok(tmp_path("sphere.stl"), &fine);
  check_mesh(r, "sphere.stl remeshed");
  rel_close(bs_mesh_volume(r), exact, 0.05, "remeshed stl sphere volume");
  cr_assert_gt(r->n_tets, 2 * s->n_tets, "remeshed: %d tets, as is: %d", r->n_tets, s->n_tets);
  bs_mesh_destroy(&s);
  bs_mesh_destroy(&r);
  remove_tmpdir();
}

Test(mesh_read, off_and_obj_through_cgal) {
  make_tmpdir();
  write_text(tmp_path("octahedron.off"), octahedron_off);
  bs_mesh *m = read_ok(tmp_path("octahedron.off"), NULL);
  check_mesh(m, "octahedron.off");
  rel_close(bs_mesh_volume(m), 4.0 / 3.0, 1e-12, "octahedron volume");
  cr_assert_eq(m->n_faces, 8, "the surface is kept: %d boundary faces", m->n_faces);
  group_ok(m, "body", 3);
  bs_mesh_destroy(&m);

  bs_mesh_read_opts opts = {.size = 0.25};
  m = read_ok(tmp_path("octahedron.off"), &opts);
  check_mesh(m, "octahedron.off remeshed");
  rel_close(bs_mesh_volume(m), 4.0 / 3.0, 1e-10, "remeshed octahedron volume");
  cr_assert_gt(m->n_faces, 8 * 8, "the surface is remeshed: %d boundary faces", m->n_faces);
  bs_mesh_destroy(&m);

  /* Quadrilateral faces are split by the shim. */
  write_text(tmp_path("CUBE.OBJ"), cube_obj);
  m = read_ok(tmp_path("CUBE.OBJ"), NULL);
  check_mesh(m, "cube.obj");
  rel_close(bs_mesh_volume(m), 1.0, 1e-12, "obj cube volume");
  cr_assert_eq(m->n_faces, 12);
  bs_mesh_destroy(&m);
  remove_tmpdir();
}

/* Sparse node tags (one beyond any dense table) map to vertices in tag order;
 * groups follow. */
Test(mesh_read, sparse_node_tags) {
  make_tmpdir();
  const char *path = tmp_path("sparse.msh");
  write_text(path, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                   "$PhysicalNames\n2\n2 5 \"side\"\n3 8 \"solid\"\n$EndPhysicalNames\n"
                   "$Nodes\n5\n2000000000 0 0 0\n20 1 0 0\n30 0 1 0\n40 0 0 1\n7 0 0 -1\n$EndNodes\n"
                   "$Elements\n3\n"
                   "11 4 2 8 1 2000000000 20 30 40\n"
                   "12 4 2 8 1 2000000000 30 20 7\n"
                   "13 2 2 5 2 2000000000 20 40\n$EndElements\n");
  bs_mesh *m = read_ok(path, NULL);
  check_mesh(m, "sparse.msh");
  cr_assert_eq(m->n_vertices, 5);
  cr_assert_eq(m->n_tets, 2);
  /* Tag order 7, 20, 30, 40, 2000000000. */
  static const double want[15] = {0, 0, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
  for (int i = 0; i < 15; i++) cr_assert_eq(m->x[i], want[i], "coordinate %d", i);
  rel_close(bs_mesh_volume(m), 2.0 / 6.0, 1e-14, "two unit tets");
  const bs_group *solid = group_ok(m, "solid", 3), *side = group_ok(m, "side", 2);
  cr_assert_eq(solid->tag, 8);
  cr_assert_eq(solid->n_elems, 2);
  cr_assert_eq(m->material[0], 8);
  cr_assert_eq(side->tag, 5);
  cr_assert_eq(side->n_elems, 1);
  cr_assert_eq(side->n_vertices, 3);
  cr_assert_eq(side->vertices[0], 1);
  cr_assert_eq(side->vertices[1], 3);
  cr_assert_eq(side->vertices[2], 4);
  int32_t labelled = 0;
  for (int32_t f = 0; f < m->n_faces; f++) labelled += m->boundary[f] == 5;
  cr_assert_eq(labelled, 1, "the side triangle is one boundary face");
  bs_mesh_destroy(&m);
  remove_tmpdir();
}

/* The CGAL shim on its own: fan triangulation and its errors. */
Test(shim, read_surface) {
  make_tmpdir();
  const char *obj = tmp_path("cube.obj");
  write_text(obj, cube_obj);
  double *x = NULL;
  int32_t *tri = NULL;
  int64_t np = 0, nt = 0;
  bs_error err = {0};
  cr_assert_eq(bs_shim_read_surface(obj, &x, &np, &tri, &nt, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(np, 8);
  cr_assert_eq(nt, 12, "six quads give twelve triangles, got %lld", (long long)nt);
  /* The first quad (1 4 3 2 in OBJ, 0-based 0 3 2 1) fans from vertex 0. */
  cr_assert(tri[0] == 0 && tri[1] == 3 && tri[2] == 2);
  cr_assert(tri[3] == 0 && tri[4] == 2 && tri[5] == 1);
  cr_assert_eq(x[3 * 6 + 0], 1.0);
  cr_assert_eq(x[3 * 6 + 1], 1.0);
  cr_assert_eq(x[3 * 6 + 2], 1.0);
  bs_shim_free(x);
  bs_shim_free(tri);
  bs_shim_free(NULL);

  const char *two = tmp_path("two.off");
  write_text(two, "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1\n");
  cr_assert_eq(bs_shim_read_surface(two, &x, &np, &tri, &nt, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, two), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "polygon 1"), "%s", err.msg);
  cr_assert_null(x);
  cr_assert_null(tri);

  const char *missing = tmp_path("missing.off");
  cr_assert_eq(bs_shim_read_surface(missing, &x, &np, &tri, &nt, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, missing), "%s", err.msg);
  const char *txt = tmp_path("surface.txt");
  write_text(txt, "1 2 3\n");
  cr_assert_eq(bs_shim_read_surface(txt, &x, &np, &tri, &nt, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "'.txt'"), "%s", err.msg);
  const char *junk = tmp_path("junk.off");
  write_text(junk, "not an off file\n");
  cr_assert_eq(bs_shim_read_surface(junk, &x, &np, &tri, &nt, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, junk), "%s", err.msg);
  remove_tmpdir();
}

/* ---- error paths ------------------------------------------------------------ */

Test(mesh_read, missing_file_names_the_path) {
  const char *path = "/tmp/bigstep_no_such_dir/missing_mesh.msh";
  read_fails(path, NULL, BS_EIO, (const char *[]){path, NULL});
}

Test(mesh_read, bad_arguments) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  bs_mesh_read_opts opts = {.refine = -1};
  cr_assert_eq(bs_mesh_read("data/geo/cube.geo", &opts, &m, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "refine = -1"), "%s", err.msg);
  cr_assert_eq(bs_mesh_read(NULL, NULL, &m, &err), BS_EINPUT);
  cr_assert_eq(bs_mesh_read("data/geo/cube.geo", NULL, NULL, &err), BS_EINPUT);
  read_fails("data/geo", NULL, BS_EIO, (const char *[]){"data/geo", "not a regular file", NULL});
}

Test(mesh_read, garbage_names_the_file) {
  make_tmpdir();
  const char *msh = tmp_path("garbage.msh"), *geo = tmp_path("garbage.geo"), *dat = tmp_path("garbage.dat");
  write_text(msh, "this is not a mesh\n\x01\x02\x03 at all\n");
  write_text(geo, "Point(1) = {0, 0, 0;\nthis is not geometry {{{\n");
  write_text(dat, "1 2 3\n");
  read_fails(msh, NULL, BS_EINPUT, (const char *[]){msh, "line 1", "$MeshFormat", NULL}); /* msh_check.c */
  read_fails(geo, NULL, BS_EGMSH, (const char *[]){geo, "line", NULL});
  read_fails(dat, NULL, BS_EINPUT, (const char *[]){dat, "'.dat'", NULL});
  remove_tmpdir();
}

Test(mesh_read, surface_only_msh_has_no_volume_elements) {
  make_tmpdir();
  const char *path = tmp_path("triangle.msh");
  write_text(path, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                   "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
                   "$Elements\n1\n1 2 2 1 1 1 2 3\n$EndElements\n");
  read_fails(path, NULL, BS_EINPUT, (const char *[]){path, "no volume elements", NULL});
  remove_tmpdir();
}

Test(mesh_read, second_order_tets_read_as_corners_and_midside_nodes) {
  make_tmpdir();
  /* One 10-node tet (Gmsh type 11) written by hand: its corners' linear mesh and its 6 midside nodes
     (node 10 is off its edge (1, 3), Gmsh's 9th node); a 4-node and a 10-node tet together are refused. */
  const char *msh = tmp_path("tet10.msh");
  write_text(msh, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                  "$Nodes\n10\n"
                  "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.5 0 0\n6 0.5 0.5 0\n7 0 0.5 0\n"
                  "8 0 0 0.5\n9 0 0.5 0.5\n10 0.55 0 0.5\n$EndNodes\n"
                  "$Elements\n1\n"
                  "1 11 2 1 1 1 2 3 4 5 6 7 8 9 10\n$EndElements\n");
  bs_mesh *m = read_ok(msh, NULL);
  cr_expect_eq(m->n_vertices, 4);
  cr_expect_eq(m->n_dropped, 0);
  cr_expect_eq(m->n_midside, 6);
  int found = 0;
  for (int i = 0; i < 6; i++) {
    const int32_t a = m->midside_edge[2 * i], b = m->midside_edge[2 * i + 1];
    const double *p = m->midside_x + 3 * i;
    if (p[0] == 0.55) { /* Gmsh's node 10 is the edge (1, 3), VTK's node 8: the corners at x = 1 and z = 1 */
      found = 1;
      cr_expect_eq(m->x[3 * a] + m->x[3 * b], 1.0);
      cr_expect_eq(m->x[3 * a + 2] + m->x[3 * b + 2], 1.0);
    } else {
      for (int k = 0; k < 3; k++) cr_expect_eq(p[k], 0.5 * (m->x[3 * a + k] + m->x[3 * b + k]));
    }
  }
  cr_expect(found);
  bs_mesh_destroy(&m);
  const char *mixed = tmp_path("mixed.msh");
  write_text(mixed, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                    "$Nodes\n11\n"
                    "1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 0.5 0 0\n6 0.5 0.5 0\n7 0 0.5 0\n"
                    "8 0 0 0.5\n9 0 0.5 0.5\n10 0.5 0 0.5\n11 1 1 1\n$EndNodes\n"
                    "$Elements\n2\n"
                    "1 11 2 1 1 1 2 3 4 5 6 7 8 9 10\n"
                    "2 4 2 1 2 2 3 4 11\n$EndElements\n"); /* on another entity */
  read_fails(mixed, NULL, BS_EINPUT, (const char *[]){mixed, "1 \"Tetrahedron 10\"", NULL});
  /* And from a geometry meshed at order 2: read. */
  const char *geo = tmp_path("order2.geo");
  write_text(geo, "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 1};\n"
                  "Mesh.MeshSizeMax = 0.5;\nMesh.ElementOrder = 2;\n");
  m = read_ok(geo, NULL);
  cr_expect_eq(m->n_midside, 6 * m->n_tets);
  bs_mesh_destroy(&m);
  remove_tmpdir();
}

Test(mesh_read, hexahedra_are_named_and_counted) {
  make_tmpdir();
  const char *geo = tmp_path("hex.geo");
  write_text(geo, "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 1};\n"
                  "Transfinite Curve{:} = 3;\nTransfinite Surface{:};\nRecombine Surface{:};\n"
                  "Transfinite Volume{1};\n");
  read_fails(geo, NULL, BS_EINPUT, (const char *[]){geo, "8 \"Hexahedron 8\"", NULL});
  remove_tmpdir();
}

Test(mesh_read, zero_volume_tet_is_named) {
  make_tmpdir();
  const char *path = tmp_path("flat.msh");
  /* Element 7 has its four nodes in the plane z = 0. */
  write_text(path, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
                   "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 0\n$EndNodes\n"
                   "$Elements\n2\n"
                   "3 4 2 1 1 1 2 3 4\n"
                   "7 4 2 1 1 1 2 5 3\n$EndElements\n");
  read_fails(path, NULL, BS_EINPUT, (const char *[]){path, "element 7", "nodes 1 2 5 3", "zero volume", NULL});
  remove_tmpdir();
}

Test(mesh_read, bad_surfaces_name_the_file) {
  make_tmpdir();
  /* The octahedron without its last face: not closed. */
  const char *open = tmp_path("open.off");
  write_text(open, "OFF\n6 7 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
                   "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n");
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(open, NULL, &m, &err);
  cr_assert_lt(rc, 0, "an open surface must not give a mesh");
  cr_assert_null(m);
  cr_assert_not_null(strstr(err.msg, open), "%s", err.msg);
  /* A face that refers to a point that does not exist. */
  const char *bad = tmp_path("bad_index.off");
  write_text(bad, "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 9\n");
  read_fails(bad, NULL, BS_EINPUT, (const char *[]){bad, NULL});
  remove_tmpdir();
}

/* The library prints nothing, even when Gmsh fails. */
Test(mesh_read, silent) {
  make_tmpdir();
  const char *garbage = tmp_path("garbage.geo"), *log = tmp_path("output.txt");
  write_text(garbage, "Box(1) = {0, 0;\n");
  fflush(stdout);
  fflush(stderr);
  int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  cr_assert_geq(fd, 0);
  int saved_out = dup(1), saved_err = dup(2);
  dup2(fd, 1);
  dup2(fd, 2);
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc_bad = bs_mesh_read(garbage, NULL, &m, &err);
  int rc_good = bs_mesh_read("data/geo/sphere.geo", NULL, &m, &err);
  bs_mesh_destroy(&m);
  bs_mesh *c = NULL;
  cr_assert_eq(bs_mesh_create_box((double[]){0, 0, 0}, (double[]){1, 1, 1}, 2, 2, 2, &c, &err), BS_OK);
  int rc_write = bs_mesh_write_msh(c, NULL, tmp_path("box.msh"), &err);
  bs_mesh_destroy(&c);
  fflush(stdout);
  fflush(stderr);
  dup2(saved_out, 1);
  dup2(saved_err, 2);
  close(saved_out);
  close(saved_err);
  close(fd);
  cr_assert_eq(rc_bad, BS_EGMSH);
  cr_assert_eq(rc_good, BS_OK);
  cr_assert_eq(rc_write, BS_OK);
  struct stat st;
  cr_assert_eq(stat(log, &st), 0);
  cr_assert_eq(st.st_size, 0, "the library wrote %lld bytes to stdout/stderr", (long long)st.st_size);
  remove_tmpdir();
}

/* Gmsh's TetGen boundary recovery (inside HXT) reports nearly overlapping
 * facets with printf, whatever General.Terminal says; the session keeps
 * stdout on /dev/null. The surface: a unit prism (extruded along y) with a
 * V notch 2e-5 wide cut from its top face down to z = 0.3, whose two walls
 * meet at 0.0016 degrees (on stdout before: "Found two nearly
 * self-intersecting facets ..."; bigstep mesh info --json on
 * double-torus-example.off printed that before its JSON). */
Test(mesh_read, silent_on_nearly_overlapping_facets) {
  const double w = 1e-5, p[7][2] = {{0, 0}, {1, 0}, {1, 1}, {0.5 + w, 1}, {0.5, 0.3}, {0.5 - w, 1}, {0, 1}};
  static const int cap[5][3] = {{0, 1, 4}, {1, 2, 3}, {1, 3, 4}, {0, 4, 5}, {0, 5, 6}};
  double x[14 * 3];
  int32_t t[24 * 3], n = 0;
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < 7; i++) {
      double *q = x + 3 * (7 * k + i);
      q[0] = p[i][0], q[1] = k, q[2] = p[i][1];
    }
  for (int c = 0; c < 5; c++) { /* the end caps */
    int32_t *a = t + 3 * n++, *b = t + 3 * n++;
    a[0] = cap[c][0], a[1] = cap[c][1], a[2] = cap[c][2];
    b[0] = 7 + cap[c][0], b[1] = 7 + cap[c][2], b[2] = 7 + cap[c][1];
  }
  for (int i = 0; i < 7; i++) { /* the sides */
    const int j = (i + 1) % 7;
    int32_t *a = t + 3 * n++, *b = t + 3 * n++;
    a[0] = i, a[1] = 7 + i, a[2] = 7 + j;
    b[0] = i, b[1] = 7 + j, b[2] = j;
  }
  if (bs__soup_volume(x, t, n) < 0) /* outward */
    for (int f = 0; f < n; f++) {
      const int32_t s = t[3 * f + 1];
      t[3 * f + 1] = t[3 * f + 2], t[3 * f + 2] = s;
    }
  cr_assert_float_eq(bs__soup_volume(x, t, n), 1 - 0.7 * w, 1e-12);
  make_tmpdir();
  const char *log = tmp_path("output.txt");
  fflush(stdout);
  fflush(stderr);
  int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  cr_assert_geq(fd, 0);
  int saved_out = dup(1), saved_err = dup(2);
  dup2(fd, 1);
  dup2(fd, 2);
  bs_mesh *m = NULL;
  bs_error err = {0};
  const int rc = bs__gmsh_surface_volume("notch", x, 14, t, n, &(bs_mesh_read_opts){.min_dihedral = -1}, 10, 1, &m,
                                         &err);
  printf("after");
  fflush(stdout);
  fflush(stderr);
  dup2(saved_out, 1);
  dup2(saved_err, 2);
  close(saved_out);
  close(saved_err);
  close(fd);
  bs_mesh_destroy(&m);
  cr_log_info("notch through HXT: rc %d %s", rc, err.msg);
  cr_expect(rc == BS_OK || rc == BS_EGMSH, "rc %d: %s", rc, err.msg);
  char buf[512] = "";
  FILE *f = fopen(log, "r");
  cr_assert_not_null(f);
  const size_t got = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  cr_expect_str_eq(buf, "after", "the library wrote %zu bytes: %s", got, buf);
  remove_tmpdir();
}

/* ---- threads ---------------------------------------------------------------- */

typedef struct reader {
  const char *path;
  int reps;
  int rc;
  int32_t n_tets[4];
} reader;

static void *read_repeatedly(void *arg) {
  reader *r = arg;
  for (int i = 0; i < r->reps; i++) {
    bs_mesh *m = NULL;
    bs_error err = {0};
    r->rc = bs_mesh_read(r->path, NULL, &m, &err);
    if (r->rc) return NULL;
    r->n_tets[i] = m->n_tets;
    bs_mesh_destroy(&m);
  }
  return NULL;
}

Test(mesh_read, concurrent_reads) {
  reader r[2] = {{.path = "data/geo/cube.geo", .reps = 3}, {.path = "data/geo/torus.geo", .reps = 3}};
  pthread_t th[2];
  for (int i = 0; i < 2; i++) cr_assert_eq(pthread_create(&th[i], NULL, read_repeatedly, &r[i]), 0);
  for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
  for (int i = 0; i < 2; i++) {
    cr_assert_eq(r[i].rc, BS_OK, "%s", r[i].path);
    bs_mesh *m = read_ok(r[i].path, NULL);
    for (int k = 0; k < r[i].reps; k++)
      cr_assert_eq(r[i].n_tets[k], m->n_tets, "%s: read %d in a thread gave %d tets, alone %d", r[i].path, k,
                   r[i].n_tets[k], m->n_tets);
    bs_mesh_destroy(&m);
  }
}

/* ---- writing ---------------------------------------------------------------- */

static void same_mesh(const bs_mesh *a, const bs_mesh *b) {
  cr_assert_eq(b->n_vertices, a->n_vertices);
  cr_assert_eq(b->n_tets, a->n_tets);
  cr_assert_eq(b->n_faces, a->n_faces);
  cr_assert_eq(b->n_edges, a->n_edges);
  cr_assert_eq(b->n_groups, a->n_groups);
  for (int g = 0; g < a->n_groups; g++) {
    const bs_group *ga = &a->groups[g], *gb = bs_mesh_group_by_tag(b, ga->dim, ga->tag);
    cr_assert_not_null(gb, "group (%d, %d) \"%s\" lost", ga->dim, ga->tag, ga->name);
    cr_assert_str_eq(gb->name, ga->name);
    cr_assert_eq(gb->n_elems, ga->n_elems, "group \"%s\"", ga->name);
    cr_assert_eq(gb->n_vertices, ga->n_vertices, "group \"%s\"", ga->name);
  }
  rel_close(bs_mesh_volume(b), bs_mesh_volume(a), 1e-12, "round-trip volume");
  int32_t la = 0, lb = 0;
  for (int32_t f = 0; f < a->n_faces; f++) la += a->boundary[f] > 0;
  for (int32_t f = 0; f < b->n_faces; f++) lb += b->boundary[f] > 0;
  cr_assert_eq(lb, la, "labelled boundary faces");
}

Test(mesh_write, round_trip_of_a_read_mesh) {
  make_tmpdir();
  bs_mesh *a = read_ok("data/geo/box_hole.geo", NULL);
  bs_error err = {0};
  const char *path = tmp_path("box_hole.msh");
  cr_assert_eq(bs_mesh_write_msh(a, NULL, path, &err), BS_OK, "%s", err.msg);
  bs_mesh *b = read_ok(path, NULL);
  check_mesh(b, "written box_hole");
  same_mesh(a, b);
  bs_mesh_destroy(&a);
  bs_mesh_destroy(&b);
  remove_tmpdir();
}

/* Groups of every dimension, overlapping 3-D groups, tets in no 3-D group. */
Test(mesh_write, round_trip_of_every_kind_of_group) {
  make_tmpdir();
  bs_error err = {0};
  bs_mesh *box = NULL;
  cr_assert_eq(bs_mesh_create_box((double[]){0, 0, 0}, (double[]){2, 1, 1}, 4, 2, 2, &box, &err), BS_OK, "%s",
               err.msg);
  /* 3-D: "left_half" (centroid x < 1) and "core" (x in [0.5, 1.5]) overlap;
   * tets with x > 1.5 are in no 3-D group (material 0). */
  int32_t *half = malloc(box->n_tets * sizeof *half), *core = malloc(box->n_tets * sizeof *core);
  int32_t nh = 0, nc = 0, n_free = 0;
  for (int32_t t = 0; t < box->n_tets; t++) {
    double cx = 0;
    for (int k = 0; k < 4; k++) cx += 0.25 * box->x[3 * box->tets[4 * t + k]];
    if (cx < 1) half[nh++] = t;
    if (cx > 0.5 && cx < 1.5) core[nc++] = t;
    if (cx >= 1.5) n_free++;
  }
  cr_assert_gt(n_free, 0);
  int32_t seg[4] = {box->edges[0], box->edges[1], box->edges[2], box->edges[3]};
  int32_t pts[2] = {0, box->n_vertices - 1};
  const bs_group *xmin = bs_mesh_group(box, "xmin");
  cr_assert_not_null(xmin);
  bs_group g[5] = {
      {.dim = 3, .tag = 4, .name = "left_half", .n_elems = nh, .elems = half},
      {.dim = 3, .tag = 9, .name = "core", .n_elems = nc, .elems = core},
      {.dim = 2, .tag = 2, .name = "xmin", .n_elems = xmin->n_elems, .elems = xmin->elems},
      {.dim = 1, .tag = 3, .name = "two_edges", .n_elems = 2, .elems = seg},
      {.dim = 0, .tag = 6, .name = "corners", .n_elems = 2, .elems = pts},
  };
  bs_mesh *a = NULL;
  cr_assert_eq(bs_mesh_create(box->n_vertices, box->x, box->n_tets, box->tets, 5, g, &a, &err), BS_OK, "%s",
               err.msg);
  const char *path = tmp_path("groups.msh");
  cr_assert_eq(bs_mesh_write_msh(a, NULL, path, &err), BS_OK, "%s", err.msg);
  bs_mesh *b = read_ok(path, NULL);
  check_mesh(b, "written groups");
  same_mesh(a, b);
  int32_t free_b = 0;
  for (int32_t t = 0; t < b->n_tets; t++) free_b += b->material[t] == 0;
  cr_assert_eq(free_b, n_free, "tets in no 3-D group: %d written, %d read", n_free, free_b);
  /* The overlap is kept: tets in both 3-D groups. */
  const bs_group *bh = bs_mesh_group(b, "left_half"), *bc = bs_mesh_group(b, "core");
  char *in_h = calloc(b->n_tets, 1);
  int32_t both_b = 0, both_a = 0;
  for (int32_t e = 0; e < bh->n_elems; e++) in_h[bh->elems[e]] = 1;
  for (int32_t e = 0; e < bc->n_elems; e++) both_b += in_h[bc->elems[e]];
  for (int32_t t = 0; t < box->n_tets; t++) {
    double cx = 0;
    for (int k = 0; k < 4; k++) cx += 0.25 * box->x[3 * box->tets[4 * t + k]];
    both_a += cx > 0.5 && cx < 1;
  }
  cr_assert_eq(both_b, both_a);
  free(in_h);
  free(half);
  free(core);
  bs_mesh_destroy(&box);
  bs_mesh_destroy(&a);
  bs_mesh_destroy(&b);
  remove_tmpdir();
}

Test(mesh_write, writes_given_positions) {
  make_tmpdir();
  bs_mesh *a = read_ok("data/geo/cube.geo", NULL);
  double *x = malloc(3 * a->n_vertices * sizeof *x);
  for (int32_t i = 0; i < 3 * a->n_vertices; i++) x[i] = 2.0 * a->x[i];
  bs_error err = {0};
  const char *path = tmp_path("scaled.msh");
  cr_assert_eq(bs_mesh_write_msh(a, x, path, &err), BS_OK, "%s", err.msg);
  bs_mesh *b = read_ok(path, NULL);
  rel_close(bs_mesh_volume(b), 8.0, 1e-12, "scaled cube volume");
  group_on_plane(b, "right", 0, 2.0);
  free(x);
  bs_mesh_destroy(&a);
  bs_mesh_destroy(&b);
  remove_tmpdir();
}

Test(mesh_write, errors_name_the_path) {
  bs_mesh *a = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create_box((double[]){0, 0, 0}, (double[]){1, 1, 1}, 1, 1, 1, &a, &err), BS_OK);
  const char *nodir = "/tmp/bigstep_no_such_dir/out.msh";
  cr_assert_eq(bs_mesh_write_msh(a, NULL, nodir, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, nodir), "%s", err.msg);
  cr_assert_eq(bs_mesh_write_msh(a, NULL, "/tmp/out.vtk", &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "/tmp/out.vtk"), "%s", err.msg);
  cr_assert_eq(bs_mesh_write_msh(NULL, NULL, "/tmp/x.msh", &err), BS_EINPUT);
  bs_mesh_destroy(&a);
}
