/* Forces of a simulation's state (sim/bs_forces.h) and the quantities of
 * interest built on them (sim/bs_qoi.h), against conserved and analytic
 * values: the elastic force sums to zero and is minus the finite-difference
 * gradient of the elastic energy; a static clamped beam's clamp reaction is
 * its weight; a beam on a floor (penalty or constraint) has clamp reaction
 * plus contact force equal to its weight; a homogeneously stretched bar's
 * reaction is the model's first Piola stress times the area, in a static
 * solve and at the end of a quasi-static run in time (at the end of the 1 s
 * ramp it is still 0.8% off: the dynamics are in it); friction's impulse is
 * mu |f_contact| dt against the sliding and is the momentum lost; qoi.csv
 * holds the values. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_forces.h"
#include "bs_qoi.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"

/* The simulation of a scene given as JSON text; the scene goes to *sc. */
static bs_sim *sim_of_json(const char *json, bs_scene **sc) {
  bs_error err;
  cr_assert_eq(bs_scene_parse(json, NULL, 0, NULL, sc, &err), 0, "%s", err.msg);
  bs_sim *s = NULL;
  cr_assert_eq(bs_sim_create(*sc, &s, &err), 0, "%s", err.msg);
  return s;
}

/* A static 1 x 0.1 x 0.1 m beam (10 x 2 x 2 cells) clamped at xmin, solved
 * exactly (CHOLMOD) to a tight tolerance; `extra` is more JSON at the top. */
static bs_sim *static_beam(const char *extra, bs_scene **sc) {
  char json[4096];
  snprintf(json, sizeof json,
           "{\"time\": {\"fps\": 24, \"frames\": 1, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"mode\": \"static\", \"linear\": \"cholmod\", \"tolerance\": 1e-8},\n"
           " \"gravity\": [0, -9.8, 0],\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [10, 2, 2], \"size\": [1, 0.1, 0.1]},\n"
           "   \"translate\": [0, 0.0, 0],\n"
           "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000},\n"
           "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}]%s}\n",
           extra);
  bs_error err;
  bs_sim *s = sim_of_json(json, sc);
  bs_frame_stats fs;
  cr_assert_eq(bs_sim_statics(s, &fs, &err), 0, "%s", err.msg);
  cr_assert_eq(fs.failed, 0, "the static solve failed");
  return s;
}

static double mass_total(const bs_sim *s) { return 1000 * 1.0 * 0.1 * 0.1 * (s->mesh->n_vertices > 0); }

