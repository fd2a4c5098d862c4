/* Tolerances that mean something (solver/bs_minimize.h: tau_eff, the rounding
 * floor, quadratic objectives), through the simulation library:
 *  - a stiff static linear cantilever (E = 1e9) asked for |grad E| < 1e-8 N,
 *    below what its gradient resolves (~4e-8 N), ends "converged at the
 *    rounding floor of E" in at most 3 iterations (it used to fail after 168),
 *    at the answer of a tight direct solve; the fixed-corotated one too;
 *  - rtol and load_rtol set tau_eff = max(tol, rtol |g0|, load_rtol |f_ext|),
 *    with |f_ext| the weight's norm over the free vertices computed here;
 *  - the linear model (a quadratic objective) converges in at most two Newton
 *    iterations per step on a small dynamic beam; the same beam with a
 *    nonlinear model takes more (so the count sees the quadratic path). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_minimize.h"
#include "bs_scene.h"
#include "bs_sim.h"

/* A 1 x 0.1 x 0.1 m cantilever (20 x 2 x 2 cells) clamped at xmin under
 * gravity; `solver` is the JSON of the solver object's members, `model` and
 * `youngs` the material's. */
static bs_sim *beam(const char *solver, const char *model, double youngs, const char *time, bs_scene **sc) {
  char json[4096];
  snprintf(json, sizeof json,
           "{\"time\": {%s},\n"
           " \"solver\": {%s},\n"
           " \"gravity\": [0, -9.8, 0],\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [20, 2, 2], \"size\": [1, 0.1, 0.1]},\n"
           "   \"material\": {\"model\": \"%s\", \"youngs\": %g, \"poisson\": 0.3, \"density\": 1000},\n"
           "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}]}\n",
           time, solver, model, youngs);
  bs_error err;
  cr_assert_eq(bs_scene_parse(json, NULL, 0, NULL, sc, &err), 0, "%s", err.msg);
  bs_sim *s = NULL;
  cr_assert_eq(bs_sim_create(*sc, &s, &err), 0, "%s", err.msg);
  return s;
}

static const char *static_time = "\"fps\": 24, \"frames\": 1, \"steps_per_frame\": 1";

/* The static solve's step record. */
static bs_step_stats solve_static(bs_sim *s) {
  bs_frame_stats fs;
  bs_error err;
  cr_assert_eq(bs_sim_statics(s, &fs, &err), 0, "%s", err.msg);
  return fs.steps[0].st;
}

/* The y displacement of the vertex at (1, 0, 0), the beam's tip. */
static double tip_y(const bs_sim *s) {
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) {
    const double *X = s->x0 + 3 * v;
    if (fabs(X[0] - 1) < 1e-12 && fabs(X[1]) < 1e-12 && fabs(X[2]) < 1e-12) return s->x[3 * v + 1] - X[1];
  }
  cr_assert_fail("no vertex at the tip");
  return NAN;
}

static void stiff_cantilever_floor(const char *model, int max_iterations) {
  bs_scene *sc, *sr;
  bs_sim *s = beam("\"mode\": \"static\", \"linear\": \"cg\", \"tolerance\": 1e-8", model, 1e9, static_time, &sc);
  bs_step_stats st = solve_static(s);
  cr_assert_eq(st.failed, 0, "%s: failed: %s", model, st.min.reason_text);
  cr_assert_eq(st.min.reason, BS_MIN_FLOOR, "%s: %s: %s", model, bs_min_reason_name(st.min.reason), st.min.reason_text);
  cr_assert(strstr(st.min.reason_text, "rounding floor of E") != NULL, "%s", st.min.reason_text);
  cr_assert_gt(st.min.grad_norm, 1e-8, "the tolerance is below the floor: |g| %.3e", st.min.grad_norm);
  cr_assert_lt(st.min.grad_norm, 1e-6, "the floor is at the gradient's rounding level: |g| %.3e", st.min.grad_norm);
  cr_assert_leq(st.min.iterations, max_iterations, "%s: %d iterations", model, st.min.iterations);
  /* The answer of a tight direct solve. */
  bs_sim *r = beam("\"mode\": \"static\", \"linear\": \"cholmod\", \"tolerance\": 1e-6", model, 1e9, static_time, &sr);
  bs_step_stats rt = solve_static(r);
  cr_assert_eq(rt.failed, 0, "reference: %s", rt.min.reason_text);
  const double a = tip_y(s), b = tip_y(r);
  cr_assert(fabs(a - b) <= 1e-7 * fabs(b), "%s: tip %.12e vs direct %.12e", model, a, b);
  bs_sim_destroy(&s);
  bs_sim_destroy(&r);
  bs_scene_destroy(&sc);
  bs_scene_destroy(&sr);
}

