/* A study's quantities of interest (bs__study_read_qoi, bs_study_qoi_gci)
 * without processes: run folders get hand-written qoi.csv files whose last
 * value follows f(dt) = f0 + C dt^p, so that the observed order, the
 * Richardson extrapolation and the errors against the reference are known;
 * a failed level is skipped, not fitted through; bad qoi.csv files are
 * refused naming the line. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bs_runfolder.h"
#include "bs_study.h"
#include "study_internal.h" /* the steps of the evaluation, private to study/ */

static const char *scene =
    "{\"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 1},\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 1, 1], \"size\": [1, 0.5, 0.5]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}]}\n";

static double f_of(double dt) { return 0.25 - 3.0 * pow(dt, 1.5); }

/* A study of steps_per_frame=1,2,4,8 with the quantity "tip". */
static bs_study *make_study(char *dir, size_t n) {
  snprintf(dir, n, "/tmp/bs_study_qoi_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
  char p[512], out[512];
  snprintf(p, sizeof p, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/study", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(scene, f);
  fclose(f);
  bs_study_knob k;
  bs_error err;
  cr_assert_eq(bs_study_knob_parse("steps_per_frame=1,2,4,8", &k, &err), 0, "%s", err.msg);
  const char *qoi[1] = {"tip"};
  bs_study_opts o = {.scene = p, .n_knobs = 1, .knobs = &k, .out = out, .n_qoi = 1, .qoi = qoi};
  bs_study *S = NULL;
  cr_assert_eq(bs_study_create(&o, &S, &err), 0, "%s", err.msg);
  bs_study_knob_free(&k);
  cr_assert_eq(bs_study_plan(S, &err), 0, "%s", err.msg);
  return S;
}

/* Run r's qoi.csv: frames 0..2, the last one f(dt), the one before half of it. */
static void write_qoi(const bs_study_run *r) {
  bs_error err;
  cr_assert_eq(bs_mkdir_p(r->dir, &err), 0, "%s", err.msg);
  char p[1600];
  snprintf(p, sizeof p, "%s/qoi.csv", r->dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  double dt = 1.0 / (24.0 * r->spf), v = f_of(dt);
  fprintf(f, "frame,time,other,tip\n0,0,1,0\n1,%.17g,1,%.17g\n2,%.17g,1,%.17g\n", 1 / 24.0, 0.5 * v, 2 / 24.0, v);
  fclose(f);
}

Test(study_qoi, errors_order_and_extrapolation_of_a_known_sequence) {
  char dir[256];
  bs_study *S = make_study(dir, sizeof dir);
  cr_assert_eq(S->n_runs, 4);
  cr_assert_eq(S->ref, 3, "the reference is steps_per_frame=8");
  for (int i = 0; i < 4; i++) write_qoi(&S->runs[i]);
  cr_expect_eq(bs__study_read_qoi(S), 0);
  const double ref = f_of(1.0 / 192), Q = fabs(ref);
  for (int i = 0; i < 4; i++) {
    const bs_study_run *r = &S->runs[i];
    double v = f_of(1.0 / (24.0 * r->spf));
    cr_expect_eq(r->q_last[0], v, "run %d: the last value", i);
    cr_expect(fabs(r->q_err_last[0] - fabs(v - ref) / Q) < 1e-15, "run %d: error %g", i, r->q_err_last[0]);
    cr_expect(fabs(r->q_err_max[0] - fabs(v - ref) / Q) < 1e-15, "run %d: the max is at the last frame", i);
  }
  cr_expect_eq(S->runs[3].q_err_last[0], 0.0);
  bs_gci g;
  int used[3], skipped;
  cr_assert_eq(bs_study_qoi_gci(S, 0, "optimization", 0, &g, used, &skipped), BS_GCI_OK);
  cr_expect(used[0] == 3 && used[1] == 2 && used[2] == 1, "the three finest, fine to coarse: %d %d %d", used[0],
            used[1], used[2]);
  cr_expect(fabs(g.p - 1.5) < 1e-9, "order %.12g", g.p);
  cr_expect(fabs(g.extrapolated - 0.25) < 1e-12, "extrapolated %.15g", g.extrapolated);
  /* the finest level fails: the GCI comes from the three levels left, none skipped silently */
  S->runs[3].exit_code = 1;
  cr_assert_eq(bs_study_qoi_gci(S, 0, "optimization", 0, &g, used, &skipped), BS_GCI_OK);
  cr_expect_eq(skipped, 1);
  cr_expect(used[0] == 2 && used[2] == 0);
  cr_expect(fabs(g.extrapolated - 0.25) < 1e-12);
  bs_study_destroy(&S);
}

static void expect_refused(const char *text, const char *what) {
  char dir[] = "/tmp/bs_qoi_csv_XXXXXX", p[64];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(p, sizeof p, "%s/qoi.csv", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(text, f);
  fclose(f);
  bs_qoi_table t;
  bs_error err;
  bs_error_clear(&err);
  cr_expect_eq(bs_qoi_csv_read(dir, &t, &err), BS_EINPUT, "%s was read", what);
  cr_expect_not_null(strstr(err.msg, p), "%s: the message does not name the file: %s", what, err.msg);
  cr_expect_eq(t.n_rows, 0);
}

Test(study_qoi, bad_qoi_csv_refused) {
  expect_refused("", "an empty file");
  expect_refused("frame,t,a\n0,0,1\n", "a wrong header");
  expect_refused("frame,time,a\n0,0\n", "a short row");
  expect_refused("frame,time,a\n0,0,1,2\n", "a long row");
  expect_refused("frame,time,a\n0,0,nan\n", "a NaN");
  expect_refused("frame,time,a\n0,0,x\n", "a word");
  expect_refused("frame,time,a,,b\n", "an empty name");
}
