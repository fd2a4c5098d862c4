/* Closed surfaces meshed by the "remesh" path (BS_SURFACE_REMESH,
 * mesh/surface_remesh.c): CGAL's isotropic remeshing of the surface at h
 * (shim/shim_remesh.cpp), Gmsh's HXT volume mesher on those triangles, then
 * Gmsh's optimisers to the quality gate.
 *
 * Corpus: data/meshes/ from Debian's libcgal-demo (setup.sh extracts it; the
 * tests that need a file skip without it). The figures the bounds stand on
 * (Release, this machine, h = diagonal / N; HXT's tet count varies from run
 * to run by a few tenths of a percent, the surface does not):
 *   elephant N 100: 93.0k to 93.3k tets, min dihedral 14.0 to 14.4, volume
 *   -0.35%, Hausdorff 0.530 h (tips of thin parts cut by the uniform edge
 *   length; CGAL Mesh_3 at that size: 82k tets, 0.45 h).
 * At coarse sizes the path is not used by default (BS_SURFACE_AUTO picks
 * Mesh_3 under about 2e5 tets): at N 36 the elephant is 3.7% short and
 * 0.85 h off. */
#define _POSIX_C_SOURCE 200809L

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_scene.h"
#include "bs_shim.h"
#include "cli_util.h"
#include "scene_fixture.h"
#include "soup_util.h"

Test(mesh_remesh, elephant_scan) { mesh_checked_with("data/meshes/elephant.off", 100, BS_SURFACE_REMESH, 0.01, 0.75); }

/* An open surface is refused by bs_mesh_read (the repair, before any
 * mesher) and by the shim itself, each message naming the file. */
Test(mesh_remesh, open_surface_refused) {
  char path[512];
  snprintf(path, sizeof path, "/tmp/bs_test_mesh_remesh_%d_open.off", (int)getpid());
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  fputs("OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n", f);
  fclose(f);
  bs_mesh_read_opts o = {.size = 0.2, .surface_mesher = BS_SURFACE_REMESH};
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_neq(bs_mesh_read(path, &o, &m, &err), 0, "%s was meshed", path);
  cr_assert_null(m);
  cr_log_info("%s", err.msg);
  cr_expect_not_null(strstr(err.msg, path), "the message does not name %s: %s", path, err.msg);
  cr_expect_not_null(strstr(err.msg, "not closed"), "%s", err.msg);
  unlink(path);
  const double x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const int32_t t[9] = {0, 2, 1, 0, 1, 3, 0, 3, 2};
  bs_shim_remesh_opts ro = {.size = 0.2};
  bs_shim_remesh_out r;
  cr_assert_neq(bs_shim_remesh_surface("open.off", x, 4, t, 3, &ro, &r, &err), 0, "the open soup was remeshed");
  cr_expect_null(r.points);
  cr_expect(strstr(err.msg, "open.off") && strstr(err.msg, "not closed"), "%s", err.msg);
}

/* The mesher names of --mesher and bodies[].mesher, parsed once into BS_SURFACE_*. */
Test(mesh_remesh, mesher_names) {
  int m = -7;
  cr_expect_eq(bs_mesh_parse_mesher("remesh", &m), 0);
  cr_expect_eq(m, BS_SURFACE_REMESH);
  cr_expect_eq(bs_mesh_parse_mesher("cgal", &m), 0);
  cr_expect_eq(m, BS_SURFACE_CGAL);
  cr_expect_eq(bs_mesh_parse_mesher("auto", &m), 0);
  cr_expect_eq(m, BS_SURFACE_AUTO);
  cr_expect_eq(bs_mesh_parse_mesher("gmsh", &m), -1, "gmsh is not offered");
  cr_expect_eq(bs_mesh_parse_mesher(NULL, &m), -1);
  cr_expect_eq(m, BS_SURFACE_AUTO, "a refused name changed the value");
  cr_expect_str_eq(bs_mesh_mesher_name(BS_SURFACE_REMESH), "remesh");
  cr_expect_str_eq(bs_mesh_mesher_name(BS_SURFACE_CGAL), "cgal");
}

/* bigstep mesh --mesher: remesh meshes the sphere; another word is a usage
 * error (exit 2) naming the flag. */
Test(mesh_remesh, cli_mesher) {
  if (access(BS_SOURCE_DIR "/data/meshes/sphere.off", R_OK) != 0) cr_skip_test("data/meshes/sphere.off missing");
  char *out = NULL;
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info " BS_SOURCE_DIR "/data/meshes/sphere.off --size 0.2 --mesher remesh",
                           &out),
               0, "%s", out);
  cr_expect(strstr(out, "tets") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:2 --mesher tetgen", &out), 2, "%s", out);
  cr_expect(strstr(out, "--mesher") && strstr(out, "tetgen"), "%s", out);
  free(out);
}

