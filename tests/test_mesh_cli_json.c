/* bigstep mesh info --json and --time-budget (issue 44): the report as one
 * JSON object (quality, gate, size chosen, alpha wrap, tetrahedral
 * remeshing, volume change and Hausdorff distance to the input surface, what
 * closing holes did), and the budget's named error. */
#define _GNU_SOURCE

#include <criterion/criterion.h>
#include <cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli_util.h"

/* Two unit cubes sharing the edge x = y = 1 (a non-manifold edge: the repair
 * refuses it, the alpha wrap replaces it), written as OFF to path. */
static void write_two_cubes(const char *path) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  fprintf(f, "OFF\n16 24 0\n");
  for (int b = 0; b < 2; b++)
    for (int i = 0; i < 8; i++) fprintf(f, "%d %d %d\n", b + (i & 1), b + ((i >> 1) & 1), (i >> 2) & 1);
  for (int b = 0; b < 2; b++)
    for (int k = 0; k < 6; k++)
      fprintf(f, "3 %d %d %d\n3 %d %d %d\n", 8 * b + q[k][0], 8 * b + q[k][1], 8 * b + q[k][2], 8 * b + q[k][0],
              8 * b + q[k][2], 8 * b + q[k][3]);
  fclose(f);
}

static double number(const cJSON *o, const char *a, const char *b) {
  const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, a);
  if (b) x = cJSON_GetObjectItemCaseSensitive(x, b);
  cr_assert(cJSON_IsNumber(x), "%s.%s is not a number", a, b ? b : "");
  return x->valuedouble;
}

/* `bigstep mesh info PATH ARGS --json`, which must succeed, parsed (its
 * output into *out). */
static cJSON *info_json(const char *path, const char *args, char **out) {
  char cmd[512];
  snprintf(cmd, sizeof cmd, "%s mesh info %s %s --json", BS_BIGSTEP_EXE, path, args);
  cr_assert_eq(bs_test_run(cmd, out), 0, "%s", *out);
  cJSON *j = cJSON_Parse(*out);
  cr_assert_not_null(j, "not JSON: %s", *out);
  return j;
}

Test(mesh_cli_json, info_json_of_a_wrapped_surface) {
  char path[96], *out = NULL;
  snprintf(path, sizeof path, "/tmp/bs_test_cli_json_%d.off", (int)getpid());
  write_two_cubes(path);
  cJSON *j = info_json(path, "--size 0.2", &out);
  cr_expect(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "gate_passed")), "%s", out);
  cr_expect(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "check")), "%s", out);
  cr_expect_geq(number(j, "quality", "dihedral_min"), 10.0);
  cr_expect_eq(number(j, "wrap", "how"), 1);
  const double dv = number(j, "surface", "volume_change"), d = number(j, "surface", "hausdorff");
  cr_log_info("two cubes --json: volume change %+.3f%%, Hausdorff %.4g, wrap %+.3f%%", 100 * dv, d,
              100 * number(j, "wrap", "volume_change"));
  cr_expect_leq(dv, 0.04);
  cr_expect_leq(d, 0.2, "Hausdorff %g over h", d);
  cJSON_Delete(j);
  free(out);
  unlink(path);
}

/* The unit cube without its face z = 0 (the two triangles of quad 0 left
 * out), written as OFF to path. */
static void write_open_cube(const char *path) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  static const int q[5][4] = {{4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  fprintf(f, "OFF\n8 10 0\n");
  for (int i = 0; i < 8; i++) fprintf(f, "%d %d %d\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
  for (int k = 0; k < 5; k++)
    fprintf(f, "3 %d %d %d\n3 %d %d %d\n", q[k][0], q[k][1], q[k][2], q[k][0], q[k][2], q[k][3]);
  fclose(f);
}

/* A planar hole closed on request: its fill is the missing face (area 1,
 * a sixth of the surface; nothing beyond the flat cap). */
Test(mesh_cli_json, holes_closed_reported) {
  char path[96], *out = NULL;
  snprintf(path, sizeof path, "/tmp/bs_test_cli_json_hole_%d.off", (int)getpid());
  write_open_cube(path);
  cJSON *j = info_json(path, "--size 0.2 --close-holes --max-hole 1", &out);
  const cJSON *holes = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(j, "surface"), "holes");
  cr_assert(cJSON_IsObject(holes), "%s", out);
  cr_expect_eq(number(holes, "found", NULL), 1);
  cr_expect_eq(number(holes, "closed", NULL), 1);
  cr_expect_eq(number(holes, "fair_estimated", NULL), 0, "two triangles: no inner vertex to fair");
  cr_expect(fabs(number(holes, "fair_volume", NULL)) < 1e-12, "%s", out);
  cr_expect(fabs(number(holes, "area", NULL) - 1) < 1e-12, "%s", out);
  cr_expect(fabs(number(holes, "area_fraction", NULL) - 1.0 / 6) < 1e-5, "%s", out);
  cr_expect(fabs(number(holes, "cap_volume", NULL)) < 1e-12, "%s", out);
  cr_expect(fabs(number(j, "surface", "volume_in") - 1) < 1e-12, "%s", out);
  cJSON_Delete(j);
  free(out);
  unlink(path);
}

Test(mesh_cli_json, time_budget_named) {
  char path[96], cmd[512], *out = NULL;
  snprintf(path, sizeof path, "/tmp/bs_test_cli_budget_%d.off", (int)getpid());
  write_two_cubes(path);
  snprintf(cmd, sizeof cmd, "%s mesh info %s --size 0.05 --time-budget 0.000001", BS_BIGSTEP_EXE, path);
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, "the meshing time budget of 1e-06 s") != NULL, "%s", out);
  free(out);
  snprintf(cmd, sizeof cmd, "%s mesh info %s --time-budget -3", BS_BIGSTEP_EXE, path);
  cr_expect_eq(bs_test_run(cmd, &out), 2, "%s", out);
  cr_expect(strstr(out, "--time-budget") != NULL, "%s", out);
  free(out);
  unlink(path);
}

/* The scan with no size: refused before by the gate on its own triangles
 * (3.17 degrees); now meshed at a size chosen from its bounding box. */
Test(mesh_cli_json, armadillo_without_a_size) {
  char path[1024], cmd[1400], *out = NULL;
  snprintf(path, sizeof path, "%s/data/meshes/armadillo.off", BS_SOURCE_DIR);
  if (access(path, R_OK)) cr_skip_test("%s missing (bash setup.sh build extracts it)", path);
  snprintf(cmd, sizeof cmd, "%s mesh info %s --json", BS_BIGSTEP_EXE, path);
  cr_assert_eq(bs_test_run(cmd, &out), 0, "%s", out);
  cJSON *j = cJSON_Parse(out);
  cr_assert_not_null(j, "not JSON: %s", out);
  const double h = number(j, "size_chosen", NULL), d = number(j, "surface", "hausdorff");
  cr_log_info("armadillo --json: size chosen %g, dihedral min %.2f, volume change %+.3f%%, Hausdorff %.4g = %.3f h", h,
              number(j, "quality", "dihedral_min"), 100 * number(j, "surface", "volume_change"), d, d / h);
  cr_expect(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(j, "gate_passed")), "%s", out);
  cr_expect_gt(h, 0);
  cJSON_Delete(j);
  free(out);
}
