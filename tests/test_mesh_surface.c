/* Closed surfaces meshed into tets by CGAL's Mesh_3 (bs_mesh_read at a size,
 * mesh/surface_mesh.c, shim/shim_mesh3.cpp) and the quality gate
 * (bs_mesh_dihedral_gate, on the CGAL and the Gmsh paths).
 *
 * Corpus: data/meshes/ from Debian's libcgal-demo (setup.sh extracts it; the
 * tests that need a file skip without it): fandisk.off (a CAD part with sharp
 * edges), armadillo.off (a 52k-triangle scan), elephant.off (a 5.6k-triangle
 * scan), sphere.off, sphere.stl. The figures the bounds stand on (Release,
 * this machine, h = diagonal / N):
 *   fandisk   N 36: 10.7k tets, min dihedral 10.08, volume +0.03%, Hausdorff 0.22 h
 *   armadillo N 35: 39.3k tets, min dihedral 10.004, volume -0.84%, Hausdorff 0.13 h
 *   elephant  N 36: 22.6k tets, min dihedral 10.008, volume -0.84%, Hausdorff 0.16 h
 * A scan (not CAD-like) is meshed with facet distance h / 25, facet angle
 * 30, radius-edge 2 and a size field from its thickness (2 elements across
 * parts thinner than 2 h); with a CAD part's criteria (facet distance h / 10,
 * radius-edge 3, size h) the armadillo's volume was 3.0% short (7.8k tets)
 * and the elephant's 2.7% (6.4k tets, 9.1 degrees: under the gate). */
#define _POSIX_C_SOURCE 200809L

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "soup_util.h"

/* Through the default mesher (auto: Mesh_3 at these sizes). */
static void mesh_checked(const char *rel, double n, double vol_tol, double haus_over_h) {
  mesh_checked_with(rel, n, BS_SURFACE_AUTO, vol_tol, haus_over_h);
}

Test(mesh_surface, fandisk_cad_part) { mesh_checked("data/meshes/fandisk.off", 36, 0.01, 0.3); }

Test(mesh_surface, armadillo_scan) { mesh_checked("data/meshes/armadillo.off", 35, 0.01, 0.2); }

/* The elephant's trunk, ears and tusks are thinner than h: the scan criteria
 * keep its volume within 1% and meet the gate. */
Test(mesh_surface, elephant_scan_volume) { mesh_checked("data/meshes/elephant.off", 36, 0.01, 0.25); }

/* The camel (data/corpus/cgal: 20 self-intersecting pairs removed by
 * autorefinement) at diagonal / 30 through Mesh_3. Before the shim made the
 * complex a 2-manifold, its mesh had a one-tet cavity under the hump and 7
 * edges in four boundary triangles (two parts of the body touching along
 * them), which bs_mesh_check accepts; that first mesh (15,949 tets, 10.003
 * degrees) is 1.38% short of the volume, so it is made again with facet
 * distance h / 40 (8.0 degrees: refused) and h / 55, whose mesh left two
 * cavities in a 3 mm sheet on the head until every cavity of a one-piece
 * surface was filled, and is under the gate, so HXT meshes it again inside
 * its boundary. Measured: 95,099 tets, 11.92 degrees, volume -0.60%,
 * Hausdorff 0.37 h. That last step is Gmsh's, and Gmsh's result depends
 * on where the heap lands (ASLR: under `setarch -R` every run gives the
 * same 94,884 tets): 11.38 to 12.11 degrees over 30 runs here, and in 1
 * run here and in CI's run of 2026-12-05 it missed the gate, so the first
 * mesh (-1.38%, Hausdorff 0.40 h) was kept, as the mesher says it does.
 * HXT has had three attempts since (bs__mesh_hxt_inside), so that takes
 * three misses now; the bound holds for both meshes. */
Test(mesh_surface, camel_mesh3_boundary_is_a_manifold) {
  mesh_checked_with("data/corpus/cgal/camel.off", 30, BS_SURFACE_CGAL, 0.015, 0.5);
}

/* At diagonal / 40 Mesh_3's first mesh is under the gate (9.6 degrees);
 * meshed again inside its own boundary by HXT it passes (34.4k tets,
 * 12.9 degrees) but 1.15% short of the volume; with facet distance h / 40,
 * then HXT inside its boundary: 89,543 tets, 10.96 degrees, volume -0.63%,
 * Hausdorff 0.49 h. Before the HXT step, both paths refused it. */
