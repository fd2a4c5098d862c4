/* `bigstep run` itself (the simulation is tested through the library in
 * test_sim.c, test_scene.c and the scene tests): what it prints, what it
 * writes into --out, and its exit statuses (0 success, 1 a failed step or a
 * bad scene, 2 a usage error). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_runfolder.h"
#include "cli_util.h"
#include "scene_fixture.h"


/* Writes the good scene to a fresh file and runs `bigstep run FILE ARGS`. */
static int run_good(const char *args, char **out) {
  char path[] = "/tmp/bs_cli_run_XXXXXX";
  bs_test_write_scene(path, bs_test_good_scene);
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "%s run %s %s", BS_BIGSTEP_EXE, path, args);
  int rc = bs_test_run(cmd, out);
  unlink(path);
  return rc;
}

Test(cli_run, prints_frames_and_summary_and_writes_the_folder) {
  const char *dir = "/tmp/bs_cli_run_out";
  cr_assert_eq(system("rm -rf /tmp/bs_cli_run_out"), 0);
  char *out = NULL;
  int rc = run_good("--out /tmp/bs_cli_run_out --set output.stats=true --set output.states=true "
                    "--set output.vtu_every=1",
                    &out);
  cr_assert_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "bigstep run ") == out, "no header line first:\n%s", out);
  cr_expect_not_null(strstr(out, ": 27 vertices, 48 tets, "), "%s", out);
  cr_expect_not_null(strstr(out, "method optimization"), "%s", out);
  cr_expect_not_null(strstr(out, "\nframe 1/2  newton "), "%s", out);
  cr_expect_not_null(strstr(out, "\nframe 2/2  newton "), "%s", out);
  cr_expect_null(strstr(out, "FAILED"), "%s", out);
  double solves = 0;
  long failed = -1;
  cr_assert_eq(bs_test_summary_row(out, &solves, &failed), 0, "no summary row:\n%s", out);
  cr_expect_eq(failed, 0, "%s", out);
  cr_expect_gt(solves, 0.0, "%s", out);
  cr_expect_not_null(strstr(out, "\nat the last frame: 0 inverted tets"), "%s", out);
  /* the files, read back by the library */
  static const char *const files[] = {"frames.csv", "stats.csv", "state.bin", "frames.pvd", "summary.txt",
                                      "frame_00000.vtu", "frame_00002.vtu"};
  char p[512];
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
    snprintf(p, sizeof p, "%s/%s", dir, files[i]);
    cr_expect_eq(access(p, R_OK), 0, "%s missing", p);
  }
  bs_error err;
  bs_frames_table t;
  cr_assert_eq(bs_frames_csv_read(dir, &t, &err), 0, "%s", err.msg);
  cr_expect_eq(t.n, 3, "frames.csv: %d rows", t.n);
  cr_expect_eq(t.failed, 0);
  bs_frames_table_free(&t);
  bs_state_reader st;
  cr_assert_eq(bs_state_open(dir, &st, &err), 0, "%s", err.msg);
  cr_expect_eq(st.frames, 3);
  cr_expect_eq(st.n, 27);
  bs_state_close(&st);
  bs_summary u;
  cr_assert_eq(bs_summary_read(dir, &u, &err), 0, "%s", err.msg);
  cr_expect_eq(u.failed, 0);
  cr_expect_float_eq(u.solves_per_step, solves, 0.006, "summary.txt %g, printed %g", u.solves_per_step, solves);
  snprintf(p, sizeof p, "%s/stats.csv", dir);
  FILE *f = fopen(p, "r");
  cr_assert_not_null(f);
  char line[4096];
  int lines = 0;
  while (fgets(line, sizeof line, f)) lines++;
  fclose(f);
  cr_expect_eq(lines, 3, "stats.csv: header and 2 steps, got %d lines", lines);
  free(out);
}

/* One iteration for a tolerance no step reaches: every step fails. */
Test(cli_run, failed_steps_exit_1) {
  char *out = NULL;
  int rc = run_good("--quiet --set output.dir= --set solver.tolerance=1e-14 --set solver.max_iterations=1", &out);
  cr_expect_eq(rc, 1, "%s", out);
  cr_expect_not_null(strstr(out, "bigstep run: 2 of 2 steps did not converge; the first (frame 1, step 0): max_iter"),
                     "%s", out);
  double solves;
  long failed = -1;
  cr_assert_eq(bs_test_summary_row(out, &solves, &failed), 0, "no summary row:\n%s", out);
  cr_expect_eq(failed, 2, "%s", out);
  free(out);
}

