/* bigstep study: the cross product of varied settings is run (resumably),
 * compared with the reference and summarised; bad flags are usage errors;
 * backward Euler shows first order in time on the dynamic beam. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli_util.h"

static const char *box_scene =
    "{\"time\": {\"fps\": 24, \"frames\": 3, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-3},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 1, 1], \"size\": [1, 0.5, 0.5]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}]}\n";

/* Creates a fresh folder (its path into dir) holding scene.json. */
static void make_dir(char *dir, size_t n, const char *scene) {
  snprintf(dir, n, "/tmp/bs_study_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
  char p[512];
  snprintf(p, sizeof p, "%s/scene.json", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(scene, f);
  fclose(f);
}

static int study(const char *dir, const char *args, char **out) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "%s study %s/scene.json --out %s/study %s", BS_BIGSTEP_EXE, dir, dir, args);
  return bs_test_run(cmd, out);
}

/* study.csv split at every comma. The first field (the run name) holds
 * commas itself, so fields are found counting from the right end. */
typedef struct table {
  int rows;
  int n[64];
  char cell[64][48][64];
} table;

static int read_table(const char *path, table *t) {
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  char line[8192];
  t->rows = 0;
  while (t->rows < 64 && fgets(line, sizeof line, f)) {
    line[strcspn(line, "\n")] = 0;
    int c = 0;
    for (char *tok = strtok(line, ","); tok && c < 48; tok = strtok(NULL, ",")) snprintf(t->cell[t->rows][c++], 64, "%s", tok);
    t->n[t->rows++] = c;
  }
  fclose(f);
  return t->rows;
}

static const char *field(const table *t, int row, const char *name) {
  int idx = -1;
  for (int c = 0; c < t->n[0]; c++)
    if (!strcmp(t->cell[0][c], name)) idx = c;
  cr_assert(idx >= 0, "study.csv has no column '%s'", name);
  return t->cell[row][t->n[row] - (t->n[0] - idx)];
}

static int png_ok(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  unsigned char m[8] = {0};
  size_t n = fread(m, 1, 8, f);
  fclose(f);
  static const unsigned char magic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return n == 8 && memcmp(m, magic, 8) == 0;
}

Test(study, two_by_two_resumable_with_plots) {
  char dir[256], *out = NULL, p[512];
  make_dir(dir, sizeof dir, box_scene);
  int rc = study(dir, "--vary steps_per_frame=1,2 --vary tolerance=1e-2,1e-4", &out);
  cr_assert_eq(rc, 0, "study exited %d:\n%s", rc, out);
  cr_expect(strstr(out, "4 runs, 4 to do") != NULL, "%s", out);
  cr_expect(strstr(out, "verdict: judged on the position error") != NULL, "the verdict names its quantity:\n%s", out);
  cr_expect(strstr(out, "within 1%") && strstr(out, "within 0.1%") && strstr(out, "within 0.01%"), "%s", out);
  free(out);

  static table t;
  memset(&t, 0, sizeof t);
  snprintf(p, sizeof p, "%s/study/study.csv", dir);
  cr_assert_eq(read_table(p, &t), 5, "study.csv: header and 4 rows");
  int n_ref = 0;
  for (int r = 1; r < 5; r++) {
    cr_expect_str_eq(field(&t, r, "exit"), "0");
    double e = atof(field(&t, r, "pos_err_max")), ev = atof(field(&t, r, "vel_err_max"));
    if (!strcmp(field(&t, r, "reference"), "1")) {
      n_ref++;
      cr_expect_str_eq(field(&t, r, "steps_per_frame"), "2", "the reference is the finest setting");
      cr_expect_str_eq(field(&t, r, "tolerance"), "1e-4");
      cr_expect_eq(e, 0.0, "the reference has zero position error, got %g", e);
      cr_expect_eq(ev, 0.0, "the reference has zero velocity error, got %g", ev);
    } else if (!strcmp(field(&t, r, "steps_per_frame"), "1")) {
      cr_expect(e > 0 && e < 0.5, "a coarser time step has a small positive error, got %g", e);
    }
    cr_expect(atof(field(&t, r, "newton_per_step")) >= 1, "Newton iterations per step");
    cr_expect(atof(field(&t, r, "s_per_frame")) > 0, "seconds per frame");
  }
  cr_expect_eq(n_ref, 1, "exactly one reference row");
  snprintf(p, sizeof p, "%s/study/error_vs_cost.png", dir);
  cr_expect(png_ok(p), "%s is not a PNG", p);
  snprintf(p, sizeof p, "%s/study/iterations_vs_steps.png", dir);
  cr_expect(png_ok(p), "%s is not a PNG", p);

  /* a second invocation redoes nothing: the done markers are untouched */
  struct stat before, after;
  snprintf(p, sizeof p, "%s/study/steps_per_frame=1,tolerance=1e-2/done", dir);
  cr_assert_eq(stat(p, &before), 0, "no done marker %s", p);
  rc = study(dir, "--vary steps_per_frame=1,2 --vary tolerance=1e-2,1e-4", &out);
  cr_assert_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "4 runs, 0 to do") != NULL, "a second invocation should run nothing:\n%s", out);
  free(out);
  cr_assert_eq(stat(p, &after), 0);
  cr_expect(before.st_mtim.tv_sec == after.st_mtim.tv_sec && before.st_mtim.tv_nsec == after.st_mtim.tv_nsec,
            "the done marker was rewritten");

  /* a run with different settings (another --set) is redone */
  rc = study(dir, "--vary steps_per_frame=1,2 --vary tolerance=1e-2,1e-4 --set time.frames=2", &out);
  cr_assert_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "4 runs, 4 to do") != NULL, "changed settings should be rerun:\n%s", out);
  free(out);
}