Test(mesh_surface, camel_under_the_gate_meshed_again_inside_its_boundary) {
  mesh_checked_with("data/corpus/cgal/camel.off", 40, BS_SURFACE_CGAL, 0.01, 0.75);
}

/* At diagonal / 50 (the mesher auto): Mesh_3's first mesh is under the
 * gate (7.07 degrees, and after HXT inside its boundary); the tetrahedral
 * remeshing does not lift it (2 rounds of each protection, no gain); made
 * again with facet distance h / 40 its complex had 7 cavities (2 to 52
 * cells) in a 3 mm sheet on the head, now filled (a one-piece surface
 * encloses no void), and HXT inside that boundary meets the gate.
 * Measured: 129.5k tets, 10.02 degrees, volume -0.49%, Hausdorff 0.31 h
 * (before: the remesh path, 2.67% short). */
Test(mesh_surface, camel_at_diagonal_50_meshed_again_finer_when_mesh3_misses_the_gate) {
  mesh_checked_with("data/corpus/cgal/camel.off", 50, BS_SURFACE_AUTO, 0.01, 0.5);
}

/* The elk (7 self-intersecting pairs, removed locally) at diagonal / 40:
 * Mesh_3 with the scan criteria passes the gate 1.06% short of the volume
 * (28.8k tets, 10.02 degrees); meshed again with facet distance h / 40 it
 * is within 1%. Measured: 59,986 tets, 10.001 degrees, volume -0.51%,
 * Hausdorff 0.12 h. (The cow at diagonal / 30, refused at 5.73 degrees
 * before, passes the same way at h = 0.04051, -0.38%, but not at h =
 * 0.04057: 9.48 degrees at h / 40, so it is not the test.) */
Test(mesh_surface, elk_meshed_again_with_a_finer_facet_distance) {
  mesh_checked_with("data/corpus/cgal/elk.off", 40, BS_SURFACE_AUTO, 0.01, 0.2);
}

/* A CAD part whose Mesh_3 mesh (sharp edges kept, facet distance h / 10)
 * passes the gate short of the volume is meshed again with finer facet
 * distances, as a scan is: pinion.off (CGAL's data/meshes, a gear) at
 * diagonal / 25 was 1.12% short at h / 10 (bench/results/mesh-corpus-d25.txt);
 * measured at h / 40: 24.9k tets, 10.23 degrees, -0.33%, Hausdorff 0.12 h. */
Test(mesh_surface, cad_part_meshed_again_with_a_finer_facet_distance) {
  mesh_checked_with("data/corpus/cgal/pinion.off", 25, BS_SURFACE_AUTO, 0.01, 0.3);
}

/* The mesher auto takes the remesh path when the Mesh_3 path refuses: the
 * camel at diagonal / 50 with a gate of 13 degrees, which Mesh_3's meshes
 * do not reach (7.07; 10.02 and up to 12.03 after HXT inside the finer ones'
 * boundaries); the remesh path meets it, 2.7% short of the volume, about
 * 11.5k tets (Mesh_3's are 24k-130k). HXT's result depends on the heap's
 * addresses (see camel_mesh3_boundary_is_a_manifold): 13.45 to 13.96
 * degrees in 22 runs here, and one run in about 24 missed 13, so the
 * mesher refused the camel, until HXT was given three attempts
 * (bs__mesh_hxt_inside). */
Test(mesh_surface, auto_takes_the_remesh_path_when_mesh3_refuses) {
  char path[1024];
  soup s;
  soup_or_skip("data/corpus/cgal/camel.off", path, sizeof path, &s);
  bs_mesh_read_opts o = {.size = s.diag / 50, .min_dihedral = 13};
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_log_info("camel at diagonal / 50, gate 13: %d tets, %.3f degrees, volume %g vs %g", m->n_tets, q.dihedral_min,
              bs_mesh_volume(m), s.volume);
  cr_expect_geq(q.dihedral_min, 13.0, "%.3f degrees", q.dihedral_min);
  cr_expect_eq(q.n_inverted, 0);
  cr_expect_eq(bs__boundary_manifold(m, path, 1, &err), BS_OK, "%s", err.msg);
  cr_expect_lt(m->n_tets, 20000, "%d tets: not the remesh path's mesh", m->n_tets);
  cr_expect(fabs(bs_mesh_volume(m) - s.volume) <= 0.03 * s.volume, "tets %g, surface %g", bs_mesh_volume(m), s.volume);
  bs_mesh_destroy(&m);
  soup_free(&s);
}

