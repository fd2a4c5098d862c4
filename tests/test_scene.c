/* Scenes through the library (bs_scene_load, bs_sim_create): every bad input
 * is refused before any simulation exists, with a message naming the file and
 * the key (the message `bigstep run` prints); overrides reach any key and are
 * validated like the file; a good run writes its outputs and its summary.
 * The command line's own flags: test_cli_run.c. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene_fixture.h"
#include "sim_util.h"


/* Writes text to a fresh scene file and loads it with the overrides, then
 * creates the simulation: the status, the message in *err. */
static int load_scene(const char *text, int n_sets, const char *const *sets, bs_error *err) {
  char path[] = "/tmp/bs_scene_XXXXXX";
  bs_test_write_scene(path, text);
  int rc = sim_load_error(path, sets, n_sets, err);
  unlink(path);
  return rc;
}

/* Replaces the first occurrence of `from` in the good scene by `to`. */
static char *edit(const char *from, const char *to) {
  const char *p = strstr(bs_test_good_scene, from);
  cr_assert_not_null(p, "fixture does not hold '%s'", from);
  size_t n = strlen(bs_test_good_scene) - strlen(from) + strlen(to) + 1;
  char *s = malloc(n);
  snprintf(s, n, "%.*s%s%s", (int)(p - bs_test_good_scene), bs_test_good_scene, to, p + strlen(from));
  return s;
}

/* The scene with `from` replaced by `to` is refused (BS_EINPUT, or BS_EIO for
 * a missing file) with a message holding `needle`. */
static void expect_error(const char *from, const char *to, const char *needle) {
  char *scene = edit(from, to);
  bs_error err;
  int rc = load_scene(scene, 0, NULL, &err);
  cr_expect(rc == BS_EINPUT || rc == BS_EIO, "scene with '%s' -> '%s': status %d: %s", from, to, rc, err.msg);
  cr_expect(strstr(err.msg, needle) != NULL, "message for '%s' should name '%s': %s", to, needle, err.msg);
  free(scene);
}

/* The good scene with one override is refused with a message holding needle. */
static void expect_set_error(const char *set, const char *needle) {
  bs_error err;
  int rc = load_scene(bs_test_good_scene, 1, &set, &err);
  cr_expect_eq(rc, BS_EINPUT, "set %s: status %d: %s", set, rc, err.msg);
  cr_expect(strstr(err.msg, needle) != NULL, "set %s: message should hold '%s': %s", set, needle, err.msg);
}

/* The good scene through the library, into a run folder: two converged steps,
 * stats.csv with a row each, frames.pvd and the last frame's VTU. */
Test(scene, good_scene_runs) {
  char path[] = "/tmp/bs_scene_XXXXXX";
  bs_test_write_scene(path, bs_test_good_scene);
  cr_assert_eq(system("rm -rf /tmp/bs_scene_out"), 0);
  sim_rec rec;
  bs_run_totals T;
  sim_run_scene(path, "output.dir=/tmp/bs_scene_out", "/tmp/bs_scene_out", &rec, &T, 0, NULL);
  unlink(path);
  cr_expect_eq(T.steps, 2);
  cr_expect_eq(T.failed, 0, "%s", T.first_fail_reason);
  cr_expect_eq(rec.failed, 0, "%s", rec.reason);
  FILE *f = fopen("/tmp/bs_scene_out/stats.csv", "r");
  cr_assert_not_null(f, "stats.csv missing");
  char line[4096];
  int lines = 0;
  while (fgets(line, sizeof line, f)) lines++;
  fclose(f);
  cr_expect_eq(lines, 3, "stats.csv: header and 2 steps, got %d lines", lines);
  cr_expect_eq(access("/tmp/bs_scene_out/frames.pvd", R_OK), 0);
  cr_expect_eq(access("/tmp/bs_scene_out/frame_00002.vtu", R_OK), 0);
  bs_summary u;
  bs_error err;
  cr_assert_eq(bs_summary_read("/tmp/bs_scene_out", &u, &err), 0, "%s", err.msg);
  cr_expect_str_eq(u.method, "optimization");
  cr_expect_eq(u.failed, 0);
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
               "solver.cg_sigma: must be a number > 0 or \"auto\", got string \"half\"");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma\": 0", "solver.cg_sigma: must be > 0");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_precision\": \"half\"",
               "solver.cg_precision: must be \"double\" or \"single\", got \"half\"");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma_scale\": -1",
               "solver.cg_sigma_scale: must be > 0, got -1");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_sigma\": 1, \"cg_sigma_scale\": 0.1",
               "solver.cg_sigma_scale: applies to cg_sigma \"auto\" only");
  expect_error("\"tolerance\": 1e-3", "\"tolerance\": 1e-3, \"cg_forcing\": \"ew\"",
               "solver.cg_forcing: must be \"paper\", \"eisenstat_walker\" or \"adaptive\", got \"ew\"");
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
  bs_error err;
  int rc = load_scene("{\"time\": {\"fps\": 24,,}", 0, NULL, &err);
  cr_expect_eq(rc, BS_EINPUT, "%d: %s", rc, err.msg);
  cr_expect(strstr(err.msg, "line 1, column 21: malformed JSON") != NULL, "%s", err.msg);
  rc = sim_load_error("/no/such/scene.json", NULL, 0, &err);
  cr_expect_eq(rc, BS_EIO, "%d: %s", rc, err.msg);
  cr_expect(strstr(err.msg, "/no/such/scene.json") != NULL, "%s", err.msg);
}

Test(scene, set_overrides_are_validated) {
  expect_set_error("bodies.0.material.youngs=-5", "youngs");
  expect_set_error("bodies.3.material.youngs=1e6", "'3' is not an index");
  expect_set_error("solver.colour=blue", "solver.colour: unknown key");
  expect_set_error("bodies.0.velocity=[0,nan,0]", "bodies.0.velocity");
  /* a valid override takes effect: 2 steps per frame, 4 steps in the 2 frames */
  char path[] = "/tmp/bs_scene_XXXXXX";
  bs_test_write_scene(path, bs_test_good_scene);
  sim_rec rec;
  bs_run_totals T;
  bs_scene *sc = NULL;
  bs_sim *s = sim_run_scene(path, "time.steps_per_frame=2", NULL, &rec, &T, 1, &sc);
  unlink(path);
  cr_expect_eq(sc->steps_per_frame, 2);
  cr_expect_float_eq(sc->dt, 1.0 / 48, 1e-15);
  cr_expect_eq(T.steps, 4, "%ld steps", T.steps);
  cr_expect_eq(T.failed, 0, "%s", T.first_fail_reason);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}