Test(study, summary_names_each_method_and_failed_runs_are_recorded) {
  char dir[256], *out = NULL, p[512];
  make_dir(dir, sizeof dir, box_scene);
  int rc = study(dir, "--vary method=newton,optimization --vary solver.max_iterations=1,500 --set time.frames=2 "
                      "--set solver.tolerance=1e-9 --jobs 2", &out);
  cr_assert_eq(rc, 0, "a failed run must not stop the study (exit %d):\n%s", rc, out);
  /* one ranking across the method knob: both methods' runs in it, one verdict */
  cr_expect(strstr(out, "method=optimization,solver.max_iterations=500") != NULL, "%s", out);
  cr_expect(strstr(out, "method=newton,solver.max_iterations=500") != NULL, "%s", out);
  const char *v = strstr(out, "verdict: ");
  cr_expect(v && !strstr(v + 1, "verdict: "), "one verdict:\n%s", out);
  free(out);
  static table t;
  memset(&t, 0, sizeof t);
  snprintf(p, sizeof p, "%s/study/study.csv", dir);
  cr_assert_eq(read_table(p, &t), 5);
  int failed = 0;
  for (int r = 1; r < 5; r++) {
    if (!strcmp(field(&t, r, "solver.max_iterations"), "1")) {
      cr_expect_str_eq(field(&t, r, "failed"), "1", "one iteration cannot reach tolerance 1e-9");
      cr_expect(atoi(field(&t, r, "failed_steps")) > 0);
    }
    failed += atoi(field(&t, r, "failed"));
    if (!strcmp(field(&t, r, "reference"), "1")) cr_expect_str_eq(field(&t, r, "method"), "optimization");
  }
  cr_expect_eq(failed, 2);
}

Test(study, refinement_compares_through_coarse_vertices) {
  char dir[256], *out = NULL, p[512];
  make_dir(dir, sizeof dir, box_scene);
  int rc = study(dir, "--vary refine=0,1,2 --set solver.mode=static --set solver.tolerance=1e-8", &out);
  cr_assert_eq(rc, 0, "%s", out);
  cr_expect(strstr(out, "order in space (error ~ h^p, vs refine): method optimization p = ") != NULL, "%s", out);
  /* the order from successive levels (refine 0 against 1, 1 against 2) */
  const char *succ = strstr(out, "from successive levels (each run against the next finer): p = ");
  cr_expect(succ != NULL, "%s", out);
  if (succ) {
    double ps = atof(strstr(succ, "p = ") + 4);
    /* positive: the differences shrink (the 2 x 1 x 1 box is far from asymptotic: 0.29) */
    cr_expect(ps > 0 && ps < 3, "order from successive levels %g", ps);
  }
  free(out);
  static table t;
  memset(&t, 0, sizeof t);
  snprintf(p, sizeof p, "%s/study/study.csv", dir);
  cr_assert_eq(read_table(p, &t), 4);
  double e[3];
  for (int r = 1; r < 4; r++) e[atoi(field(&t, r, "refine"))] = atof(field(&t, r, "pos_err_max"));
  cr_expect(isfinite(e[0]) && isfinite(e[1]) && e[0] > e[1] && e[1] > 0 && e[2] == 0,
            "errors must fall under refinement towards the finest run: %g %g %g", e[0], e[1], e[2]);
  snprintf(p, sizeof p, "%s/study/error_vs_refine.png", dir);
  cr_expect(png_ok(p), "%s is not a PNG", p);

  /* renumbered meshes cannot be compared across refinement levels */
  rc = study(dir, "--vary refine=0,1 --set bodies.0.reorder=rcm", &out);
  cr_expect_eq(rc, 2, "%s", out);
  cr_expect(strstr(out, "bodies.0.reorder") != NULL, "%s", out);
  free(out);
}