/* The cow (101 self-intersecting pairs, folds re-filled) at diagonal / 40
 * of the repaired surface: Mesh_3 at the first try. Measured: 30,097 tets,
 * 10.004 degrees, volume -0.56%, Hausdorff 0.34 h. (At diagonal / 30 it
 * passes at h = 0.04051 through h / 40, -0.38%, and is refused at h =
 * 0.04057: the gate is at Mesh_3's edge there.) */
Test(mesh_surface, cow_repaired_scan) { mesh_checked_repaired("data/corpus/cgal/cow.off", 40, 0, 0.01, 0.45); }

/* The pig (7 holes closed on request, 3 self-intersecting pairs) at
 * diagonal / 30. Measured: 7,055 tets, 10.45 degrees, volume -0.79%,
 * Hausdorff 0.38 h. */
Test(mesh_surface, pig_holes_closed_meshed_at_a_size) {
  mesh_checked_repaired("data/corpus/cgal/pig.off", 30, 1, 0.01, 0.5);
}

/* The thickness size field is built for a scan and not for a CAD part: on
 * the elephant (its ears and trunk thinner than 2 h) part of the surface
 * samples get a size under h, down to the floor h / 8; the fandisk keeps
 * its features and size h everywhere. */
Test(mesh_surface, thickness_field_on_scans_only) {
  const char *rel[2] = {"data/meshes/elephant.off", "data/meshes/fandisk.off"};
  for (int k = 0; k < 2; k++) {
    char path[1024];
    soup s;
    soup_or_skip(rel[k], path, sizeof path, &s);
    const double h = s.diag / 12;
    bs_shim_mesh3_opts o = {.size = h, .feature_angle = 60, .smoother = BS_SHIM_SMOOTH_ODT, .smooth_iterations = 5,
                            .perturb = 1, .exude = 1, .target_dihedral = 10, .max_rounds = 1,
                            .thickness_elements = 2, .min_size = h / 8};
    bs_shim_mesh3_out r;
    bs_error err;
    bs_error_clear(&err);
    cr_assert_eq(bs_shim_mesh_surface(path, s.x, s.np, s.t, s.nt, &o, &r, &err), 0, "%s", err.msg);
    cr_log_info("%s at h %g: %lld tets, local size min %.3f h, %.3f of the samples under h, %lld feature chains",
                rel[k], h, (long long)r.n_tets, r.local_size_min / h, r.local_fraction, (long long)r.n_features);
    if (k == 0) {
      cr_expect_eq(r.n_features, 0);
      cr_expect(r.local_fraction > 0.2 && r.local_fraction < 1, "%.3f of the elephant under h", r.local_fraction);
      cr_expect(fabs(r.local_size_min - h / 8) < 1e-9 * h, "the floor is %g h, not 1/8", r.local_size_min / h);
    } else {
      cr_expect_gt(r.n_features, 0, "the fandisk is meshed as a scan");
      cr_expect_eq(r.local_fraction, 0, "a CAD part got the thickness field");
      cr_expect_eq(r.local_size_min, h);
    }
    bs_shim_free(r.x);
    bs_shim_free(r.tets);
    soup_free(&s);
  }
}

/* s meshed by the shim at h without features and with a CAD part's
 * criteria (facet distance h / 10, radius-edge 3, size h; bs_mesh_read
 * would mesh it as a scan). */
static bs_mesh *no_features(const char *path, const soup *s, double h) {
  bs_shim_mesh3_opts o = {.size = h, .smoother = BS_SHIM_SMOOTH_ODT, .smooth_iterations = 10, .perturb = 1,
                          .exude = 1, .target_dihedral = 10, .max_rounds = 3};
  bs_shim_mesh3_out r;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_eq(bs_shim_mesh_surface(path, s->x, s->np, s->t, s->nt, &o, &r, &err), 0, "%s", err.msg);
  bs_mesh *m = NULL;
  cr_assert_eq(bs_mesh_create((int32_t)r.n_vertices, r.x, (int32_t)r.n_tets, r.tets, 0, NULL, &m, &err), 0, "%s",
               err.msg);
  bs_shim_free(r.x);
  bs_shim_free(r.tets);
  return m;
}

/* The fandisk's sharp edges (faces turning by more than 60 degrees) are kept:
 * every point along them lies within h / 8 of the mesh's boundary (measured
 * 0.097 h: the chords of its curved edges at h), while without features
 * (and a CAD part's criteria) the edges are cut off (0.58 h). */
