/* `bigstep levelset SURFACE OUT`: grid level sets from closed surfaces. The
 * written file loads; its values are the signed distance (checked against
 * the exact distance to a cube given as an .off file, and against the ball of
 * data/geo/sphere.geo); a missing file, an open surface and an unwritable
 * output exit 1 naming the file; bad flags exit 2. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_levelset.h"
#include "cli_util.h"

static char dir[64];
static char exe[256]; /* the bigstep command with its environment */

/* In a sanitizer build (BS_SANITIZE) Gmsh 4.8 itself leaks a few hundred
 * bytes while meshing a surface (meshGFace), which LeakSanitizer turns into a
 * failed exit of bigstep: leaks whose stack is in libgmsh are suppressed
 * (bigstep's own are still reported). Without a sanitizer this is ignored. */
static void make_dir(void) {
  strcpy(dir, "/tmp/bs_test_levelset_cli_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
  char supp[128];
  snprintf(supp, sizeof supp, "%s/lsan.supp", dir);
  FILE *f = fopen(supp, "w");
  cr_assert_not_null(f);
  fputs("leak:libgmsh.so\n", f);
  fclose(f);
  snprintf(exe, sizeof exe, "LSAN_OPTIONS=suppressions=%s:print_suppressions=0 %s", supp, BS_BIGSTEP_EXE);
}

static void remove_dir(void) {
  if (dir[0]) {
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    (void)!system(cmd);
  }
}

TestSuite(levelset_cli, .init = make_dir, .fini = remove_dir);

/* The unit cube [0, 1]^3 as an OFF surface: 8 points, 12 outward triangles;
 * with drop_top the two triangles of the face y = 1 are left out (open). */
static void write_cube_off(const char *path, int drop_top) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  static const int tri[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                 {3, 7, 6}, {3, 6, 2}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}};
  static const double p[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                 {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  fprintf(f, "OFF\n8 %d 0\n", drop_top ? 10 : 12);
  for (int i = 0; i < 8; i++) fprintf(f, "%g %g %g\n", p[i][0], p[i][1], p[i][2]);
  for (int t = 0; t < 12; t++) {
    int top = p[tri[t][0]][1] == 1 && p[tri[t][1]][1] == 1 && p[tri[t][2]][1] == 1;
    if (drop_top && top) continue;
    fprintf(f, "3 %d %d %d\n", tri[t][0], tri[t][1], tri[t][2]);
  }
  fclose(f);
}

/* Exact signed distance to the box [0, 1]^3. */
static double cube_sdf(const double x[3]) {
  double out2 = 0, in = -1e300;
  for (int k = 0; k < 3; k++) {
    double d = fmax(-x[k], x[k] - 1); /* > 0 outside the slab */
    if (d > 0) out2 += d * d;
    in = fmax(in, d);
  }
  return out2 > 0 ? sqrt(out2) : in;
}

static bs_levelset *load(const char *path) {
  bs_levelset *ls = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_grid_load(path, &ls, &err), 0, "%s", err.msg);
  return ls;
}

Test(levelset_cli, cube_off_is_exact) {
  char off[128], out_path[128], cmd[1024];
  snprintf(off, sizeof off, "%s/cube.off", dir);
  snprintf(out_path, sizeof out_path, "%s/cube.bsls", dir);
  write_cube_off(off, 0);
  char *out = NULL;
  snprintf(cmd, sizeof cmd, "%s levelset %s %s --h 0.125 --margin 0.5", exe, off, out_path);
  cr_assert_eq(bs_test_run(cmd, &out), 0, "%s", out);
  /* box 1 m + 2 x 0.5 m margin = 2 m = 16 cells of 0.125 m: 17 nodes per axis */
  cr_expect(strstr(out, "17 x 17 x 17 = 4913 nodes") != NULL, "%s", out);
  cr_expect(strstr(out, "12 triangles") != NULL, "%s", out);
  free(out);
  bs_levelset *ls = load(out_path);
  int32_t n[3];
  double origin[3], h;
  const double *v = bs_levelset_grid_values(ls, n, origin, &h);
  cr_assert_not_null(v);
  cr_expect_eq(n[0], 17);
  cr_expect_eq(n[1], 17);
  cr_expect_eq(n[2], 17);
  cr_expect_float_eq(h, 0.125, 1e-15);
  for (int k = 0; k < 3; k++) cr_expect_float_eq(origin[k], -0.5, 1e-15);
  /* every node: the exact distance to the cube, negative inside */
  double worst = 0;
  int n_in = 0;
  for (int32_t k = 0; k < n[2]; k++)
    for (int32_t j = 0; j < n[1]; j++)
      for (int32_t i = 0; i < n[0]; i++) {
        double x[3] = {origin[0] + h * i, origin[1] + h * j, origin[2] + h * k};
        double got = v[i + n[0] * (j + n[1] * k)];
        worst = fmax(worst, fabs(got - cube_sdf(x)));
        n_in += got < 0;
      }
  cr_expect_lt(worst, 1e-12, "largest error %g m", worst);
  cr_expect_eq(n_in, 7 * 7 * 7, "nodes inside: %d", n_in); /* 0.125 .. 0.875 on each axis */
  bs_levelset_destroy(&ls);
}

