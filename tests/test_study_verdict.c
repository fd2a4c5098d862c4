/* The study's verdict through the library, without processes: run folders
 * get hand-written state.bin and qoi.csv files. The default position error
 * of a run that moved 1.5 cm on a 1 m body is relative to 1.5 cm; with
 * quantities of interest the verdict judges them against their Richardson
 * extrapolation and names them; the scene's own quantities are studied by
 * default; the summary holds no verdict (one verdict: S->verdict); a string
 * knob (solver.linear=cg,pcg) ranks like any other. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_runfolder.h"
#include "bs_study.h"
#include "study_internal.h" /* the steps of the evaluation, private to study/ */

/* A 1 m x 0.1 m x 0.1 m box of one cell (8 vertices), with a quantity. */
static const char *box_scene =
    "{\"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 1},\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1], \"size\": [1, 0.1, 0.1]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}],\n"
    " \"qoi\": [{\"name\": \"tip\", \"quantity\": \"displacement\", \"group\": \"xmax\", \"component\": \"y\"}]}\n";

/* A planned study of box_scene in a fresh folder; qoi NULL: the scene's own. */
static bs_study *make_study(const char *spec, int n_qoi, const char *const *qoi, int no_scene_qoi) {
  char dir[] = "/tmp/bs_verdict_XXXXXX", p[512], out[512];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(p, sizeof p, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/study", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(box_scene, f);
  fclose(f);
  bs_study_knob k;
  bs_error err;
  cr_assert_eq(bs_study_knob_parse(spec, &k, &err), 0, "%s", err.msg);
  bs_study_opts o = {.scene = p, .n_knobs = 1, .knobs = &k, .out = out, .n_qoi = n_qoi, .qoi = qoi,
                     .no_scene_qoi = no_scene_qoi};
  bs_study *S = NULL;
  cr_assert_eq(bs_study_create(&o, &S, &err), 0, "%s", err.msg);
  bs_study_knob_free(&k);
  cr_assert_eq(bs_study_plan(S, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_study_measure_bodies(S, &err), 0, "%s", err.msg);
  for (int i = 0; i < S->n_runs; i++) cr_assert_eq(bs_mkdir_p(S->runs[i].dir, &err), 0, "%s", err.msg);
  return S;
}

/* dir/state.bin (version 2) of n vertices: frame 0 at rest (all at the
 * origin), frame 1 every vertex moved by dy in y. */
static void write_state(const char *dir, int32_t n, double dy) {
  char p[1600];
  snprintf(p, sizeof p, "%s/state.bin", dir);
  FILE *f = fopen(p, "wb");
  cr_assert_not_null(f);
  uint32_t v = 2;
  int32_t hdr[2] = {n, 0};
  fwrite("BSST", 1, 4, f);
  fwrite(&v, 4, 1, f);
  fwrite(hdr, 4, 2, f);
  for (int k = 0; k < 2; k++) {
    double t = k / 24.0;
    fwrite(&t, sizeof t, 1, f);
    for (int32_t i = 0; i < 2 * n; i++) {
      double xyz[3] = {0, i < n ? k * dy : 0, 0};
      fwrite(xyz, sizeof(double), 3, f);
    }
  }
  fclose(f);
}

/* dir/qoi.csv with the column "tip": 0 at frame 0, value at the frames after. */
static void write_qoi(const char *dir, double value) {
  char p[1600];
  snprintf(p, sizeof p, "%s/qoi.csv", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fprintf(f, "frame,time,tip\n0,0,0\n1,%.17g,%.17g\n2,%.17g,%.17g\n", 1 / 24.0, 0.5 * value, 2 / 24.0, value);
  fclose(f);
}

Test(study_verdict, position_error_is_relative_to_what_moved) {
  bs_study *S = make_study("steps_per_frame=1,2", 0, NULL, 1);
  cr_assert_eq(S->n_qoi, 0, "--qoi none: no quantity");
  cr_assert_eq(S->n_runs, 2);
  cr_assert_eq(S->ref, 1);
  cr_expect(S->size > 1.0 && S->size < 1.02, "body size %g: the 1 m box's diagonal", S->size);
  /* the reference sagged 1.5 cm; the run 1.35 cm: 1.5 mm off, 10% of what moved */
  write_state(S->runs[1].dir, 8, -0.015);
  write_state(S->runs[0].dir, 8, -0.0135);
  cr_expect_eq(bs_study_evaluate(S), 0);
  cr_expect(fabs(S->disp - 0.015) < 1e-15, "what the reference moved: %.17g m", S->disp);
  cr_expect(fabs(S->runs[0].pos_max - 0.1) < 1e-12, "error %.17g: relative to 1.5 cm, not to the 1 m body (%.3g)",
            S->runs[0].pos_max, 0.0015 / S->size);
  cr_expect_eq(S->runs[1].pos_max, 0.0);
  /* the verdict judges the position error: 10% is not within 1% */
  S->runs[0].s_per_frame = 1;
  S->runs[1].s_per_frame = 2;
  bs_study_verdict_make(S, &S->verdict);
  const bs_study_verdict *v = &S->verdict;
  cr_expect_eq(v->on_qoi, 0);
  cr_expect_eq(v->ref_competes, 0, "against itself the reference's error is 0");
  cr_expect_eq(v->n_candidates, 1);
  cr_expect_eq(v->cheapest[0], -1, "nothing within 1%%");
  cr_expect_eq(v->most_accurate, 0);
  cr_expect_eq(S->runs[0].verdict_by, -1, "the position error set it");
  /* a reference that did not move: the body size is the scale */
  write_state(S->runs[1].dir, 8, 0);
  write_state(S->runs[0].dir, 8, 0.001);
  bs_study_evaluate(S);
  cr_expect(fabs(S->runs[0].pos_max - 0.001 / S->size) < 1e-15, "error %.17g", S->runs[0].pos_max);
  bs_study_destroy(&S);
}

static double f_of(double dt) { return 0.25 - 3.0 * pow(dt, 1.5); }

Test(study_verdict, quantities_are_judged_against_the_extrapolation_and_named) {
  bs_study *S = make_study("steps_per_frame=1,2,4,8", 0, NULL, 0);
  cr_assert_eq(S->n_qoi, 1, "the scene's own quantity is studied by default");
  cr_assert_str_eq(S->qoi[0], "tip");
  cr_expect_eq(S->q_kind[0], BS_QOI_DISPLACEMENT);
  for (int i = 0; i < S->n_runs; i++) {
    write_qoi(S->runs[i].dir, f_of(1.0 / (24.0 * S->runs[i].spf)));
    S->runs[i].s_per_frame = 0.01 * S->runs[i].spf;
  }
  cr_expect_eq(bs__study_read_qoi(S), 0);
  bs_study_verdict_make(S, &S->verdict);
  const bs_study_verdict *v = &S->verdict;
  cr_assert_eq(v->on_qoi, 1);
  cr_assert_eq(v->n_judged, 1);
  const bs_study_judged *j = &v->judged[0];
  cr_expect_str_eq(S->qoi[j->qoi], "tip", "the verdict names the quantity it judged");
  cr_expect_eq(j->extrapolated, 1);
  cr_expect_eq(j->knob, 0);
  cr_expect(fabs(j->target - 0.25) < 1e-12, "the extrapolated value %.15g", j->target);
  cr_expect(fabs(j->gci.p - 1.5) < 1e-9);
  cr_expect_eq(v->ref_competes, 1, "against the extrapolation the reference competes");
  for (int i = 0; i < S->n_runs; i++) {
    double want = 12.0 * pow(1.0 / (24.0 * S->runs[i].spf), 1.5);
    cr_expect(fabs(S->runs[i].verdict_err - want) < 1e-12, "run %d: error %.15g, want %.15g", i, S->runs[i].verdict_err,
              want);
    cr_expect_eq(S->runs[i].verdict_by, 0);
  }
  /* against the reference steps_per_frame=4 is within 1% (0.83%); against
     the extrapolated value it is 1.28% off: the verdict is the extrapolation's */
  cr_expect(S->runs[2].q_err_last[0] < 0.01, "against the reference %.4g", S->runs[2].q_err_last[0]);
  cr_expect_eq(v->cheapest[0], 3, "within 1%%: steps_per_frame=8 (0.45%%), got %d", v->cheapest[0]);
  cr_expect_eq(v->cheapest[1], -1);
  cr_expect_eq(v->cheapest[2], -1);
  cr_expect_eq(v->most_accurate, 3);
  cr_expect_eq(v->n_candidates, 4);
  /* the finest level failed: the extrapolation comes from 1, 2, 4, and the
     failed reference is no candidate */
  S->runs[3].exit_code = 1;
  bs_study_verdict_make(S, &S->verdict);
  cr_expect_eq(v->judged[0].extrapolated, 1);
  cr_expect_eq(v->n_candidates, 3);
  cr_expect_eq(v->cheapest[0], -1, "1.28%% at best: nothing within 1%%");
  cr_expect_eq(v->most_accurate, 2);
  bs_study_destroy(&S);
}

Test(study_verdict, the_summary_holds_no_second_verdict) {
  const char *qoi[1] = {"tip"};
  bs_study *S = make_study("steps_per_frame=1,2,4", 1, qoi, 0);
  for (int i = 0; i < S->n_runs; i++) {
    write_qoi(S->runs[i].dir, f_of(1.0 / (24.0 * S->runs[i].spf)));
    write_state(S->runs[i].dir, 8, -0.01 * (1 + 0.1 * S->runs[i].spf));
  }
  bs_study_evaluate(S);
  char *text = NULL;
  size_t n = 0;
  FILE *f = open_memstream(&text, &n);
  cr_assert_not_null(f);
  bs_study_summary_write(S, f);
  fclose(f);
  cr_expect_null(strstr(text, "cheapest"), "the summary ranks nothing (the verdict is S->verdict):\n%s", text);
  cr_expect_not_null(strstr(text, "Richardson extrapolated"), "%s", text);
  free(text);
  cr_expect_eq(S->verdict.on_qoi, 1);
  bs_study_destroy(&S);
}

Test(study_verdict, a_string_knob_ranks) {
  bs_study *S = make_study("solver.linear=cg,pcg", 0, NULL, 1);
  cr_assert_eq(S->n_runs, 2);
  cr_expect_eq(S->knobs[0].kind, BS_KNOB_OTHER);
  cr_expect_str_eq(S->runs[0].name, "solver.linear=cg");
  cr_expect_eq(S->ref, 1, "the reference of a string knob: the last listed value");
  /* a three-valued string knob with a second knob: the cheapest across both */
  bs_study_destroy(&S);
  S = make_study("solver.linear=cholmod,cg,pcg", 0, NULL, 1);
  cr_assert_eq(S->n_runs, 3);
  const double cost[3] = {3, 1, 2}, err[3] = {0.0005, 0.02, 0};
  for (int i = 0; i < 3; i++) {
    S->runs[i].s_per_frame = cost[i];
    S->runs[i].pos_max = err[i];
  }
  bs_study_verdict_make(S, &S->verdict);
  cr_expect_eq(S->verdict.cheapest[0], 0, "within 1%%: cholmod (cg is 2%% off, pcg the reference)");
  cr_expect_eq(S->verdict.cheapest[1], 0);
  cr_expect_eq(S->verdict.cheapest[2], -1);
  cr_expect_eq(S->verdict.n_candidates, 2);
  bs_study_destroy(&S);
}

Test(study_verdict, a_low_order_extrapolation_is_not_trusted) {
  bs_study *S = make_study("steps_per_frame=1,2,4", 0, NULL, 0);
  for (int i = 0; i < S->n_runs; i++) {
    write_qoi(S->runs[i].dir, 0.25 - 3.0 * pow(1.0 / (24.0 * S->runs[i].spf), 0.2));
    S->runs[i].s_per_frame = S->runs[i].spf;
  }
  cr_expect_eq(bs__study_read_qoi(S), 0);
  bs_study_verdict_make(S, &S->verdict);
  const bs_study_judged *j = &S->verdict.judged[0];
  cr_assert_eq(S->verdict.n_judged, 1);
  cr_expect_eq(j->knob, 0, "the GCI along steps_per_frame is reported");
  cr_expect(fabs(j->gci.p - 0.2) < 1e-9, "order %.12g", j->gci.p);
  cr_expect_eq(j->extrapolated, 0, "p = 0.2 < %g: judged against the reference", BS_STUDY_MIN_ORDER);
  cr_expect_eq(j->target, S->runs[2].q_last[0]);
  cr_expect_eq(S->verdict.ref_competes, 0);
  cr_expect_eq(S->runs[1].verdict_err, S->runs[1].q_err_last[0]);
  bs_study_destroy(&S);
}