Test(mesh_surface, fandisk_keeps_sharp_edges) {
  char path[1024];
  soup s;
  soup_or_skip("data/meshes/fandisk.off", path, sizeof path, &s);
  bs_error err;
  bs_error_clear(&err);
  double *seg = NULL;
  int64_t ne = 0;
  cr_assert_eq(bs_shim_sharp_edges(s.x, s.np, s.t, s.nt, 60, &seg, &ne, &err), 0, "%s", err.msg);
  cr_assert_gt(ne, 100, "only %lld sharp edges on the fandisk", (long long)ne);
  double h = s.diag / 36, worst[2] = {0, 0};
  for (int pass = 0; pass < 2; pass++) {
    bs_mesh *m = pass ? no_features(path, &s, h) : NULL;
    bs_mesh_read_opts o = {.size = h, .min_dihedral = -1};
    if (!pass) cr_assert_eq(bs_mesh_read(path, &o, &m, &err), 0, "%s", err.msg);
    bs_shim_tree *tree = NULL;
    cr_assert_eq(bs_shim_tree_create(m->x, m->n_vertices, m->faces, m->n_faces, &tree, &err), 0, "%s", err.msg);
    for (int64_t e = 0; e < ne; e++)
      for (int k = 0; k <= 4; k++) {
        double q[3], c[3];
        for (int j = 0; j < 3; j++) q[j] = seg[6 * e + j] + 0.25 * k * (seg[6 * e + 3 + j] - seg[6 * e + j]);
        cr_assert_eq(bs_shim_tree_closest(tree, q, c, NULL, NULL, NULL), 0);
        double d = sqrt((q[0] - c[0]) * (q[0] - c[0]) + (q[1] - c[1]) * (q[1] - c[1]) + (q[2] - c[2]) * (q[2] - c[2]));
        worst[pass] = fmax(worst[pass], d);
      }
    bs_shim_tree_destroy(&tree);
    bs_mesh_destroy(&m);
  }
  cr_log_info("fandisk sharp edges: %lld, farthest from the boundary %.3g h with features, %.3g h without", (long long)ne,
              worst[0] / h, worst[1] / h);
  cr_expect_leq(worst[0], h / 8, "a sharp-edge point %g (%.3f h) from the mesh", worst[0], worst[0] / h);
  cr_expect_gt(worst[1], 3 * worst[0], "without features the edges are as close (%g vs %g)", worst[1], worst[0]);
  bs_shim_free(seg);
  soup_free(&s);
}

/* The shim's tets come positively oriented (bs_shim_orient3d) and the mesh
 * is the same on a second run (sequential, seeded; with the scan criteria
 * and the thickness field). STL goes through it too. */
Test(mesh_surface, shim_orientation_and_determinism) {
  char path[1024];
  soup s;
  soup_or_skip("data/meshes/sphere.off", path, sizeof path, &s);
  bs_shim_mesh3_opts o = {.size = s.diag / 8, .feature_angle = 60, .smoother = BS_SHIM_SMOOTH_ODT,
                          .smooth_iterations = 5, .perturb = 1, .exude = 1, .target_dihedral = 10, .max_rounds = 2,
                          .scan_facet_angle = 30, .scan_radius_edge = 2, .thickness_elements = 2};
  bs_shim_mesh3_out r[2];
  bs_error err;
  bs_error_clear(&err);
  for (int k = 0; k < 2; k++) cr_assert_eq(bs_shim_mesh_surface(path, s.x, s.np, s.t, s.nt, &o, &r[k], &err), 0, "%s", err.msg);
  cr_assert_gt(r[0].n_tets, 50);
  for (int64_t t = 0; t < r[0].n_tets; t++) {
    const int32_t *v = r[0].tets + 4 * t;
    cr_assert_eq(bs_shim_orient3d(r[0].x + 3 * v[0], r[0].x + 3 * v[1], r[0].x + 3 * v[2], r[0].x + 3 * v[3]), 1,
                 "tet %lld is not positively oriented", (long long)t);
  }
  cr_expect_eq(r[0].n_tets, r[1].n_tets);
  cr_expect_eq(r[0].n_vertices, r[1].n_vertices);
  cr_expect(r[0].n_vertices == r[1].n_vertices && !memcmp(r[0].x, r[1].x, 3 * sizeof(double) * r[0].n_vertices),
            "a second run gives other vertices");
  cr_expect_eq(r[0].n_features, 0, "a sphere has no sharp edge");
  for (int k = 0; k < 2; k++) {
    bs_shim_free(r[k].x);
    bs_shim_free(r[k].tets);
  }
  soup_free(&s);
  if (have("data/meshes/sphere.stl", path, sizeof path)) {
    bs_mesh_read_opts ro = {.size = s.diag / 8};
    bs_mesh *m = NULL;
    cr_assert_eq(bs_mesh_read(path, &ro, &m, &err), 0, "%s", err.msg);
    cr_expect_gt(m->n_tets, 50);
    bs_mesh_destroy(&m);
  }
}

