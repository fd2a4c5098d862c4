/* Surfaces that are not clean (bs_shim_repair_surface, bs_surface_prepare and
 * bs_mesh_read on .off files): a synthetic cube soup with duplicated and
 * zero-area triangles, and the corpus of data/corpus/cgal (setup.sh extracts
 * it from Debian's libcgal-demo): closed scans with self-intersections
 * (camel: removed by autorefinement; elk, cow: removed locally, cow's folds
 * re-filled), a scan with small
 * holes (pig) and one with large holes (mech-holes-shark). Every refusal names
 * the file and the reason. */
#define _GNU_SOURCE

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "cli_util.h"
#include "mesh_internal.h"
#include "scene_fixture.h"
#include "sim_util.h"

#define CORPUS BS_SOURCE_DIR "/data/corpus/cgal/"

static const char *corpus(const char *name) {
  static char path[512];
  snprintf(path, sizeof path, CORPUS "%s", name);
  cr_assert_eq(access(path, R_OK), 0, "%s is missing: run `bash setup.sh build` (it extracts the corpus)", path);
  return path;
}

/* Every edge of the soup in exactly two triangles, once in each direction. */
static void assert_closed_oriented(const int32_t *t, int64_t nt) {
  for (int64_t e = 0; e < nt; e++)
    for (int k = 0; k < 3; k++) {
      int32_t a = t[3 * e + k], b = t[3 * e + (k + 1) % 3];
      int same = 0, opposite = 0;
      for (int64_t f = 0; f < nt; f++)
        for (int j = 0; j < 3; j++) {
          int32_t c = t[3 * f + j], d = t[3 * f + (j + 1) % 3];
          same += c == a && d == b;
          opposite += c == b && d == a;
        }
      cr_assert(same == 1 && opposite == 1, "edge %d-%d of triangle %lld: %d same, %d opposite", a, b, (long long)e,
                same, opposite);
    }
}

static double soup_volume(const double *x, const int32_t *t, int64_t nt) {
  double v = 0;
  for (int64_t e = 0; e < nt; e++) {
    const double *a = x + 3 * t[3 * e], *b = x + 3 * t[3 * e + 1], *c = x + 3 * t[3 * e + 2];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
  }
  return v;
}

/* ---- a synthetic soup ---------------------------------------------------- */

/* The unit cube as 12 outward triangles, with triangle (0 5 4) of the face
 * y = 0 split at the midpoint m = 8 of its edge 4-0 into (0 5 m), (m 5 4) and
 * the zero-area (0 m 4); plus two copies of cube triangles (one reversed)
 * and a triangle with a repeated corner. Every triangle gets its own three
 * points, as in an STL file. */
enum { CUBE_TRIS = 17, CUBE_POSITIONS = 9 };
static const double corner[9][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1},
                                    {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, 0.5}};
static const int cube_tri[CUBE_TRIS][3] = {
    {0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, /* z = 0, z = 1, y = 0 */
    {0, 5, 8}, {8, 5, 4}, {0, 8, 4},                       /* y = 0 split, zero-area (0 m 4) */
    {3, 6, 2}, {3, 7, 6}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}, /* y = 1, x = 0, x = 1 */
    {0, 2, 1}, {6, 5, 4},                                  /* copies of 0 and (reversed) 2 */
    {1, 1, 2}};                                            /* a repeated corner */

static void cube_soup(double *x, int32_t *t) {
  for (int e = 0; e < CUBE_TRIS; e++)
    for (int k = 0; k < 3; k++) {
      for (int c = 0; c < 3; c++) x[3 * (3 * e + k) + c] = corner[cube_tri[e][k]][c];
      t[3 * e + k] = 3 * e + k;
    }
}