Test(tolerance, stiff_linear_cantilever_converges_at_the_floor) { stiff_cantilever_floor("linear", 3); }
Test(tolerance, stiff_corotated_cantilever_converges_at_the_floor) { stiff_cantilever_floor("fixed_corotated", 20); }

/* |f_ext| of the weight on the beam's free vertices (x > 0). */
static double weight_norm(const bs_sim *s) {
  double q = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    if (s->x0[3 * v] > 1e-12) q += pow(s->fem->mass[v] * 9.8, 2);
  return sqrt(q);
}

Test(tolerance, rtol_is_relative_to_the_initial_gradient) {
  bs_scene *sc;
  bs_sim *s = beam("\"mode\": \"static\", \"linear\": \"cg\", \"tolerance\": 1e-14, \"rtol\": 1e-5", "fixed_corotated",
                   1e9, static_time, &sc);
  bs_step_stats st = solve_static(s);
  cr_assert_eq(st.min.reason, BS_MIN_CONVERGED, "%s", st.min.reason_text);
  /* At the rest shape only gravity acts: |g0| is the weight's norm. */
  const double W = weight_norm(s);
  cr_assert(fabs(st.min.tol_used - 1e-5 * W) <= 1e-9 * W, "tau_eff %.12e, 1e-5 |g0| %.12e", st.min.tol_used, 1e-5 * W);
  cr_assert_lt(st.min.grad_norm, st.min.tol_used);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(tolerance, load_rtol_is_relative_to_the_external_load) {
  bs_scene *sc;
  bs_sim *s = beam("\"mode\": \"static\", \"linear\": \"cg\", \"tolerance\": 1e-14, \"load_rtol\": 1e-7",
                   "fixed_corotated", 1e8, static_time, &sc);
  bs_step_stats st = solve_static(s);
  cr_assert_eq(st.min.reason, BS_MIN_CONVERGED, "%s", st.min.reason_text);
  const double W = weight_norm(s);
  cr_assert(fabs(st.min.tol_used - 1e-7 * W) <= 1e-9 * W, "tau_eff %.12e, 1e-7 |f_ext| %.12e", st.min.tol_used,
            1e-7 * W);
  cr_assert_lt(st.min.grad_norm, st.min.tol_used);
  /* The absolute tolerance still rules when it is the larger. */
  bs_scene_destroy(&sc);
  bs_sim_destroy(&s);
  s = beam("\"mode\": \"static\", \"linear\": \"cg\", \"tolerance\": 1e-3, \"load_rtol\": 1e-7", "fixed_corotated", 1e8,
           static_time, &sc);
  st = solve_static(s);
  cr_assert_eq(st.min.tol_used, 1e-3);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* Newton iterations of the beam's steps, dynamic at 240 steps/s for 0.25 s. */
static void dynamic_counts(const char *model, long *steps, int *max_per_step, long *failed) {
  bs_scene *sc;
  bs_sim *s = beam("\"linear\": \"cg\", \"tolerance\": 1e-7", model, 1e8,
                   "\"fps\": 24, \"frames\": 6, \"steps_per_frame\": 10", &sc);
  *steps = *failed = 0;
  *max_per_step = 0;
  bs_error err;
  for (int f = 0; f < sc->frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "%s", err.msg);
    for (int k = 0; k < fs.n_steps; k++) {
      const bs_step_stats *st = &fs.steps[k].st;
      (*steps)++;
      *failed += st->failed;
      if (st->min.iterations > *max_per_step) *max_per_step = st->min.iterations;
    }
  }
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(tolerance, linear_model_converges_in_two_newton_iterations_per_step) {
  long steps, failed;
  int most;
  dynamic_counts("linear", &steps, &most, &failed);
  cr_assert_eq(steps, 60);
  cr_assert_eq(failed, 0, "%ld failed steps", failed);
  cr_assert_leq(most, 2, "a step of the linear model took %d Newton iterations", most);
  /* A nonlinear model of the same beam takes more: the count sees the path. */
  dynamic_counts("fixed_corotated", &steps, &most, &failed);
  cr_assert_eq(failed, 0, "%ld failed steps", failed);
  cr_assert_gt(most, 2, "fixed_corotated: at most %d Newton iterations per step", most);
}
