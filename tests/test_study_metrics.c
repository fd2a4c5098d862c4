/* The study engine without processes: the metrics on hand-made numbers
 * (order fits, Pareto front, cheapest within a threshold, energy drift),
 * the state comparison on hand-written state files, and the plan (knob
 * parsing, finest values, the cross product, errors). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_study.h"
#include "study_internal.h" /* the steps of the evaluation, private to study/ */

/* ---- order fits ------------------------------------------------------------ */

Test(study_metrics, fit_order_is_exact_on_a_power_law) {
  double h[3] = {1, 0.5, 0.25}, e[3] = {4, 1, 0.25}, logc;
  int used = -1;
  double p = bs_study_fit_order(3, h, e, &logc, &used);
  cr_expect(fabs(p - 2) < 1e-12, "order %.15g, expected 2", p);
  cr_expect(fabs(logc - log(4.0)) < 1e-12, "logc %.15g, expected log 4", logc);
  cr_expect_eq(used, 3);
}

Test(study_metrics, fit_order_skips_points_that_are_not_positive_and_finite) {
  double h[8] = {1, 0.5, 0.25, 0.1, 0.2, 0.3, 0.4, 0}, e[8] = {4, 1, 0.25, 0, -1, NAN, INFINITY, 1};
  double logc;
  int used = -1;
  double p = bs_study_fit_order(8, h, e, &logc, &used);
  cr_expect_eq(used, 3, "only the three good points count, got %d", used);
  cr_expect(fabs(p - 2) < 1e-12, "order %.15g", p);
  cr_expect(fabs(logc - log(4.0)) < 1e-12);
}

Test(study_metrics, fit_order_needs_two_distinct_points) {
  double h[2] = {0.5, 0.5}, e[2] = {1, 2}, logc = 0;
  int used = -1;
  cr_expect(isnan(bs_study_fit_order(1, h, e, &logc, &used)), "one point gives no slope");
  cr_expect(isnan(logc));
  cr_expect_eq(used, 1);
  cr_expect(isnan(bs_study_fit_order(2, h, e, &logc, &used)), "two points at the same h give no slope");
  cr_expect(isnan(bs_study_fit_order(0, h, e, &logc, &used)));
  cr_expect_eq(used, 0);
}

Test(study_metrics, successive_order_recovers_the_exponent) {
  /* halvings, p = 2: d_j = C h_j^2 (1 - 1/4) */
  double h[3] = {1, 0.5, 0.25}, d[3], rho[3] = {0.5, 0.5, 0.5};
  for (int j = 0; j < 3; j++) d[j] = 3.0 * h[j] * h[j] * (1 - 0.25);
  int used = -1;
  double p = bs_study_successive_fit(3, h, d, rho, &used);
  cr_expect(fabs(p - 2) < 1e-9, "order %.15g, expected 2", p);
  cr_expect_eq(used, 3);
  /* uneven ratios (1/2 then 1/5), p = 1.5: the bracket differs per level, so
     the plain fit is off and only the fixed point gives 1.5 */
  double h2[2] = {1, 0.5}, rho2[2] = {0.5, 0.2}, d2[2];
  for (int j = 0; j < 2; j++) d2[j] = 2.0 * pow(h2[j], 1.5) * (1 - pow(rho2[j], 1.5));
  double logc, plain = bs_study_fit_order(2, h2, d2, &logc, &used);
  p = bs_study_successive_fit(2, h2, d2, rho2, &used);
  cr_expect(fabs(p - 1.5) < 1e-9, "order %.15g, expected 1.5", p);
  cr_expect(fabs(plain - 1.5) > 1e-2, "the plain fit should be biased here, got %.15g", plain);
  cr_expect(isnan(bs_study_successive_fit(1, h, d, rho, &used)), "one pair gives no order");
}

/* ---- Pareto front and cheapest run ----------------------------------------- */