Test(surface_repair, cube_soup_duplicates_and_degenerates) {
  double x[3 * 3 * CUBE_TRIS];
  int32_t t[3 * CUBE_TRIS];
  cube_soup(x, t);
  double *xo = NULL;
  int32_t *to = NULL;
  int64_t npo = 0, nto = 0;
  bs_surface_report r;
  bs_error err = {0};
  int rc = bs_shim_repair_surface(x, 3 * CUBE_TRIS, t, CUBE_TRIS, NULL, &xo, &npo, &to, &nto, &r, &err);
  cr_assert_eq(rc, BS_OK, "%s", err.msg);
  cr_expect_eq(r.tris_in, CUBE_TRIS);
  cr_expect_eq(r.duplicate_points, 3 * CUBE_TRIS - CUBE_POSITIONS, "merged %lld", (long long)r.duplicate_points);
  cr_expect_eq(r.duplicate_tris, 2, "duplicates %lld", (long long)r.duplicate_tris);
  cr_expect_eq(r.degenerate_tris, 2, "degenerates %lld (one repeated corner, one collinear)",
               (long long)r.degenerate_tris);
  cr_expect_eq(r.holes, 0);
  cr_expect_eq(r.self_intersections, 0);
  cr_expect_eq(r.tris_out, nto);
  cr_expect(nto >= 12 && nto <= 14, "%lld triangles out", (long long)nto);
  assert_closed_oriented(to, nto);
  cr_expect_float_eq(soup_volume(xo, to, nto), 1.0, 1e-12);
  cr_expect_float_eq(r.volume, 1.0, 1e-12);
  int32_t *pairs = NULL;
  int64_t n_pairs = -1;
  cr_assert_eq(bs_shim_self_intersections(xo, npo, to, nto, &pairs, &n_pairs, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(n_pairs, 0, "%lld intersecting pairs (a degenerate triangle is a pair (i, i))", (long long)n_pairs);
  bs_shim_free(pairs);
  bs_shim_free(xo);
  bs_shim_free(to);
}

/* A new file /tmp/bs_test_repair_XXXXXX.off (path: a buffer of 64), open for writing. */
static FILE *temp_off(char *path) {
  snprintf(path, 64, "/tmp/bs_test_repair_XXXXXX.off");
  int fd = mkstemps(path, 4);
  cr_assert(fd >= 0, "cannot create %s", path);
  FILE *f = fdopen(fd, "w");
  cr_assert_not_null(f);
  return f;
}

/* The soup written as an OFF file meshes into the unit cube. */
Test(surface_repair, cube_soup_file_meshes) {
  char path[64];
  FILE *f = temp_off(path);
  double x[3 * 3 * CUBE_TRIS];
  int32_t t[3 * CUBE_TRIS];
  cube_soup(x, t);
  fprintf(f, "OFF\n%d %d 0\n", 3 * CUBE_TRIS, CUBE_TRIS);
  for (int i = 0; i < 3 * CUBE_TRIS; i++) fprintf(f, "%.17g %.17g %.17g\n", x[3 * i], x[3 * i + 1], x[3 * i + 2]);
  for (int e = 0; e < CUBE_TRIS; e++) fprintf(f, "3 %d %d %d\n", t[3 * e], t[3 * e + 1], t[3 * e + 2]);
  fclose(f);
  bs_surface_report r;
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, &(bs_mesh_read_opts){.report = &r}, &m, &err);
  remove(path);
  cr_assert_eq(rc, BS_OK, "%s", err.msg);
  cr_expect_float_eq(bs_mesh_volume(m), 1.0, 1e-12);
  cr_expect_eq(r.duplicate_tris, 2);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* Polygons that are not convex are split on their own vertices without a
 * triangle outside them: an L-shaped prism of two hexagons and six quads
 * (CGAL's corner_poly.off, vertex for vertex). Split into fans its hexagons
 * had a triangle outside each, 12 intersecting pairs, and the repaired
 * surface (14,482 triangles, volume 6.083) came out of Mesh_3 pinched. */
Test(surface_repair, non_convex_polygons_split_inside) {
  char path[64];
  FILE *f = temp_off(path);
  fputs("OFF\n12 8 0\n0 2 1\n2 2 1\n2 0 1\n0 2 -1\n2 2 -1\n2 0 -1\n1 1 1\n1 1 -1\n0 1 1\n0 1 -1\n1 0 1\n"
        "1 0 -1\n4 3 0 1 4\n6 8 6 10 2 1 0\n4 9 8 0 3\n6 9 3 4 5 11 7\n4 5 4 1 2\n4 9 7 6 8\n4 11 5 2 10\n"
        "4 11 10 6 7\n",
        f);
  fclose(f);
  double *x = NULL;
  int32_t *t = NULL;
  int64_t np = 0, nt = 0, n_pairs = -1;
  int32_t *pairs = NULL;
  bs_error err = {0};
  int rc = bs_shim_read_surface(path, &x, &np, &t, &nt, &err);
  remove(path);
  cr_assert_eq(rc, BS_OK, "%s", err.msg);
  cr_expect_eq(nt, 20, "4 + 4 triangles for the hexagons, 12 for the quads");
  cr_assert_eq(bs_shim_self_intersections(x, np, t, nt, &pairs, &n_pairs, &err), BS_OK, "%s", err.msg);
  cr_expect_eq(n_pairs, 0, "%lld intersecting pairs", (long long)n_pairs);
  bs_shim_surface_audit_out a;
  cr_assert_eq(bs_shim_surface_audit(x, np, t, nt, &a, &err), BS_OK, "%s", err.msg);
  cr_expect(a.closed && !a.self_intersecting, "closed %d, self-intersecting %d", a.closed, a.self_intersecting);
  cr_expect_float_eq(fabs(a.volume), 6.0, 1e-12, "volume %.17g", a.volume);
  bs_shim_free(pairs);
  bs_shim_free(x);
  bs_shim_free(t);
}

Test(surface_repair, bad_soups_refused) {
  double x[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  int32_t t[3] = {0, 1, 3};
  double *xo = NULL;
  int32_t *to = NULL;
  int64_t npo, nto;
  bs_error err = {0};
  cr_expect_eq(bs_shim_repair_surface(x, 3, t, 1, NULL, &xo, &npo, &to, &nto, NULL, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "triangle 0 refers to point 3"), "%s", err.msg);
  int32_t flat[3] = {0, 0, 1};
  cr_expect_eq(bs_shim_repair_surface(x, 3, flat, 1, NULL, &xo, &npo, &to, &nto, NULL, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "degenerate"), "%s", err.msg);
  x[4] = NAN;
  cr_expect_eq(bs_shim_repair_surface(x, 3, t, 1, NULL, &xo, &npo, &to, &nto, NULL, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "point 1 has a non-finite coordinate"), "%s", err.msg);
  cr_expect_null(xo);
  cr_expect_null(to);
}

/* A file whose triangles are all degenerate: the message names the file. */
Test(surface_repair, all_degenerate_file_refused) {
  char path[64];
  FILE *f = temp_off(path);
  fputs("OFF\n3 2 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 1\n3 0 1 2\n", f);
  fclose(f);
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, NULL, &m, &err);
  remove(path);
  cr_expect_eq(rc, BS_EINPUT, "%s", err.msg);
  cr_expect(strstr(err.msg, path) && strstr(err.msg, "degenerate"), "%s", err.msg);
  cr_expect_null(m);
}

/* ---- the corpus ----------------------------------------------------------- */

/* Meshes path with opts and checks the tets: valid, none inverted, the volume
 * within 1% of what the repaired surface encloses. */
static bs_mesh *mesh_corpus(const char *path, bs_mesh_read_opts *o, bs_surface_report *r) {
  o->report = r;
  /* On the scans' own triangles (size 0) Gmsh's tets are slivers (0.2-0.5
   * degrees): the repair is what these tests check, so the quality gate is
   * off; meshing at a size through CGAL is test_mesh_surface's. */
  if (o->size <= 0) o->min_dihedral = -1;
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_read(path, o, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_expect_eq(q.n_inverted, 0);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  cr_expect(r->volume > 0);
  cr_expect(fabs(bs_mesh_volume(m) - r->volume) <= 0.01 * r->volume, "tets %.9g, surface %.9g", bs_mesh_volume(m),
            r->volume);
  return m;
}

Test(surface_repair, camel_self_intersections_autorefined) {
  bs_surface_report r;
  bs_mesh *m = mesh_corpus(corpus("camel.off"), &(bs_mesh_read_opts){0}, &r);
  cr_expect_eq(r.tris_in, 19536);
  cr_expect_eq(r.self_intersections, 20);
  cr_expect_eq(r.self_intersection_fix, 1);
  cr_expect(fabs(r.volume - r.volume_before) <= 1e-3 * r.volume_before, "%.9g vs %.9g", r.volume, r.volume_before);
  cr_expect_eq(r.tris_out, m->n_faces, "the clean surface is the mesh's boundary");
  bs_mesh_destroy(&m);
}

/* Gmsh refused the cow after the local removal ("overlapping facets") until
 * the folds it leaves were cut out and re-filled. */
Test(surface_repair, cow_folds_refilled) {
  bs_surface_report r;
  bs_mesh *m = mesh_corpus(corpus("cow.off"), &(bs_mesh_read_opts){0}, &r);
  cr_expect_eq(r.self_intersections, 101);
  cr_expect_eq(r.self_intersection_fix, 2);
  cr_expect(r.fold_tris > 0, "no fold was re-filled");
  cr_expect(fabs(r.volume - r.volume_before) <= 2e-3 * r.volume_before, "%.9g vs %.9g", r.volume, r.volume_before);
  bs_mesh_destroy(&m);
}

Test(surface_repair, elk_self_intersections_removed_locally) {
  bs_surface_report r;
  bs_mesh *m = mesh_corpus(corpus("elk.off"), &(bs_mesh_read_opts){0}, &r);
  cr_expect_eq(r.self_intersections, 7);
  cr_expect_eq(r.self_intersection_fix, 2, "autorefinement keeps almost nothing of the elk: the local removal runs");
  cr_expect(fabs(r.volume - r.volume_before) <= 1e-3 * r.volume_before, "%.9g vs %.9g", r.volume, r.volume_before);
  bs_mesh_destroy(&m);
}

Test(surface_repair, pig_holes_refused_by_default) {
  const char *path = corpus("pig.off");
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_read(path, NULL, &m, &err), BS_EINPUT, "%s", err.msg);
  const char *needles[] = {path, "not closed", "7 boundary loops", "largest has diameter 0.1439", "perimeter",
                           "11 edges", "around (0.1363, 0.2008, 0.2021)", "close_holes"};
  for (size_t i = 0; i < sizeof needles / sizeof *needles; i++)
    cr_expect(strstr(err.msg, needles[i]), "'%s' not in: %s", needles[i], err.msg);
  cr_expect_null(m);
}

Test(surface_repair, pig_holes_closed_on_request) {
  bs_surface_report r;
  bs_mesh *m = mesh_corpus(corpus("pig.off"), &(bs_mesh_read_opts){.close_holes = 1}, &r);
  cr_expect_eq(r.holes, 7);
  cr_expect_eq(r.holes_closed, 7);
  cr_expect(r.hole_tris >= 7, "%lld triangles added", (long long)r.hole_tris);
  cr_expect(fabs(r.hole_max_diameter - 0.1439) < 1e-4, "largest closed %.6g", r.hole_max_diameter);
  cr_expect(r.hole_max_perimeter > r.hole_max_diameter);
  cr_expect(r.hole_max_diameter <= BS_SURFACE_MAX_HOLE_DEFAULT * r.bbox_diagonal);
  cr_expect_eq(r.self_intersections, 3, "the pig also has 3 intersecting pairs");
  bs_mesh_destroy(&m);
}

Test(surface_repair, shark_large_holes_refused) {
  const char *path = corpus("mech-holes-shark.off");
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_read(path, &(bs_mesh_read_opts){.close_holes = 1}, &m, &err), BS_EINPUT, "%s", err.msg);
  const char *needles[] = {path, "4 boundary loops", "largest has diameter 0.799", "exceeds the largest hole closed"};
  for (size_t i = 0; i < sizeof needles / sizeof *needles; i++)
    cr_expect(strstr(err.msg, needles[i]), "'%s' not in: %s", needles[i], err.msg);
  cr_expect_null(m);
}

Test(surface_repair, shark_holes_closed_with_a_larger_limit) {
  bs_surface_report r;
  bs_mesh *m = mesh_corpus(corpus("mech-holes-shark.off"), &(bs_mesh_read_opts){.close_holes = 1, .max_hole = 0.5},
                           &r);
  cr_expect_eq(r.holes_closed, 4);
  cr_expect(fabs(r.hole_max_diameter - 0.799) < 1e-3, "%.6g", r.hole_max_diameter);
  bs_mesh_destroy(&m);
}

/* The unit sphere as latitude rings with the cap above z = z0 cut away:
 * ring 0 (the hole's loop, planar at z0) down to the south pole, `rings`
 * rings of `around` points, outward triangles. x, t sized by the caller. */
#define CAP_RINGS 40
#define CAP_AROUND 96
#define CAP_POINTS (CAP_RINGS * CAP_AROUND + 1)
#define CAP_TRIS ((2 * (CAP_RINGS - 1) + 1) * CAP_AROUND)
static void open_sphere(double z0, double *x, int32_t *t) {
  const double th0 = acos(z0);
  for (int i = 0; i < CAP_RINGS; i++)
    for (int j = 0; j < CAP_AROUND; j++) {
      double th = th0 + (M_PI - th0) * i / CAP_RINGS, ph = 2 * M_PI * j / CAP_AROUND;
      double *p = x + 3 * (i * CAP_AROUND + j);
      p[0] = sin(th) * cos(ph), p[1] = sin(th) * sin(ph), p[2] = cos(th);
    }
  double *pole = x + 3 * (CAP_POINTS - 1);
  pole[0] = pole[1] = 0, pole[2] = -1;
  int32_t *q = t;
  for (int i = 0; i < CAP_RINGS; i++)
    for (int j = 0; j < CAP_AROUND; j++) {
      int32_t a = i * CAP_AROUND + j, b = i * CAP_AROUND + (j + 1) % CAP_AROUND;
      if (i + 1 == CAP_RINGS) {
        int32_t f[3] = {a, CAP_POINTS - 1, b};
        memcpy(q, f, sizeof f), q += 3;
        continue;
      }
      int32_t c = a + CAP_AROUND, d = b + CAP_AROUND, f[6] = {a, c, b, b, c, d};
      memcpy(q, f, sizeof f), q += 6;
    }
}

/* Closing a hole across a curved surface: the fill kept is a membrane over
 * the planar loop (flat: the closed volume is the open surface closed by the
 * disc at z0, exactly), and the report measures what it leaves out: faired,
 * the fill would bulge like the sphere around it and enclose most of the
 * missing cap. */
Test(surface_repair, hole_fill_measured_against_its_faired_form) {
  static double x[3 * CAP_POINTS];
  static int32_t t[3 * CAP_TRIS];
  const double z0 = 0.8, h = 1 - z0, cap = M_PI * h * h * (3 - h) / 3; /* the spherical cap's volume */
  open_sphere(z0, x, t);
  double flat = soup_volume(x, t, CAP_TRIS); /* + the flat disc's tets, which have volume 0 about (0, 0, z0) */
  for (int j = 0; j < CAP_AROUND; j++) {
    const double *a = x + 3 * j, *b = x + 3 * ((j + 1) % CAP_AROUND);
    flat += z0 * (a[0] * b[1] - a[1] * b[0]) / 6; /* the fan from (0, 0, z0), reversed: ring 0 runs clockwise */
  }
  double *xo = NULL;
  int32_t *to = NULL;
  int64_t npo = 0, nto = 0;
  bs_surface_report r;
  bs_error err = {0};
  bs_surface_repair_opts o = {.close_holes = 1, .max_hole = 0.5};
  cr_assert_eq(bs_shim_repair_surface(x, CAP_POINTS, t, CAP_TRIS, &o, &xo, &npo, &to, &nto, &r, &err), BS_OK, "%s",
               err.msg);
  cr_expect_eq(r.holes_closed, 1);
  cr_expect_eq(r.holes_fair_estimated, 1, "the faired fill is measured");
  cr_expect_eq(r.self_intersections, 0);
  assert_closed_oriented(to, nto);
  cr_expect(fabs(r.volume - soup_volume(xo, to, nto)) < 1e-12, "%.12g", r.volume);
  cr_expect(fabs(r.hole_cap_volume) < 1e-12, "a membrane over a planar loop is flat: %.3g", r.hole_cap_volume);
  cr_expect(fabs(r.volume - flat) < 1e-9 * r.volume, "volume %.12g = flat-capped %.12g", r.volume, flat);
  /* Faired, the fill has 90% of the missing cap (0.1059 of 0.1173). */
  cr_expect(r.hole_fair_volume > 0.8 * cap && r.hole_fair_volume < 1.05 * cap, "faired: %.6g of the cap's %.6g",
            r.hole_fair_volume, cap);
  const double disc = M_PI * (1 - z0 * z0);
  cr_expect(fabs(r.hole_area - disc) < 0.01 * disc, "fill area %.6g (the disc's %.6g)", r.hole_area, disc);
  bs_shim_free(xo);
  bs_shim_free(to);
}

/* bigstep mesh info prints the report; --close-holes reaches the repair. */
Test(surface_repair, cli_close_holes) {
  char cmd[1024], *out = NULL;
  snprintf(cmd, sizeof cmd, "%s mesh info %s --min-dihedral 0", BS_BIGSTEP_EXE, corpus("pig.off"));
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, "7 boundary loops"), "%s", out);
  free(out);
  snprintf(cmd, sizeof cmd, "%s mesh info %s --min-dihedral 0 --close-holes", BS_BIGSTEP_EXE, corpus("pig.off"));
  cr_expect_eq(bs_test_run(cmd, &out), 0, "%s", out);
  cr_expect(strstr(out, "holes: 7 found, 7 closed with"), "%s", out);
  /* the 4 smallest fills have no inner vertex to fair */
  cr_expect(strstr(out, "the fills: area") && strstr(out, "faired (3 of 7), they would enclose"), "%s", out);
  cr_expect(strstr(out, "self-intersections: 3 pairs of triangles, removed by autorefinement"), "%s", out);
  free(out);
  snprintf(cmd, sizeof cmd, "%s mesh info %s --min-dihedral 0 --close-holes --max-hole 2", BS_BIGSTEP_EXE, corpus("pig.off"));
  cr_expect_eq(bs_test_run(cmd, &out), 2, "%s", out);
  cr_expect(strstr(out, "--max-hole must be a number in (0, 1]"), "%s", out);
  free(out);
}

/* A scene's body on pig.off: refused (naming the scene's body, the file and
 * the loops) without bodies[].close_holes, simulated with it. */
Test(surface_repair, scene_close_holes) {
  static const char *const fmt =
      "{\"time\": {\"fps\": 24, \"frames\": 1, \"steps_per_frame\": 1},\n"
      " \"bodies\": [{\"mesh\": \"%s\", \"min_dihedral\": 0, \"close_holes\": %s,\n"
      "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}]}\n";
  const char *mesh = corpus("pig.off");
  char text[2048];
  for (int close = 0; close <= 1; close++) {
    snprintf(text, sizeof text, fmt, mesh, close ? "true" : "false");
    char path[] = "/tmp/bs_scene_repair_XXXXXX";
    bs_test_write_scene(path, text);
    bs_error err;
    int rc = sim_load_error(path, NULL, 0, &err);
    unlink(path);
    if (close) {
      cr_expect_eq(rc, BS_OK, "%s", err.msg);
    } else {
      cr_expect_eq(rc, BS_EINPUT, "%s", err.msg);
      cr_expect(strstr(err.msg, "pig.off") && strstr(err.msg, "7 boundary loops"), "%s", err.msg);
    }
  }
}