Test(levelset_cli, sphere_geo_centre_and_corner) {
  char out_path[128], cmd[1024];
  snprintf(out_path, sizeof out_path, "%s/sphere.bsls", dir);
  char *out = NULL;
  snprintf(cmd, sizeof cmd, "%s levelset data/geo/sphere.geo %s --h 0.1 --margin 0.3", exe, out_path);
  cr_assert_eq(bs_test_run(cmd, &out), 0, "%s", out);
  cr_expect(strstr(out, "nodes, h 0.1 m, margin 0.3 m") != NULL, "%s", out);
  free(out);
  bs_levelset *ls = load(out_path);
  int32_t n[3];
  double origin[3], h;
  const double *v = bs_levelset_grid_values(ls, n, origin, &h);
  cr_assert_not_null(v);
  /* the ball of radius 0.5 m at the origin, meshed with flat facets of size
   * about 0.15 m: its surface lies within ~0.02 m inside the sphere */
  const double c[3] = {0, 0, 0};
  double phi_c = bs_levelset_eval(ls, 0.0, c, NULL, NULL);
  cr_expect(phi_c < -0.45 && phi_c > -0.5 - 1e-9, "phi at the centre %g, expected about -0.5", phi_c);
  /* the far corner node: positive, about its distance to the sphere */
  int32_t i = n[0] - 1, j = n[1] - 1, k = n[2] - 1;
  double p[3] = {origin[0] + h * i, origin[1] + h * j, origin[2] + h * k};
  double corner = v[i + n[0] * (j + n[1] * k)];
  double expect = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 0.5;
  cr_expect(corner > 0, "phi at the far corner %g", corner);
  cr_expect(fabs(corner - expect) < 0.03, "phi at the far corner %g, distance to the sphere %g", corner, expect);
  /* every node well away from the surface has the right sign and size */
  int bad = 0;
  for (int32_t kk = 0; kk < n[2]; kk++)
    for (int32_t jj = 0; jj < n[1]; jj++)
      for (int32_t ii = 0; ii < n[0]; ii++) {
        double q[3] = {origin[0] + h * ii, origin[1] + h * jj, origin[2] + h * kk};
        double r = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        double got = v[ii + n[0] * (jj + n[1] * kk)];
        bad += fabs(got - (r - 0.5)) > 0.03;
      }
  cr_expect_eq(bad, 0, "%d nodes off the sphere's distance by more than 0.03 m", bad);
  bs_levelset_destroy(&ls);
}

Test(levelset_cli, errors_name_the_file) {
  char path[128], cmd[1024];
  char *out = NULL;
  /* missing */
  snprintf(path, sizeof path, "%s/missing.off", dir);
  snprintf(cmd, sizeof cmd, "%s levelset %s %s/x.bsls", exe, path, dir);
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, path) != NULL, "%s", out);
  free(out);
  snprintf(path, sizeof path, "%s/missing.geo", dir);
  snprintf(cmd, sizeof cmd, "%s levelset %s %s/x.bsls", exe, path, dir);
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, path) != NULL, "%s", out);
  free(out);
  /* open: the cube without its top face */
  snprintf(path, sizeof path, "%s/open.off", dir);
  write_cube_off(path, 1);
  snprintf(cmd, sizeof cmd, "%s levelset %s %s/x.bsls", exe, path, dir);
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, path) != NULL, "%s", out);
  cr_expect(strstr(out, "not closed") != NULL, "%s", out);
  cr_expect(strstr(out, "4 edges") != NULL, "%s", out); /* the rim of the missing face */
  free(out);
  char xpath[160];
  snprintf(xpath, sizeof xpath, "%s/x.bsls", dir);
  cr_expect_neq(access(xpath, F_OK), 0, "no file is written on failure");
  /* unwritable output */
  snprintf(path, sizeof path, "%s/cube.off", dir);
  write_cube_off(path, 0);
  snprintf(cmd, sizeof cmd, "%s levelset %s %s/no/such/folder/x.bsls --h 0.5", exe, path, dir);
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, "no/such/folder/x.bsls") != NULL, "%s", out);
  free(out);
}

Test(levelset_cli, usage_errors_exit_2) {
  static const char *const args[] = {
      "",                                        /* no arguments */
      "data/geo/sphere.geo",                     /* no OUT */
      "data/geo/sphere.geo X.bsls --h -1",       /* h <= 0 */
      "data/geo/sphere.geo X.bsls --h abc",      /* not a number */
      "data/geo/sphere.geo X.bsls --h",          /* missing value */
      "data/geo/sphere.geo X.bsls --margin -0.1", /* negative margin */
      "data/geo/sphere.geo X.bsls --frobnicate", /* unknown flag */
      "data/geo/sphere.geo X.bsls extra",        /* a third argument */
  };
  static const char *const culprit[] = {"SURFACE and OUT", "SURFACE and OUT", "--h -1", "abc",
                                        "--h needs a value", "--margin -0.1", "--frobnicate", "extra"};
  for (size_t i = 0; i < sizeof args / sizeof args[0]; i++) {
    char cmd[1024];
    char *out = NULL;
    snprintf(cmd, sizeof cmd, "%s levelset %s", exe, args[i]);
    cr_expect_eq(bs_test_run(cmd, &out), 2, "'%s': %s", args[i], out);
    cr_expect(strstr(out, culprit[i]) != NULL, "'%s': %s", args[i], out);
    free(out);
  }
  char cmd[1024], *out = NULL;
  cr_expect_eq(bs_test_run(strcat(strcpy(cmd, exe), " levelset --help"), &out), 0);
  cr_expect(strstr(out, "usage: bigstep levelset SURFACE OUT") != NULL, "%s", out);
  free(out);
}