Test(forces, clamp_reaction_of_a_static_beam_is_its_weight) {
  bs_scene *sc;
  bs_sim *s = static_beam("", &sc);
  double R[3];
  bs_error err;
  cr_assert_eq(bs_sim_reaction(s, &s->scripts[0], R, &err), 0, "%s", err.msg);
  const double W = mass_total(s) * 9.8;
  cr_expect(fabs(R[1] - W) <= 1e-8 * W, "clamp reaction %.15g N, weight %.15g N (rel %.3g)", R[1], W,
            fabs(R[1] - W) / W);
  cr_expect(fabs(R[0]) <= 1e-8 * W && fabs(R[2]) <= 1e-8 * W, "horizontal reaction %g %g", R[0], R[2]);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(forces, elastic_force_sums_to_zero_and_is_minus_the_energy_gradient) {
  bs_scene *sc;
  bs_sim *s = static_beam("", &sc);
  const int32_t n = s->mesh->n_vertices;
  double *f = malloc(sizeof(double) * 3 * (size_t)n), sum[3] = {0, 0, 0}, fmax = 0;
  bs_error err;
  cr_assert_eq(bs_sim_force_elastic(s, f, &err), 0, "%s", err.msg);
  for (int32_t v = 0; v < n; v++)
    for (int k = 0; k < 3; k++) sum[k] += f[3 * v + k], fmax = fmax > fabs(f[3 * v + k]) ? fmax : fabs(f[3 * v + k]);
  cr_assert_gt(fmax, 0.1, "the beam is deformed");
  for (int k = 0; k < 3; k++) cr_expect(fabs(sum[k]) < 1e-10 * fmax * n, "sum %d = %g", k, sum[k]);
  bs_sim_measures m0, m1;
  const int vs[3] = {0, n / 2, n - 1};
  for (int q = 0; q < 3; q++)
    for (int k = 0; k < 3; k++) {
      double *x = &s->x[3 * vs[q] + k], x0 = *x, h = 1e-7;
      *x = x0 + h;
      bs_sim_measure(s, 0, &m1);
      *x = x0 - h;
      bs_sim_measure(s, 0, &m0);
      *x = x0;
      double fd = -(m1.elastic - m0.elastic) / (2 * h);
      cr_expect(fabs(fd - f[3 * vs[q] + k]) <= 1e-5 * fmax, "vertex %d dof %d: force %.9g, FD %.9g", vs[q], k,
                f[3 * vs[q] + k], fd);
    }
  free(f);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* A beam lying on the floor y = 0 (penalty or constraint), clamped at xmin. */
static void floor_balance(const char *mode) {
  char extra[512];
  snprintf(extra, sizeof extra,
           ", \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": -0.0001, "
           "\"collision\": \"%s\", \"stiffness\": 1e9}],\n"
           " \"qoi\": [{\"name\": \"floor_y\", \"quantity\": \"contact\", \"obstacle\": 0, \"component\": \"y\"},\n"
           "  {\"name\": \"clamp_y\", \"quantity\": \"reaction\", \"group\": \"xmin\", \"component\": \"y\"}]",
           mode);
  bs_scene *sc;
  bs_sim *s = static_beam(extra, &sc);
  bs_qoi *q = NULL;
  bs_error err;
  double v[2];
  cr_assert_eq(bs_qoi_create(s, &q, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_qoi_eval(q, s, v, &err), 0, "%s", err.msg);
  const double W = mass_total(s) * 9.8;
  cr_expect_gt(v[0], 0.5 * W, "%s: the floor carries most of the beam: %g of %g N", mode, v[0], W);
  cr_expect(fabs(v[0] + v[1] - W) <= 1e-7 * W, "%s: floor %.12g + clamp %.12g = %.12g N, weight %.12g N", mode, v[0],
            v[1], v[0] + v[1], W);
  bs_qoi_destroy(&q);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(forces, floor_plus_clamp_carry_the_weight_penalty) { floor_balance("penalty"); }
Test(forces, floor_plus_clamp_carry_the_weight_constraint) { floor_balance("constraint"); }

/* A bar of length L, section A, nu = 0, clamped at xmin and held at xmax
 * displaced by e L: F = diag(1 + e, 1, 1) is the exact equilibrium (no
 * lateral stress when lambda = 0), so the support at xmax pulls with P11 A. */
static void stretched_bar(const char *model, double P11_over_E) {
  const double e = 0.2, L = 1.0, A = 0.25 * 0.25, E = 1e6;
  char json[2048];
  snprintf(json, sizeof json,
           "{\"time\": {\"fps\": 24, \"frames\": 1, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"mode\": \"static\", \"linear\": \"cholmod\", \"tolerance\": 1e-9, \"load_steps\": 4},\n"
           " \"gravity\": [0, 0, 0],\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [4, 2, 2], \"size\": [%g, 0.25, 0.25]},\n"
           "   \"material\": {\"model\": \"%s\", \"youngs\": %g, \"poisson\": 0, \"density\": 1000},\n"
           "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true},\n"
           "     {\"group\": \"xmax\", \"keyframes\": [{\"t\": 0, \"offset\": [%g, 0, 0]}]}]}],\n"
           " \"qoi\": [{\"name\": \"pull\", \"quantity\": \"reaction\", \"group\": \"xmax\", \"component\": \"x\"}]}\n",
           L, model, E, e * L);
  bs_scene *sc;
  bs_error err;
  bs_sim *s = sim_of_json(json, &sc);
  bs_frame_stats fs;
  cr_assert_eq(bs_sim_statics(s, &fs, &err), 0, "%s", err.msg);
  bs_qoi *q = NULL;
  double v;
  cr_assert_eq(bs_qoi_create(s, &q, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_qoi_eval(q, s, &v, &err), 0, "%s", err.msg);
  const double want = P11_over_E * E * A;
  cr_expect(fabs(v - want) <= 1e-8 * want, "%s: reaction %.15g N, analytic %.15g N (rel %.3g)", model, v, want,
            fabs(v - want) / want);
  bs_qoi_destroy(&q);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* The stretched cube of data/scenes/cube_stretch.json, made quasi-static:
 * the unit cube (nu = 0) is run in time (backward Euler, 24 fps, Rayleigh
 * damping) while xmax is pulled to +e over 1 s and then held for 2 s; at the
 * end of the run the pulled group's reaction is the analytic P11 A of the
 * homogeneous stretch, within what is left of the dynamics (the residual
 * inertia of a body at rest to the solver's tolerance). */
static void quasi_static_cube(const char *model, double P11_over_E, double *rel) {
  const double e = 0.2, E = 1e6;
  char json[2048];
  snprintf(json, sizeof json,
           "{\"time\": {\"fps\": 24, \"frames\": 72, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"linear\": \"cholmod\", \"tolerance\": 1e-9},\n"
           " \"gravity\": [0, 0, 0],\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [3, 3, 3], \"size\": [1, 1, 1]},\n"
           "   \"material\": {\"model\": \"%s\", \"youngs\": %g, \"poisson\": 0, \"density\": 1000,\n"
           "     \"rayleigh\": 0.01},\n"
           "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true},\n"
           "     {\"group\": \"xmax\", \"keyframes\": [{\"t\": 0, \"offset\": [0, 0, 0]},\n"
           "        {\"t\": 1, \"offset\": [%g, 0, 0]}]}]}],\n"
           " \"qoi\": [{\"name\": \"pull\", \"quantity\": \"reaction\", \"group\": \"xmax\", \"component\": \"x\"}]}\n",
           model, E, e);
  bs_scene *sc;
  bs_error err;
  bs_sim *s = sim_of_json(json, &sc);
  for (int f = 0; f < sc->frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "%s", err.msg);
    cr_assert_eq(fs.failed, 0, "%s: frame %d failed", model, f);
  }
  bs_qoi *q = NULL;
  double v;
  cr_assert_eq(bs_qoi_create(s, &q, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_qoi_eval(q, s, &v, &err), 0, "%s", err.msg);
  const double want = P11_over_E * E * 1.0;
  *rel = fabs(v - want) / want;
  bs_qoi_destroy(&q);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* nu = 0: mu = E / 2, lambda = 0; with s = 1 + e = 1.2:
 * fixed corotated P11 = 2 mu (s - 1) = E e; neo-Hookean P11 = mu (s - 1/s). */
Test(forces, stretched_bar_reaction_is_the_analytic_force) {
  stretched_bar("fixed_corotated", 0.2);
  stretched_bar("neo_hookean", 0.5 * (1.2 - 1 / 1.2));
}

Test(forces, quasi_static_stretched_cube_reaction_is_the_analytic_force) {
  double rel_fc, rel_nh;
  quasi_static_cube("fixed_corotated", 0.2, &rel_fc);
  quasi_static_cube("neo_hookean", 0.5 * (1.2 - 1 / 1.2), &rel_nh);
  fprintf(stderr, "quasi-static cube: reaction relative error %.3g (fixed_corotated), %.3g (neo_hookean)\n", rel_fc,
          rel_nh);
  cr_expect_leq(rel_fc, 1e-8, "fixed_corotated: relative error %.3g", rel_fc);
  cr_expect_leq(rel_nh, 1e-8, "neo_hookean: relative error %.3g", rel_nh);
}

Test(forces, qoi_csv_rows_and_bad_qoi_keys) {
  bs_scene *sc;
  bs_sim *s = static_beam(", \"qoi\": [{\"name\": \"tip\", \"quantity\": \"displacement\", \"group\": \"xmax\", "
                          "\"component\": \"y\"}, {\"name\": \"E\", \"quantity\": \"energy\", \"term\": \"elastic\"}]",
                          &sc);
  bs_qoi *q = NULL;
  bs_error err;
  double v[2];
  cr_assert_eq(bs_qoi_create(s, &q, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_qoi_eval(q, s, v, &err), 0, "%s", err.msg);
  double tip = 0;
  int cnt = 0;
  for (int32_t i = 0; i < s->mesh->n_vertices; i++)
    if (fabs(s->x0[3 * i] - 1.0) < 1e-12) tip += s->x[3 * i + 1] - s->x0[3 * i + 1], cnt++;
  cr_expect_eq(cnt, 9);
  cr_expect(fabs(v[0] - tip / cnt) < 1e-15, "tip %g, by hand %g", v[0], tip / cnt);
  cr_expect_lt(v[0], 0.0);
  bs_sim_measures m;
  bs_sim_measure(s, 0, &m);
  cr_expect_eq(v[1], m.elastic);
  bs_qoi_destroy(&q);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  static const char *const bad[][2] = {
      {"{\"name\": \"a\", \"quantity\": \"displacement\"}", "qoi.0: give exactly one of \"group\" or \"at\""},
      {"{\"name\": \"a\", \"quantity\": \"force\"}", "qoi.0.quantity"},
      {"{\"name\": \"a\", \"quantity\": \"reaction\"}", "qoi.0: a reaction needs"},
      {"{\"name\": \"a\", \"quantity\": \"energy\"}, {\"name\": \"a\", \"quantity\": \"energy\"}", "qoi.1: name 'a'"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1], \"size\": [1, 1, 1]}, \"material\": {\"model\": \"linear\", \"youngs\": 1e5, \"poisson\": 0.3, "
             "\"density\": 1000}}], \"qoi\": [%s]}",
             bad[i][0]);
    bs_scene *b = NULL;
    bs_error_clear(&err);
    cr_expect_eq(bs_scene_parse(json, NULL, 0, NULL, &b, &err), BS_EINPUT, "case %zu parsed", i);
    cr_expect_not_null(strstr(err.msg, bad[i][1]), "case %zu: %s", i, err.msg);
    bs_scene_destroy(&b);
  }
}

/* A box sliding at 2 m/s along x on a frictional floor (mu 0.3): in each
 * step every touching vertex slides, so the friction impulse of the step is
 * mu |contact force| dt per vertex, against the motion (its small z part is
 * against the body's own vibration); nothing else acts along x, so its x
 * part is also the step's change of x momentum. */
static void sliding_box(const char *mode) {
  char json[2048];
  const double mu = 0.3, fps = 24;
  snprintf(json, sizeof json,
           "{\"time\": {\"fps\": %g, \"frames\": 3, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"linear\": \"cholmod\", \"tolerance\": 1e-9},\n"
           " \"gravity\": [0, -9.8, 0],\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [3, 1, 3], \"size\": [0.3, 0.1, 0.3]},\n"
           "   \"velocity\": [2, 0, 0],\n"
           "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000}}],\n"
           " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": 0, \"collision\": \"%s\",\n"
           "   \"stiffness\": 1e8, \"friction\": %g}]}\n",
           fps, mode, mu);
  bs_scene *sc;
  bs_error err;
  bs_sim *s = sim_of_json(json, &sc);
  cr_assert_not_null(s->friction_impulse, "%s: the scene has friction", mode);
  const int32_t n = s->mesh->n_vertices;
  double *fc = malloc(sizeof(double) * 3 * (size_t)n);
  for (int frame = 1; frame <= 3; frame++) {
    double p0 = 0, p1 = 0, J[3] = {0, 0, 0}, C = 0, Jabs = 0;
    for (int32_t v = 0; v < n; v++) p0 += s->fem->mass[v] * s->v[3 * v];
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "%s", err.msg);
    cr_assert_eq(fs.failed, 0, "%s: frame %d failed", mode, frame);
    cr_assert_eq(bs_sim_force_contact(s, -1, fc, &err), 0, "%s", err.msg);
    for (int32_t v = 0; v < n; v++) {
      const double *jv = s->friction_impulse + 3 * v, *cv = fc + 3 * v;
      p1 += s->fem->mass[v] * s->v[3 * v];
      for (int k = 0; k < 3; k++) J[k] += jv[k];
      Jabs += sqrt(jv[0] * jv[0] + jv[1] * jv[1] + jv[2] * jv[2]);
      C += sqrt(cv[0] * cv[0] + cv[1] * cv[1] + cv[2] * cv[2]);
    }
    const double want = mu * C / fps;
    cr_expect_gt(C, 0.5 * 9.8 * 9.0, "%s: frame %d: the floor carries the box (%g N)", mode, frame, C);
    cr_expect(fabs(Jabs - want) <= 1e-9 * want, "%s: frame %d: sum |friction impulse| %.12g N s, mu sum|f| dt %.12g",
              mode, frame, Jabs, want);
    cr_expect(J[0] < -0.999 * Jabs && J[1] == 0, "%s: frame %d: J = (%g, %g, %g) is against the motion", mode, frame,
              J[0], J[1], J[2]);
    cr_expect(fabs((p1 - p0) - J[0]) <= 1e-6 * want, "%s: frame %d: momentum change %.12g, impulse %.12g", mode,
              frame, p1 - p0, J[0]);
  }
  free(fc);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(forces, friction_impulse_of_a_sliding_box_penalty) { sliding_box("penalty"); }
Test(forces, friction_impulse_of_a_sliding_box_constraint) { sliding_box("constraint"); }

Test(forces, no_friction_no_impulse_buffer) {
  bs_scene *sc;
  bs_sim *s = static_beam("", &sc);
  cr_expect_null(s->friction_impulse);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}