/* ---- refusals: each message names the file and the reason ------------------ */

static const char *write_tmp(const char *name, const char *text) {
  static char path[4][512];
  static int k;
  k = (k + 1) % 4;
  snprintf(path[k], sizeof path[k], "/tmp/bs_test_mesh_surface_%d_%s", (int)getpid(), name);
  FILE *f = fopen(path[k], "w");
  cr_assert_not_null(f);
  fputs(text, f);
  fclose(f);
  return path[k];
}

static void refused(const char *path, double size, double gate, const char *a, const char *b) {
  bs_mesh_read_opts o = {.size = size, .min_dihedral = gate};
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  int rc = bs_mesh_read(path, &o, &m, &err);
  cr_log_info("%s", err.msg);
  cr_assert_neq(rc, 0, "%s was meshed", path);
  cr_assert_null(m);
  cr_expect_not_null(strstr(err.msg, path), "the message does not name %s: %s", path, err.msg);
  cr_expect_not_null(strstr(err.msg, a), "'%s' not in: %s", a, err.msg);
  if (b) cr_expect_not_null(strstr(err.msg, b), "'%s' not in: %s", b, err.msg);
}

#define TET_OFF "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"

Test(mesh_surface, refusals) {
  refused(write_tmp("open.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n"), 0.2, 0,
          "not closed", "1 boundary loop");
  refused(write_tmp("empty.off", "OFF\n0 0 0\n"), 0.2, 0, "empty", NULL);
  refused(write_tmp("coarse.off", TET_OFF), 5.0, 0, "larger than the surface's bounding-box diagonal", NULL);
  refused(write_tmp("fine.off", TET_OFF), 1e-5, 0, "more than the", "the smallest size that fits");
  /* two tets through each other: the repair (bs_surface_prepare) makes their
   * union, which meshes; the shim's own refusal of a self-intersecting soup
   * is asked of the shim itself */
  {
    const double X[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.2, 0.2, 0.2, 1.2, 0.2, 0.2, 0.2, 1.2, 0.2, 0.2, 0.2, 1.2};
    const int32_t T[24] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4, 6, 5, 4, 5, 7, 4, 7, 6, 5, 6, 7};
    bs_shim_mesh3_opts o = {.size = 0.2, .max_rounds = 1};
    bs_shim_mesh3_out r;
    bs_error e;
    bs_error_clear(&e);
    cr_assert_neq(bs_shim_mesh_surface("crossing.off", X, 8, T, 8, &o, &r, &e), 0, "the crossing tets were meshed");
    cr_expect_not_null(strstr(e.msg, "crossing.off: the surface intersects itself"), "%s", e.msg);
  }
  /* three triangles on one edge */
  refused(write_tmp("fin.off", "OFF\n5 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
                               "3 0 1 4\n"),
          0.2, 0, "the surface", NULL);
  bs_error err;
  bs_error_clear(&err);
  double x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  int32_t t[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  bs_shim_mesh3_opts o = {.size = 0};
  bs_shim_mesh3_out r;
  cr_expect_neq(bs_shim_mesh_surface("zero.off", x, 4, t, 4, &o, &r, &err), 0);
  cr_expect(strstr(err.msg, "zero.off") && strstr(err.msg, "must be > 0"), "%s", err.msg);
  x[4] = NAN;
  o.size = 0.2;
  cr_expect_eq(bs_shim_mesh_surface("nan.off", x, 4, t, 4, &o, &r, &err), BS_ENUMERIC);
  cr_expect(strstr(err.msg, "nan.off") && strstr(err.msg, "point 1"), "%s", err.msg);
}

/* bs_mesh_read that must succeed, with the mesh's quality into q. */
static bs_mesh *read_quality(const char *path, const bs_mesh_read_opts *o, bs_mesh_quality *q) {
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_eq(bs_mesh_read(path, o, &m, &err), 0, "%s", err.msg);
  bs_mesh_quality_compute(m, NULL, q);
  return m;
}