/* The fandisk's sharp edges survive the remeshing (diagonal / 36, the shim
 * alone, deterministic): with features 18 of the 3495 points sampled along
 * them lie farther than h / 8 from the remeshed surface, the farthest 0.243 h
 * (a short curved chain near (0.09, 0.055, -0.05) collapsed to its chord);
 * without features the edges are cut off (0.675 h). */
Test(mesh_remesh, fandisk_keeps_sharp_edges) {
  char path[1024];
  soup s;
  soup_or_skip("data/meshes/fandisk.off", path, sizeof path, &s);
  bs_error err;
  bs_error_clear(&err);
  double *seg = NULL, h = s.diag / 36, worst[2] = {0, 0};
  int64_t ne = 0, feats[2] = {0, 0}, far[2] = {0, 0};
  cr_assert_eq(bs_shim_sharp_edges(s.x, s.np, s.t, s.nt, 60, &seg, &ne, &err), 0, "%s", err.msg);
  for (int pass = 0; pass < 2; pass++) {
    bs_shim_remesh_opts o = {.size = h, .feature_angle = pass ? 0 : 60, .iterations = 3};
    bs_shim_remesh_out r;
    cr_assert_eq(bs_shim_remesh_surface(path, s.x, s.np, s.t, s.nt, &o, &r, &err), 0, "%s", err.msg);
    feats[pass] = r.n_features;
    bs_shim_tree *tree = NULL;
    cr_assert_eq(bs_shim_tree_create(r.points, r.n_points, r.tris, r.n_tris, &tree, &err), 0, "%s", err.msg);
    for (int64_t e = 0; e < ne; e++)
      for (int k = 0; k <= 4; k++) {
        double q[3], c[3], d2 = 0;
        for (int j = 0; j < 3; j++) q[j] = seg[6 * e + j] + 0.25 * k * (seg[6 * e + 3 + j] - seg[6 * e + j]);
        cr_assert_eq(bs_shim_tree_closest(tree, q, c, NULL, NULL, NULL), 0);
        for (int j = 0; j < 3; j++) d2 += (q[j] - c[j]) * (q[j] - c[j]);
        worst[pass] = fmax(worst[pass], sqrt(d2));
        far[pass] += sqrt(d2) > h / 8;
      }
    bs_shim_tree_destroy(&tree);
    bs_shim_free(r.points);
    bs_shim_free(r.tris);
  }
  cr_log_info("fandisk: %lld sharp edges, %lld chains kept; farthest %.3g h with features, %.3g h without",
              (long long)ne, (long long)feats[0], worst[0] / h, worst[1] / h);
  cr_expect_gt(feats[0], 10, "only %lld sharp-edge chains kept", (long long)feats[0]);
  cr_expect_eq(feats[1], 0);
  cr_expect_leq(worst[0], 0.3 * h, "a sharp-edge point %.3f h from the remeshed surface", worst[0] / h);
  cr_expect_leq(far[0], 5 * ne / 100, "%lld of %lld sharp-edge points over h / 8 away", (long long)far[0],
                (long long)(5 * ne));
  cr_expect_gt(worst[1], 2 * worst[0], "without features the edges are as close (%g vs %g)", worst[1], worst[0]);
  bs_shim_free(seg);
  soup_free(&s);
}

/* bodies[].mesher: parsed into BS_SURFACE_* (auto when absent); another word
 * is refused naming the key and the choices. */
Test(mesh_remesh, scene_mesher) {
  bs_scene *s = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_eq(bs_scene_parse(bs_test_good_scene, "good.json", 0, NULL, &s, &err), 0, "%s", err.msg);
  cr_expect_eq(s->bodies[0].mesher, BS_SURFACE_AUTO);
  bs_scene_destroy(&s);
  const char *set = "bodies.0.mesher=\"remesh\"";
  cr_assert_eq(bs_scene_parse(bs_test_good_scene, "good.json", 1, &set, &s, &err), 0, "%s", err.msg);
  cr_expect_eq(s->bodies[0].mesher, BS_SURFACE_REMESH);
  bs_scene_destroy(&s);
  set = "bodies.0.mesher=\"tetgen\"";
  cr_expect_eq(bs_scene_parse(bs_test_good_scene, "good.json", 1, &set, &s, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "bodies.0.mesher") && strstr(err.msg, "tetgen") && strstr(err.msg, "remesh"), "%s",
            err.msg);
  bs_scene_destroy(&s);
}
