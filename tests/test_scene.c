/* Scenes and `bigstep run`: every bad input is refused before any step runs,
 * with a message naming the file and the key; --set reaches any key and is
 * validated like the file; a good run writes its outputs and its summary. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli_util.h"

static const char *good =
    "{\"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-3},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"ymin\", \"fixed\": true}]}]}\n";

/* Writes text to a fresh scene file and runs `bigstep run` on it with extra args. */
static int run_scene(const char *text, const char *args, char **out) {
  char path[] = "/tmp/bs_scene_XXXXXX";
  int fd = mkstemp(path);
  cr_assert(fd >= 0);
  FILE *f = fdopen(fd, "w");
  fputs(text, f);
  fclose(f);
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "%s run %s --quiet %s", BS_BIGSTEP_EXE, path, args ? args : "");
  int rc = bs_test_run(cmd, out);
  unlink(path);
  return rc;
}

/* Replaces the first occurrence of `from` in good by `to`. */
static char *edit(const char *from, const char *to) {
  const char *p = strstr(good, from);
  cr_assert_not_null(p, "fixture does not hold '%s'", from);
  size_t n = strlen(good) - strlen(from) + strlen(to) + 1;
  char *s = malloc(n);
  snprintf(s, n, "%.*s%s%s", (int)(p - good), good, to, p + strlen(from));
  return s;
}

static void expect_error(const char *from, const char *to, const char *needle) {
  char *scene = edit(from, to), *out = NULL;
  int rc = run_scene(scene, NULL, &out);
  cr_expect_eq(rc, 1, "scene with '%s' -> '%s' exited %d:\n%s", from, to, rc, out);
  cr_expect(strstr(out, needle) != NULL, "message for '%s' should name '%s':\n%s", to, needle, out);
  cr_expect(strstr(out, "frame 1") == NULL, "a step ran before the error:\n%s", out);
  free(scene);
  free(out);
}

Test(scene, good_scene_runs) {
  char *out = NULL;
  int rc = run_scene(good, "--set output.dir=/tmp/bs_scene_out", &out);
  cr_expect_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "optimization") != NULL, "%s", out);
  cr_expect(strstr(out, "solves/step") != NULL, "%s", out);
  free(out);
  FILE *f = fopen("/tmp/bs_scene_out/stats.csv", "r");
  cr_assert_not_null(f, "stats.csv missing");
  char line[4096];
  int lines = 0;
  while (fgets(line, sizeof line, f)) lines++;
  fclose(f);
  cr_expect_eq(lines, 3, "stats.csv: header and 2 steps, got %d lines", lines);
  cr_expect_eq(access("/tmp/bs_scene_out/frames.pvd", R_OK), 0);
  cr_expect_eq(access("/tmp/bs_scene_out/frame_00002.vtu", R_OK), 0);
}

Test(scene, unknown_keys_and_types) {
  expect_error("\"gravity\"", "\"gravty\"", "gravty: unknown key");
  expect_error("\"youngs\": 1e5", "\"young\": 1e5", "bodies.0.material.young: unknown key");
  expect_error("\"fps\": 24", "\"fps\": \"24\"", "time.fps: must be a number");
  expect_error("\"gravity\": [0, -9.8, 0]", "\"gravity\": [0, -9.8]", "gravity: must be an array of 3 numbers");
  expect_error("\"method\": \"optimization\"", "\"method\": \"magic\"", "solver.method");
  expect_error("\"model\": \"fixed_corotated\"", "\"model\": \"rubber\"", "bodies.0.material.model");
}

Test(scene, impossible_values) {
  expect_error("\"density\": 1000", "\"density\": -1", "density");
  expect_error("\"fps\": 24", "\"fps\": 0", "time.fps: must be > 0");
  expect_error("\"poisson\": 0.3", "\"poisson\": 0.5", "poisson");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": -1", "solver.tolerance");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma\": \"half\"",
               "solver.cg_sigma: must be a number > 0 or \"auto\", got \"half\"");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma\": 0", "solver.cg_sigma: must be > 0");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_precision\": \"half\"",
               "solver.cg_precision: must be \"double\" or \"single\", got \"half\"");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma_scale\": -1",
               "solver.cg_sigma_scale: must be > 0, got -1");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma\": 1, \"cg_sigma_scale\": 0.1",
               "solver.cg_sigma_scale: applies to cg_sigma \"auto\" only");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_forcing\": \"ew\"",
               "solver.cg_forcing: must be \"paper\" or \"eisenstat_walker\", got \"ew\"");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_downhill\": 1", "solver.cg_downhill: must be true or false");
  expect_error("\"frames\": 2", "\"frames\": 2.5", "time.frames");
  expect_error("\"cells\": [2, 2, 2]", "\"cells\": [2, 0, 2]", "bodies.0.box");
}

Test(scene, missing_mesh_and_group) {
  expect_error("\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]}",
               "\"mesh\": \"no/such/mesh.msh\"", "bodies.0.mesh: cannot open mesh file 'no/such/mesh.msh'");
  expect_error("\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]}", "\"mesh\": \"box\"",
               "bodies.0.box: missing");
  expect_error("\"group\": \"ymin\"", "\"group\": \"nowhere\"", "bodies.0.scripted.0.group");
  expect_error("\"fixed\": true", "\"fixed\": true, \"velocity\": [1, 0, 0]", "bodies.0.scripted.0");
}

Test(scene, malformed_json_and_missing_file) {
  char *out = NULL;
  int rc = run_scene("{\"time\": {\"fps\": 24,,}", NULL, &out);
  cr_expect_eq(rc, 1);
  cr_expect(strstr(out, "malformed JSON") != NULL, "%s", out);
  free(out);
  rc = bs_test_run(BS_BIGSTEP_EXE " run /no/such/scene.json", &out);
  cr_expect_eq(rc, 1);
  cr_expect(strstr(out, "/no/such/scene.json") != NULL, "%s", out);
  free(out);
}

Test(scene, set_overrides_are_validated) {
  char *out = NULL;
  int rc = run_scene(good, "--set bodies.0.material.youngs=-5", &out);
  cr_expect_eq(rc, 1);
  cr_expect(strstr(out, "youngs") != NULL, "%s", out);
  free(out);
  rc = run_scene(good, "--set bodies.3.material.youngs=1e6", &out);
  cr_expect_eq(rc, 1);
  cr_expect(strstr(out, "'3' is not an index") != NULL, "%s", out);
  free(out);
  rc = run_scene(good, "--set solver.colour=blue", &out);
  cr_expect_eq(rc, 1);
  cr_expect(strstr(out, "solver.colour: unknown key") != NULL, "%s", out);
  free(out);
  rc = run_scene(good, "--set bodies.0.velocity=[0,nan,0]", &out);
  cr_expect_eq(rc, 1, "%s", out);
  cr_expect(strstr(out, "bodies.0.velocity") != NULL, "%s", out);
  free(out);
  /* a valid override takes effect: the summary reports 2 steps per frame */
  rc = run_scene(good, "--set time.steps_per_frame=2", &out);
  cr_expect_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "optimization       2") != NULL, "%s", out);
  free(out);
  rc = run_scene(good, "--steps-per-frame zero", &out);
  cr_expect_eq(rc, 2, "%s", out);
  free(out);
  rc = run_scene(good, "--frobnicate 1", &out);
  cr_expect_eq(rc, 2, "%s", out);
  cr_expect(strstr(out, "--frobnicate") != NULL, "%s", out);
  free(out);
}