/* ---- the gate --------------------------------------------------------------- */

Test(mesh_surface, gate_relaxed_passes_strict_fails) {
  char path[1024];
  soup s;
  soup_or_skip("data/meshes/sphere.off", path, sizeof path, &s);
  double h = s.diag / 6;
  bs_mesh_read_opts o = {.size = h, .min_dihedral = -1};
  bs_mesh_quality q;
  bs_mesh *m = read_quality(path, &o, &q);
  bs_error err;
  bs_error_clear(&err);
  cr_assert_lt(q.dihedral_min, 40);
  cr_expect_eq(bs_mesh_dihedral_gate(m, q.dihedral_min * 0.99, path, &err), 0, "%s", err.msg);
  cr_expect_eq(bs_mesh_dihedral_gate(m, 0, path, &err), 0, "gate 0 is no gate");
  bs_mesh_destroy(&m);
  o.min_dihedral = 40;
  o.surface_mesher = BS_SURFACE_CGAL; /* (auto would try the remesh path next, whose few HXT tets can reach 40) */
  int rc = bs_mesh_read(path, &o, &m, &err);
  cr_log_info("%s", err.msg);
  cr_assert_eq(rc, BS_EINPUT, "a gate of 40 degrees passed");
  const char *want[] = {path, "smallest dihedral angle is", "under the gate of 40", "tets are under it", "centred at ("};
  for (int k = 0; k < 5; k++) cr_expect_not_null(strstr(err.msg, want[k]), "'%s' not in: %s", want[k], err.msg);
  double got = strtod(strstr(err.msg, "angle is ") + strlen("angle is "), NULL);
  cr_expect(got > 0 && got < 40, "the angle reached, %g, is not stated", got);
  soup_free(&s);
}

/* The Gmsh path (.geo) runs Gmsh's optimisers towards the gate: the cube at
 * its own size meets the default gate; 40 degrees is refused, naming it. */
Test(mesh_surface, gmsh_path_gate) {
  char path[1024];
  snprintf(path, sizeof path, "%s/data/geo/cube.geo", BS_SOURCE_DIR);
  bs_mesh_read_opts o = {0};
  bs_mesh_quality q;
  bs_mesh *m = read_quality(path, &o, &q);
  cr_log_info("cube.geo: %d tets, min dihedral %.3f", m->n_tets, q.dihedral_min);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL);
  bs_mesh_destroy(&m);
  refused(path, 0, 40, "under the gate of 40", "relax the gate");
}

/* CGAL 5.5's ODT smoother crashes (SIGSEGV) on the cheese at 1/50 of its
 * diagonal, its sharp edges protected (the options are mesh3_opts's in
 * mesh/surface_mesh.c). Mesh_3 runs in a child process: the call returns,
 * with a mesh or with the crash named, and the caller lives on. */
Test(mesh_surface, a_crash_inside_cgal_is_an_error_not_the_end) {
  char path[1024];
  soup s;
  soup_or_skip("data/corpus/cgal/cheese.off", path, sizeof path, &s);
  const double h = s.diag / 50;
  bs_shim_mesh3_opts o = {.size = h, .facet_distance = h / 10, .feature_angle = BS_MESH_FEATURE_ANGLE,
                          .smoother = BS_SHIM_SMOOTH_ODT, .smooth_iterations = 10, .perturb = 1, .exude = 1,
                          .target_dihedral = 10, .max_rounds = 3, .scan_facet_distance = fmax(h / 25, s.diag / 900),
                          .scan_facet_angle = 30, .scan_radius_edge = 2, .thickness_elements = 2,
                          .size_gradation = 0.5, .min_size = h / 8};
  bs_shim_mesh3_out r;
  bs_error err;
  bs_error_clear(&err);
  const int rc = bs_shim_mesh_surface(path, s.x, s.np, s.t, s.nt, &o, &r, &err);
  cr_log_info("cheese at h %g: rc %d, %lld tets: %s", h, rc, (long long)r.n_tets, err.msg);
  cr_assert(rc == BS_OK || strstr(err.msg, "CGAL Mesh_3 crashed") || strstr(err.msg, "CGAL Mesh_3 ended"),
            "neither a mesh nor the crash named: %s", err.msg);
  if (rc == BS_OK) cr_expect_gt(r.n_tets, 0);
  else cr_expect_null(r.x, "an error left arrays");
  bs_shim_free(r.x);
  bs_shim_free(r.tets);
  soup_free(&s);
}