Test(study_metrics, pareto_front_marks_the_undominated_finished_points) {
  /* 0 (1, 0.5) front; 1 (2, 0.1) front; 2 (3, 0.3) dominated by 1; 3 (2, 0.2)
     ties 1 in cost with a larger error: dominated; 4 (0.5, 0.01) would
     dominate all but failed; 5 (1, NAN) not finite */
  double cost[6] = {1, 2, 3, 2, 0.5, 1}, err[6] = {0.5, 0.1, 0.3, 0.2, 0.01, NAN};
  int ok[6] = {1, 1, 1, 1, 0, 1}, front[6] = {9, 9, 9, 9, 9, 9};
  bs_study_pareto(6, cost, err, ok, front);
  static const int want[6] = {1, 1, 0, 0, 0, 0};
  for (int i = 0; i < 6; i++) cr_expect_eq(front[i], want[i], "point %d: front %d, expected %d", i, front[i], want[i]);
  /* equal points do not dominate each other */
  double c2[2] = {1, 1}, e2[2] = {0.1, 0.1};
  int ok2[2] = {1, 1}, f2[2] = {0, 0};
  bs_study_pareto(2, c2, e2, ok2, f2);
  cr_expect(f2[0] == 1 && f2[1] == 1);
}

Test(study_metrics, cheapest_within_ignores_failed_and_inaccurate_runs) {
  double cost[6] = {3, 1, 2, 0.5, 1, NAN}, err[6] = {0.001, 0.02, 0.005, 0.0001, 0.009, 0};
  int ok[6] = {1, 1, 1, 0, 1, 1};
  cr_expect_eq(bs_study_cheapest_within(6, cost, err, ok, 1e-2), 4, "run 4: cost 1 within 1%%");
  cr_expect_eq(bs_study_cheapest_within(6, cost, err, ok, 1e-3), 0, "only run 0 is within 0.1%% (3 failed)");
  cr_expect_eq(bs_study_cheapest_within(6, cost, err, ok, 1e-5), -1, "none within 0.001%% (5 has no cost)");
  double c2[3] = {1, 1, 1}, e2[3] = {NAN, 0.001, 0.001};
  int ok2[3] = {1, 1, 1};
  cr_expect_eq(bs_study_cheapest_within(3, c2, e2, ok2, 1e-2), 1, "NaN errors are not within; ties: the first");
}

Test(study_metrics, energy_drift_of_a_three_row_table) {
  double t[3] = {0, 0.1, 0.2}, kin[3] = {0, 20, 1}, tot[3] = {10, 9, 12.5};
  bs_frames_table F = {.n = 3, .time = t, .kinetic = kin, .total = tot};
  /* max |total - 10| = 2.5 over max(|10|, max kinetic 20) */
  cr_expect(fabs(bs_study_energy_drift(&F) - 0.125) < 1e-15, "drift %.15g", bs_study_energy_drift(&F));
  double k0[3] = {0, 0, 0}, t0[3] = {0, 0.5, -1};
  bs_frames_table Z = {.n = 3, .time = t, .kinetic = k0, .total = t0};
  cr_expect(fabs(bs_study_energy_drift(&Z) - 1.0) < 1e-15, "a 1 J scale when total(0) and kinetic are 0");
  bs_frames_table E = {0};
  cr_expect(isnan(bs_study_energy_drift(&E)));
}

/* ---- state comparison ------------------------------------------------------ */

/* Writes dir/state.bin (version 2) with n vertices and the given frames. */
static void write_state(const char *dir, int32_t n, int frames, const double *t, const double *xv) {
  char p[512];
  snprintf(p, sizeof p, "%s/state.bin", dir);
  FILE *f = fopen(p, "wb");
  cr_assert_not_null(f);
  uint32_t v = 2;
  int32_t hdr[2] = {n, 0};
  fwrite("BSST", 1, 4, f);
  fwrite(&v, 4, 1, f);
  fwrite(hdr, 4, 2, f);
  for (int k = 0; k < frames; k++) {
    fwrite(&t[k], sizeof(double), 1, f);
    fwrite(xv + (size_t)k * 6 * n, sizeof(double), 6 * (size_t)n, f);
  }
  fclose(f);
}