Test(cli_run, bad_scene_exit_1) {
  char *out = NULL;
  int rc = run_good("--quiet --set bodies.0.material.density=-1", &out);
  cr_expect_eq(rc, 1, "%s", out);
  cr_expect_not_null(strstr(out, "bigstep run: "), "%s", out);
  cr_expect_not_null(strstr(out, "bodies.0.material: density = -1: must be finite and > 0 (kg/m^3)"), "%s", out);
  cr_expect_null(strstr(out, "frame 1"), "%s", out);
  free(out);
  rc = bs_test_run(BS_BIGSTEP_EXE " run /no/such/scene.json", &out);
  cr_expect_eq(rc, 1, "%s", out);
  cr_expect_not_null(strstr(out, "/no/such/scene.json"), "%s", out);
  free(out);
}

Test(cli_run, usage_errors_exit_2_and_help_0) {
  char *out = NULL;
  int rc = run_good("--frobnicate 1", &out);
  cr_expect_eq(rc, 2, "%s", out);
  cr_expect_not_null(strstr(out, "unknown flag '--frobnicate'"), "%s", out);
  free(out);
  rc = run_good("--steps-per-frame zero", &out);
  cr_expect_eq(rc, 2, "%s", out);
  cr_expect_not_null(strstr(out, "--steps-per-frame must be a positive integer"), "%s", out);
  free(out);
  rc = bs_test_run(BS_BIGSTEP_EXE " run", &out);
  cr_expect_eq(rc, 2, "%s", out);
  cr_expect_not_null(strstr(out, "missing SCENE"), "%s", out);
  free(out);
  rc = bs_test_run(BS_BIGSTEP_EXE " run --help", &out);
  cr_expect_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "usage: bigstep run SCENE") == out, "%s", out);
  free(out);
}

Test(cli_run, refuses_an_earlier_run_unless_replace_and_records_the_command) {
  cr_assert_eq(system("rm -rf /tmp/bs_cli_run_again"), 0);
  char *out = NULL;
  cr_assert_eq(run_good("--out /tmp/bs_cli_run_again --quiet", &out), 0, "%s", out);
  free(out);
  cr_expect_eq(run_good("--out /tmp/bs_cli_run_again --quiet", &out), 1, "%s", out);
  cr_expect_not_null(strstr(out, "bigstep run: output folder '/tmp/bs_cli_run_again' holds an earlier run"), "%s", out);
  cr_expect_not_null(strstr(out, "--replace"), "%s", out);
  free(out);
  cr_expect_eq(run_good("--out /tmp/bs_cli_run_again --quiet --replace --set 'time.frames=1'", &out), 0, "%s", out);
  free(out);
  FILE *f = fopen("/tmp/bs_cli_run_again/run.txt", "r");
  cr_assert_not_null(f);
  char text[2048] = "";
  size_t n = fread(text, 1, sizeof text - 1, f);
  text[n] = 0;
  fclose(f);
  cr_expect_not_null(strstr(text, "\ncommand: bigstep run /tmp/bs_cli_run_"), "%s", text);
  cr_expect_not_null(strstr(text, " --replace --set time.frames=1\n"), "%s", text);
  cr_expect_eq(access("/tmp/bs_cli_run_again/frame_00002.vtu", F_OK), -1, "a stale frame is left");
  cr_expect_eq(system("rm -rf /tmp/bs_cli_run_again"), 0);
}

Test(cli_run, frame_lines_show_progress_when_not_a_terminal) {
  char *out = NULL;
  cr_assert_eq(run_good("--out ''", &out), 0, "%s", out);
  cr_expect_not_null(strstr(out, "  [1/2, "), "%s", out);
  cr_expect_not_null(strstr(out, " s/frame, ETA "), "%s", out);
  cr_expect_null(strstr(out, "\r"), "a terminal's carriage return in a pipe:\n%s", out);
  free(out);
}