Test(study, bad_flags_are_usage_errors) {
  char dir[256], *out = NULL;
  make_dir(dir, sizeof dir, box_scene);
  static const struct {
    const char *args, *needle;
  } cases[] = {
      {"--vary steps_per_frame", "--vary 'steps_per_frame'"},
      {"--vary steps_per_frame=1,,2", "--vary 'steps_per_frame=1,,2'"},
      {"--vary =1,2", "--vary '=1,2'"},
      {"--vary steps_per_frame=one,two", "'one' is not a number"},
      {"--vary steps_per_frame=1,1", "listed twice"},
      {"--vary steps_per_frame=1 --vary time.steps_per_frame=2", "varied twice"},
      {"--vary bodies.0.material.youngs=-1,1e5", "bodies.0.material.youngs"},
      {"--vary solver.methd=newton", "solver.methd"},
      {"--vary steps_per_frame=1,2 --jobs 0", "--jobs"},
      {"--vary steps_per_frame=1,2 --frobnicate 3", "--frobnicate"},
      {"", "nothing to vary"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    int rc = study(dir, cases[i].args, &out);
    cr_expect_eq(rc, 2, "'%s' exited %d:\n%s", cases[i].args, rc, out);
    cr_expect(strstr(out, cases[i].needle) != NULL, "'%s': the message should name '%s':\n%s", cases[i].args,
              cases[i].needle, out);
    cr_expect(strstr(out, "runs done") == NULL, "'%s': runs started:\n%s", cases[i].args, out);
    free(out);
  }
}

/* Backward Euler is first order in dt. The shipped beam (first mode about
 * 5 Hz) is run at 240 fps so that even one step per frame resolves the
 * oscillation (omega dt ~ 0.14); at 24 fps the numerical damping saturates the
 * error and the observed order is far below 1 (pre-asymptotic). */
Test(study, backward_euler_is_first_order_in_time) {
  char dir[256], *out = NULL;
  make_dir(dir, sizeof dir, "{}");
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           "%s study %s/data/scenes/beam_sag.json --out %s/study --set solver.mode=dynamic --set time.fps=240 "
           "--set time.frames=4 --vary steps_per_frame=1,2,4,8,32",
           BS_BIGSTEP_EXE, BS_SOURCE_DIR, dir);
  int rc = bs_test_run(cmd, &out);
  cr_assert_eq(rc, 0, "%s", out);
  const char *s = strstr(out, "order in time (error ~ dt^p, vs steps_per_frame): method optimization p = ");
  cr_assert_not_null(s, "%s", out);
  double p = atof(strstr(s, "p = ") + 4);
  cr_expect(p > 0.8 && p < 1.2, "observed order in time %g, expected 1 (0.8..1.2):\n%s", p, out);
  free(out);
}

/* Replaces the first occurrence of `from` in dir/scene.json by `to`. */
static void edit_scene(const char *dir, const char *from, const char *to) {
  char p[512], text[4096];
  snprintf(p, sizeof p, "%s/scene.json", dir);
  FILE *f = fopen(p, "r");
  cr_assert_not_null(f);
  size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = 0;
  char *at = strstr(text, from);
  cr_assert_not_null(at, "'%s' not in the scene", from);
  char out[4096];
  snprintf(out, sizeof out, "%.*s%s%s", (int)(at - text), text, to, at + strlen(from));
  cr_assert_not_null(f = fopen(p, "w"));
  fputs(out, f);
  fclose(f);
}

Test(study, cache_is_keyed_by_the_scene_content) {
  char dir[256], *out = NULL;
  make_dir(dir, sizeof dir, box_scene);
  cr_assert_eq(study(dir, "--vary steps_per_frame=1,2", &out), 0, "%s", out);
  cr_expect_not_null(strstr(out, "2 runs, 2 to do"), "%s", out);
  free(out);
  cr_assert_eq(study(dir, "--vary steps_per_frame=1,2", &out), 0, "%s", out);
  cr_expect_not_null(strstr(out, "2 runs, 0 to do"), "an unchanged study ran again:\n%s", out);
  free(out);
  edit_scene(dir, "\"youngs\": 1e5", "\"youngs\": 2e5"); /* the same --set list, another scene */
  cr_assert_eq(study(dir, "--vary steps_per_frame=1,2", &out), 0, "%s", out);
  cr_expect_not_null(strstr(out, "2 runs, 2 to do"), "the edited scene's runs were reused:\n%s", out);
  free(out);
  cr_assert_eq(study(dir, "--vary steps_per_frame=1,2 --force", &out), 0, "%s", out);
  cr_expect_not_null(strstr(out, "2 runs, 2 to do"), "--force did not rerun:\n%s", out);
  free(out);
}

Test(study, a_run_past_its_budget_is_stopped_and_listed) {
  char dir[256], *out = NULL, p[512];
  make_dir(dir, sizeof dir, box_scene);
  /* 3 frames of 100000 steps each on a 2-cell box: far more than 3 s */
  int rc = study(dir, "--vary steps_per_frame=1,100000 --run-budget 3 --reference auto", &out);
  cr_expect_eq(rc, 0, "%s", out);
  cr_expect_not_null(strstr(out, "(0 failed, 1 timed out)"), "%s", out);
  cr_expect_not_null(strstr(out, "  timeout steps_per_frame=100000"), "%s", out);
  free(out);
  static table t;
  memset(&t, 0, sizeof t);
  snprintf(p, sizeof p, "%s/study/study.csv", dir);
  cr_assert_eq(read_table(p, &t), 3, "study.csv: header and 2 rows");
  int n_timeout = 0;
  for (int r = 1; r < 3; r++) n_timeout += !strcmp(field(&t, r, "status"), "timeout");
  cr_expect_eq(n_timeout, 1);
}