Test(study_metrics, compare_states_through_vertex_blocks) {
  char da[] = "/tmp/bs_cmpa_XXXXXX", db[] = "/tmp/bs_cmpb_XXXXXX";
  cr_assert_not_null(mkdtemp(da));
  cr_assert_not_null(mkdtemp(db));
  /* a: 2 vertices at rest, frames at 0, 0.05 (not in b), 0.1 */
  double ta[3] = {0, 0.05, 0.1}, xa[3 * 12] = {0};
  write_state(da, 2, 3, ta, xa);
  /* b: 3 vertices; its vertices 1, 2 are compared with a's 0, 1 */
  double tb[2] = {0, 0.1}, xb[2 * 18] = {0};
  xb[3 * 2] = 2;          /* frame 0: x of vertex 2 = (2, 0, 0)   */
  xb[9 + 3 * 1 + 2] = 1;  /* frame 0: v of vertex 1 = (0, 0, 1)   */
  xb[18 + 3 * 2] = 4;     /* frame 1: x of vertex 2 = (4, 0, 0)   */
  xb[18 + 9 + 3 * 1 + 2] = 1;
  write_state(db, 3, 2, tb, xb);
  bs_state_reader a, b;
  bs_error err;
  cr_assert_eq(bs_state_open(da, &a, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_state_open(db, &b, &err), 0, "%s", err.msg);
  int64_t off_a = 0, off_b = 1, count = 2;
  bs_study_errors e;
  cr_expect_eq(bs__study_compare_states(&a, &b, 1, &off_a, &off_b, &count, 2.0, 1.0, &e), 0);
  cr_expect_eq(e.n_common, 2, "frames 0 and 0.1 are common, got %d", e.n_common);
  /* frame 0: sqrt(4 / 2) / 2; frame 1: sqrt(16 / 2) / 2; velocity sqrt(1 / 2) / 1 */
  cr_expect(fabs(e.pos_max - sqrt(8.0) / 2) < 1e-12 && fabs(e.pos_last - sqrt(8.0) / 2) < 1e-12, "pos %g", e.pos_max);
  cr_expect(fabs(e.vel_max - sqrt(0.5)) < 1e-12 && fabs(e.vel_last - sqrt(0.5)) < 1e-12, "vel %g", e.vel_max);
  bs_state_close(&a);
  bs_state_close(&b);
  /* a block beyond the reader's vertices is refused */
  cr_assert_eq(bs_state_open(da, &a, &err), 0);
  cr_assert_eq(bs_state_open(db, &b, &err), 0);
  off_b = 2;
  cr_expect_eq(bs__study_compare_states(&a, &b, 1, &off_a, &off_b, &count, 2.0, 1.0, &e), -1);
  cr_expect(isnan(e.pos_max));
  bs_state_close(&a);
  bs_state_close(&b);
}

/* ---- knobs and the plan ----------------------------------------------------- */

static void knob(const char *spec, bs_study_knob *k) {
  bs_error err;
  cr_assert_eq(bs_study_knob_parse(spec, k, &err), 0, "'%s': %s", spec, err.msg);
}

Test(study_plan, finest_value_per_kind) {
  static const struct {
    const char *spec;
    bs_knob_kind kind;
    const char *path;
    int finest;
  } cases[] = {
      {"steps_per_frame=2,8,4", BS_KNOB_STEPS_PER_FRAME, "time.steps_per_frame", 1},
      {"refine=1,0,2", BS_KNOB_REFINE, "", 2},
      {"bodies.1.refine=2,0", BS_KNOB_REFINE, "bodies.1.refine", 0},
      {"time.fps=48,24", BS_KNOB_FPS, "time.fps", 0},
      {"tolerance=1e-3,1e-6,1e-4", BS_KNOB_TOLERANCE, "solver.tolerance", 1},
      {"time.dt=0.01,0.001,0.005", BS_KNOB_DT, "time.dt", 1},
      {"method=newton,optimization", BS_KNOB_METHOD, "solver.method", 1},
      {"solver.method=newton,newton_k", BS_KNOB_METHOD, "solver.method", 0},
      {"solver.max_iterations=5,50,10", BS_KNOB_OTHER, "solver.max_iterations", 2},
      {"element=tet4,tet10", BS_KNOB_OTHER, "bodies.*.element", 1},
      {"integrator=backward_euler,newmark,bdf2", BS_KNOB_OTHER, "solver.integrator", 2},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    bs_study_knob k;
    knob(cases[i].spec, &k);
    cr_expect_eq(k.kind, cases[i].kind, "'%s': kind %d", cases[i].spec, k.kind);
    cr_expect_str_eq(k.path, cases[i].path, "'%s'", cases[i].spec);
    cr_expect_eq(k.finest, cases[i].finest, "'%s': finest %d, expected %d", cases[i].spec, k.finest, cases[i].finest);
    bs_study_knob_free(&k);
  }
  bs_study_knob a, b, c;
  knob("steps_per_frame=1", &a);
  knob("time.steps_per_frame=2", &b);
  knob("bodies.0.refine=1", &c);
  cr_expect(bs_study_knob_same(&a, &b), "a shorthand and its path are the same knob");
  cr_expect(!bs_study_knob_same(&a, &c));
  cr_expect_eq(c.body, 0);
  bs_study_knob_free(&a);
  bs_study_knob_free(&b);
  bs_study_knob_free(&c);
}

Test(study_plan, bad_specs_name_the_problem) {
  static const struct {
    const char *spec, *needle;
  } cases[] = {
      {"x", "'x': expected KEY=v1,v2,..."},
      {"k=", "'k=': expected KEY=v1,v2,..."},
      {"=1,2", "'=1,2': expected"},
      {"k=1,,2", "'k=1,,2': empty value in the list"},
      {"k=1,2,", "empty value"},
      {"k=1,1", "'k=1,1': value '1' listed twice"},
      {"steps_per_frame=a", "'steps_per_frame=a': 'a' is not a number"},
      {"a..b!=1", "'a..b!' is not a key path"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    bs_study_knob k;
    bs_error err;
    bs_error_clear(&err);
    int st = bs_study_knob_parse(cases[i].spec, &k, &err);
    cr_expect_eq(st, BS_EINPUT, "'%s' returned %d", cases[i].spec, st);
    cr_expect(strstr(err.msg, cases[i].needle) != NULL, "'%s': message '%s' should hold '%s'", cases[i].spec, err.msg,
              cases[i].needle);
    cr_expect_null(k.vals, "'%s': nothing left allocated", cases[i].spec);
  }
}

static const char *box_scene =
    "{\"time\": {\"fps\": 24, \"frames\": 3, \"steps_per_frame\": 1},\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 1, 1], \"size\": [1, 0.5, 0.5]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}]}\n";

/* A study of the box scene (in a fresh folder) with the given knobs. */
static int box_study(char *dir, size_t n, int n_knobs, const char *const *specs, bs_study **S, bs_error *err) {
  snprintf(dir, n, "/tmp/bs_plan_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
  char p[512], out[512];
  snprintf(p, sizeof p, "%s/scene.json", dir);
  snprintf(out, sizeof out, "%s/study", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(box_scene, f);
  fclose(f);
  bs_study_knob k[4];
  for (int i = 0; i < n_knobs; i++) knob(specs[i], &k[i]);
  const char *sets[1] = {"time.frames=2"};
  bs_study_opts o = {.scene = p, .n_sets = 1, .sets = sets, .n_knobs = n_knobs, .knobs = k, .out = out};
  int st = bs_study_create(&o, S, err);
  for (int i = 0; i < n_knobs; i++) bs_study_knob_free(&k[i]);
  if (!st) st = bs_study_plan(*S, err);
  return st;
}

static int has_set(const bs_study_run *r, const char *s) {
  for (int i = 0; i < r->n_sets; i++)
    if (!strcmp(r->sets[i], s)) return 1;
  return 0;
}

/* The shorthands of every body and of the integrator become each body's key
 * and solver.integrator in every run's settings. */
Test(study_plan, element_and_integrator_shorthands_set_every_body) {
  char dir[256];
  bs_study *S = NULL;
  bs_error err;
  const char *specs[2] = {"element=tet4,tet10", "integrator=backward_euler,bdf2"};
  cr_assert_eq(box_study(dir, sizeof dir, 2, specs, &S, &err), 0, "%s", err.msg);
  cr_assert_eq(S->n_runs, 4);
  for (int i = 0; i < 4; i++) {
    const bs_study_run *r = &S->runs[i];
    cr_expect(has_set(r, i < 2 ? "bodies.0.element=tet4" : "bodies.0.element=tet10"), "run %d: %s", i, r->name);
    cr_expect(has_set(r, i % 2 ? "solver.integrator=bdf2" : "solver.integrator=backward_euler"), "run %d", i);
  }
  cr_expect_eq(S->ref, 3, "the reference: the last listed values (tet10, bdf2)");
  bs_study_destroy(&S);
}

Test(study_plan, cross_product_names_and_reference) {
  char dir[256];
  bs_study *S = NULL;
  bs_error err;
  const char *specs[2] = {"steps_per_frame=1,2", "tolerance=1e-2,1e-4,1e-3"};
  cr_assert_eq(box_study(dir, sizeof dir, 2, specs, &S, &err), 0, "%s", err.msg);
  cr_assert_eq(S->n_runs, 6);
  cr_expect_str_eq(S->name, "scene");
  static const char *names[6] = {"steps_per_frame=1,tolerance=1e-2", "steps_per_frame=1,tolerance=1e-4",
                                 "steps_per_frame=1,tolerance=1e-3", "steps_per_frame=2,tolerance=1e-2",
                                 "steps_per_frame=2,tolerance=1e-4", "steps_per_frame=2,tolerance=1e-3"};
  for (int i = 0; i < 6; i++) {
    const bs_study_run *r = &S->runs[i];
    char d[1600], od[1700];
    cr_expect_str_eq(r->name, names[i]);
    snprintf(d, sizeof d, "%s/study/%s", dir, names[i]);
    cr_expect_str_eq(r->dir, d);
    snprintf(od, sizeof od, "output.dir=%s", d);
    cr_expect(has_set(r, od) && has_set(r, "output.states=true") && has_set(r, "output.stats=true") &&
                  has_set(r, "output.vtu_every=0") && has_set(r, "output.checkpoint_every=0") &&
                  has_set(r, "time.frames=2"),
              "run %d: the output and user settings", i);
    cr_expect(has_set(r, i < 3 ? "time.steps_per_frame=1" : "time.steps_per_frame=2"), "run %d", i);
    cr_expect_eq(r->spf, i < 3 ? 1 : 2, "run %d: steps per frame from its scene", i);
    cr_expect_eq(r->frames, 2);
    cr_expect_str_eq(r->method, "optimization");
    cr_expect_eq(r->is_ref, i == 4, "run %d: the reference is steps 2, tolerance 1e-4", i);
  }
  cr_expect(has_set(&S->runs[5], "solver.tolerance=1e-3"));
  cr_expect_eq(S->ref, 4);
  bs_study_destroy(&S);
  cr_expect_null(S);
}

Test(study_plan, a_run_that_the_scene_refuses_is_named) {
  char dir[256];
  bs_study *S = NULL;
  bs_error err;
  bs_error_clear(&err);
  const char *specs[1] = {"bodies.0.material.youngs=1e5,-1"};
  int st = box_study(dir, sizeof dir, 1, specs, &S, &err);
  cr_expect_eq(st, BS_EINPUT);
  cr_expect(strstr(err.msg, "run bodies.0.material.youngs=-1: ") != NULL, "%s", err.msg);
  cr_expect(strstr(err.msg, "bodies.0.material.youngs") != NULL, "%s", err.msg);
  bs_study_destroy(&S);
  const char *specs2[1] = {"bodies.3.refine=0,1"};
  st = box_study(dir, sizeof dir, 1, specs2, &S, &err);
  cr_expect_eq(st, BS_EINPUT);
  cr_expect(strstr(err.msg, "'bodies.3.refine': the scene has 1 bodies") != NULL, "%s", err.msg);
  bs_study_destroy(&S);
}
