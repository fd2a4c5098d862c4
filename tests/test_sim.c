/* The simulation library's own entry points (scene/bs_scene.h, sim/bs_sim.h):
 * a scene built in C is the scene of the same JSON, bit for bit;
 * bs_scene_validate names the key of a bad value; bs_sim_run's callback
 * contract (frames 0..frames at exactly f / fps, a nonzero return stops). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_scene.h"
#include "bs_sim.h"
#include "scene_fixture.h"

/* A clamped beam sagging under gravity, solved statically. */
static const char *beam_json =
    "{\"time\": {\"fps\": 24, \"frames\": 1},\n"
    " \"solver\": {\"mode\": \"static\", \"tolerance\": 1e-6},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [6, 2, 2], \"size\": [1, 0.2, 0.2]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}]}\n";

static bs_scene *beam_in_c(void) {
  bs_scene *sc = NULL;
  bs_scene_body *b = NULL;
  bs_scene_script *clamp = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_create(&sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_add_body(sc, "box", &b, &err), 0, "%s", err.msg);
  b->box_cells[0] = 6;
  b->box_cells[1] = b->box_cells[2] = 2;
  b->box_size[0] = 1.0;
  b->box_size[1] = b->box_size[2] = 0.2;
  b->materials[0] = (bs_scene_material){.model = BS_MODEL_FIXED_COROTATED, .youngs = 1e6, .poisson = 0.3,
                                        .density = 1000};
  cr_assert_eq(bs_scene_body_add_script(b, "xmin", BS_SCRIPT_FIXED, &clamp, &err), 0, "%s", err.msg);
  cr_assert_not_null(clamp);
  sc->mode = BS_MODE_STATIC;
  sc->frames = 1;
  sc->solver.min.tol = 1e-6;
  sc->gravity[0] = 0;
  sc->gravity[1] = -9.8;
  sc->gravity[2] = 0;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  return sc;
}

/* Creates the simulation of sc, solves statically; returns it. */
static bs_sim *solve(const bs_scene *sc) {
  bs_sim *s = NULL;
  bs_frame_stats fs;
  bs_error err;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_statics(s, &fs, &err), 0, "%s", err.msg);
  cr_assert_eq(fs.n_steps, 1);
  cr_assert_eq(fs.failed, 0, "the static solve failed: %s", fs.steps[0].st.min.reason_text);
  cr_assert_gt(fs.iterations, 0);
  return s;
}

Test(sim, scene_built_in_c_is_the_json_scene) {
  bs_scene *a = beam_in_c(), *j = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_parse(beam_json, NULL, 0, NULL, &j, &err), 0, "%s", err.msg);
  cr_expect_str_eq(a->path, "<scene>");
  cr_expect_eq(a->dt, j->dt);
  cr_expect_eq(j->mode, BS_MODE_STATIC);
  bs_sim *sa = solve(a), *sj = solve(j);
  cr_assert_eq(sa->mesh->n_vertices, sj->mesh->n_vertices);
  cr_assert_eq(sa->mesh->n_vertices, 7 * 3 * 3);
  cr_assert_eq(sa->n_free, sj->n_free);
  cr_assert_eq(sa->n_free, 6 * 3 * 3, "the 9 vertices of x = 0 are clamped");
  size_t bytes = 3 * sizeof(double) * (size_t)sa->mesh->n_vertices;
  cr_expect_eq(memcmp(sa->x0, sj->x0, bytes), 0, "the rest positions differ");
  cr_expect_eq(memcmp(sa->x, sj->x, bytes), 0, "the static solutions differ");
  /* and the beam did sag: the free end moved down */
  double tip = 0;
  for (int32_t i = 0; i < sa->mesh->n_vertices; i++)
    if (sa->x0[3 * i] == 1.0) tip += sa->x[3 * i + 1] - sa->x0[3 * i + 1];
  cr_expect_lt(tip, 0.0, "the tip did not sag: %g", tip);
  bs_sim_destroy(&sa);
  bs_sim_destroy(&sj);
  bs_scene_destroy(&a);
  bs_scene_destroy(&j);
}

/* Validating after one bad value: BS_EINPUT with the key in the message. */
Test(sim, validate_names_the_key) {
  bs_error err;
  bs_scene *sc = beam_in_c();
  sc->fps = 0;
  cr_expect_eq(bs_scene_validate(sc, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "<scene>: time.fps: must be in [1e-09, 1e+09], got 0"), "%s", err.msg);
  bs_scene_destroy(&sc);

  sc = beam_in_c();
  sc->bodies[0].materials[0].density = -1;
  cr_expect_eq(bs_scene_validate(sc, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "<scene>: bodies.0.material"), "%s", err.msg);
  cr_expect_not_null(strstr(err.msg, "density"), "%s", err.msg);
  bs_sim *s = NULL;
  cr_expect_eq(bs_sim_create(sc, &s, &err), BS_EINPUT, "bs_sim_create validates too");
  cr_expect_null(s);
  cr_expect_not_null(strstr(err.msg, "bodies.0.material"), "%s", err.msg);
  bs_scene_destroy(&sc);

  sc = beam_in_c();
  bs_scene_obstacle *o = NULL;
  cr_assert_eq(bs_scene_add_obstacle(sc, BS_SHAPE_PLANE, &o, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "the default plane is valid: %s", err.msg);
  o->friction = -0.5;
  cr_expect_eq(bs_scene_validate(sc, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "<scene>: obstacles.0.friction: must be >= 0, got -0.5"), "%s", err.msg);
  bs_scene_destroy(&sc);

  /* a stale dt is caught by bs_scene_check, fixed by bs_scene_validate */
  sc = beam_in_c();
  sc->fps = 48;
  cr_expect_eq(bs_scene_check(sc, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "time.dt"), "%s", err.msg);
  cr_expect_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  cr_expect_eq(sc->dt, 1.0 / 48);
  bs_scene_destroy(&sc);
}


typedef struct calls {
  int n, frames[16], n_steps[16], stop_at, code;
  double times[16], sim_times[16];
} calls;

static int count_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  calls *c = ctx;
  if (c->n < 16) {
    c->frames[c->n] = fs->frame;
    c->times[c->n] = fs->time;
    c->sim_times[c->n] = s->time;
    c->n_steps[c->n] = fs->n_steps;
  }
  c->n++;
  if (c->stop_at >= 0 && fs->frame == c->stop_at) return bs_error_set(err, c->code, "stopped at frame %d", fs->frame);
  return 0;
}

Test(sim, run_calls_back_every_frame_at_exact_times) {
  const int frames = 5, steps = 3;
  const double fps = 30;
  bs_scene *sc = bs_test_box_scene(frames, fps, steps);
  bs_sim *s = NULL;
  bs_error err;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  calls c = {.stop_at = -1};
  bs_run_totals T;
  cr_assert_eq(bs_sim_run(s, count_frame, &c, &T, &err), 0, "%s", err.msg);
  cr_assert_eq(c.n, frames + 1, "%d calls", c.n);
  for (int f = 0; f <= frames; f++) {
    cr_expect_eq(c.frames[f], f, "call %d: frame %d", f, c.frames[f]);
    cr_expect_eq(c.times[f], f / fps, "frame %d at %.17g, not %.17g", f, c.times[f], f / fps);
    cr_expect_eq(c.sim_times[f], f / fps, "frame %d: s->time %.17g", f, c.sim_times[f]);
    cr_expect_eq(c.n_steps[f], f ? steps : 0, "frame %d: %d steps", f, c.n_steps[f]);
  }
  cr_expect_eq(s->frame, frames);
  cr_expect_eq(T.steps, frames * steps);
  cr_expect_eq(T.failed, 0, "%s", T.first_fail_reason);
  /* the box fell */
  cr_expect_lt(s->x[1], s->x0[1]);
  bs_sim_destroy(&s);

  /* a nonzero return stops the run and is what bs_sim_run returns */
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  calls d = {.stop_at = 2, .code = 7};
  bs_error_clear(&err);
  cr_expect_eq(bs_sim_run(s, count_frame, &d, &T, &err), 7);
  cr_expect_eq(d.n, 3, "%d calls after a stop at frame 2", d.n);
  cr_expect_eq(s->frame, 2, "the run went on to frame %d", s->frame);
  cr_expect_str_eq(err.msg, "stopped at frame 2");
  cr_expect_eq(T.steps, 2 * steps);
  bs_sim_destroy(&s);

  /* ... also from frame 0, before any step */
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  calls z = {.stop_at = 0, .code = BS_EIO};
  cr_expect_eq(bs_sim_run(s, count_frame, &z, NULL, &err), BS_EIO);
  cr_expect_eq(z.n, 1);
  cr_expect_eq(s->frame, 0);
  cr_expect_eq(memcmp(s->x, s->x0, 3 * sizeof(double) * (size_t)s->mesh->n_vertices), 0, "a step ran");
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* A static scene: frame 0, then frame 1 (the solve), at time 0. */
Test(sim, run_of_a_static_scene_calls_back_twice) {
  bs_scene *sc = beam_in_c();
  bs_sim *s = NULL;
  bs_error err;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  calls c = {.stop_at = -1};
  bs_run_totals T;
  cr_assert_eq(bs_sim_run(s, count_frame, &c, &T, &err), 0, "%s", err.msg);
  cr_expect_eq(c.n, 2);
  cr_expect_eq(c.frames[0], 0);
  cr_expect_eq(c.frames[1], 1);
  cr_expect_eq(c.times[1], 0.0);
  cr_expect_eq(c.n_steps[1], 1);
  cr_expect_eq(T.steps, 1);
  cr_expect_eq(T.failed, 0);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* Each step of a frame keeps its own reason text: the minimizer's buffer is
 * overwritten by the next solve, so the simulation copies it (a frame of 3
 * steps once showed the last step's text on every row of stats.csv). */
Test(sim, every_step_keeps_its_own_reason) {
  bs_scene *sc = bs_test_box_scene(1, 24, 3);
  bs_sim *s = NULL;
  bs_error err;
  bs_frame_stats fs;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "%s", err.msg);
  cr_assert_eq(fs.n_steps, 3);
  for (int k = 0; k < 3; k++) {
    const bs_step_stats *st = &fs.steps[k].st;
    char want[64];
    snprintf(want, sizeof want, "|grad E| = %.3e", st->min.grad_norm);
    cr_expect(st->min.reason_text == fs.steps[k].reason, "step %d: the text is the step's own copy", k);
    cr_expect(strstr(st->min.reason_text, want) != NULL, "step %d: '%s' should say %s", k, st->min.reason_text,
              want);
  }
  cr_expect(fs.steps[0].st.min.grad_norm != fs.steps[2].st.min.grad_norm, "the steps should end at different |grad E|");
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* The rest of the C builder against its JSON: a material for a 3-D group, a
 * keyframed group, an obstacle; the same state after two frames, bit for bit. */
static const char *parts_json =
    "{\"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 2},\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"materials\": {\"body\": {\"model\": \"neo_hookean\", \"youngs\": 2e5, \"poisson\": 0.3, \"density\": 1000}},\n"
    "   \"scripted\": [{\"group\": \"xmax\", \"keyframes\": [{\"t\": 0, \"offset\": [0, 0, 0]},\n"
    "                                                  {\"t\": 0.1, \"offset\": [0.05, 0.02, 0]}]}]}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": -0.01, \"friction\": 0.3}]}\n";

Test(sim, builder_parts_match_the_json) {
  bs_scene *sc = bs_test_box_scene(2, 24, 2);
  bs_scene_body *b = &sc->bodies[0];
  bs_scene_material *m = NULL;
  bs_scene_script *key = NULL;
  bs_scene_obstacle *o = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_body_add_material(b, "body", &m, &err), 0, "%s", err.msg);
  cr_expect(m->density == 1000 && m->youngs == 1e5, "a material starts as a copy of the body's default");
  m->model = BS_MODEL_NEO_HOOKEAN;
  m->youngs = 2e5;
  const double kt[2] = {0, 0.1}, ko[6] = {0, 0, 0, 0.05, 0.02, 0};
  cr_assert_eq(bs_scene_body_add_script(b, "xmax", BS_SCRIPT_FIXED, &key, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_script_set_keyframes(key, 2, kt, ko, &err), 0, "%s", err.msg);
  cr_expect_eq(key->kind, BS_SCRIPT_KEYFRAMES);
  cr_assert_eq(bs_scene_add_obstacle(sc, BS_SHAPE_PLANE, &o, &err), 0, "%s", err.msg);
  cr_expect(o->normal[1] == 1 && o->collision == BS_COLLIDE_CONSTRAINT, "the schema's obstacle defaults");
  o->offset = -0.01;
  o->friction = 0.3;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  bs_scene *js = NULL;
  cr_assert_eq(bs_scene_parse(parts_json, "parts.json", 0, NULL, &js, &err), 0, "%s", err.msg);
  bs_sim *a = NULL, *c = NULL;
  cr_assert_eq(bs_sim_create(sc, &a, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(js, &c, &err), 0, "%s", err.msg);
  bs_run_totals Ta, Tc;
  cr_assert_eq(bs_sim_run(a, NULL, NULL, &Ta, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_run(c, NULL, NULL, &Tc, &err), 0, "%s", err.msg);
  cr_expect_eq(Ta.failed, 0, "%s", Ta.first_fail_reason);
  cr_expect_eq(Ta.iterations, Tc.iterations);
  size_t n3 = 3 * (size_t)a->mesh->n_vertices;
  cr_assert_eq(a->mesh->n_vertices, c->mesh->n_vertices);
  cr_expect_eq(memcmp(a->x, c->x, sizeof(double) * n3), 0, "the C scene and its JSON end in different states");
  cr_expect_eq(memcmp(a->v, c->v, sizeof(double) * n3), 0);
  cr_expect_eq(a->tet_material[0], 1, "the group 'body' has the second material");
  bs_sim_destroy(&a);
  bs_sim_destroy(&c);
  bs_scene_destroy(&js);
  bs_scene_destroy(&sc);
}

Test(sim, shape_names_round_trip) {
  for (int k = BS_SHAPE_PLANE; k <= BS_SHAPE_GRID; k++) {
    bs_shape s;
    bs_error err;
    cr_expect_eq(bs_shape_parse(bs_shape_name((bs_shape)k), &s, &err), 0);
    cr_expect_eq((int)s, k);
  }
  bs_shape s;
  bs_error err;
  cr_expect_eq(bs_shape_parse("cone", &s, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "cone") != NULL, "%s", err.msg);
}

/* The Newton baseline on the stretched cube (each face pulled 0.5 m in one
 * 24 Hz step) diverges: it must stop within a couple of dozen iterations
 * with the reason "diverged" or "nonfinite", a failed step, instead of
 * running its cap of MINRES solves (the issue: 500 iterations, 468 s). */
Test(sim, newton_baseline_stops_when_it_diverges) {
  bs_scene *sc = NULL;
  bs_error err;
  const char *set[] = {"solver.method=\"newton\"", "time.frames=1"}; /* 12^3 cells; at 6^3 Newton converges */
  cr_assert_eq(bs_scene_load(BS_SOURCE_DIR "/data/scenes/cube_stretch.json", 2, set, &sc, &err), 0, "%s", err.msg);
  bs_sim *s = NULL;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  bs_frame_stats fs;
  cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "%s", err.msg);
  cr_expect_eq(fs.failed, 1);
  const bs_min_reason r = fs.steps[0].st.min.reason;
  cr_expect(r == BS_MIN_DIVERGED || r == BS_MIN_NONFINITE, "%s: %s", bs_min_reason_name(r), fs.steps[0].reason);
  cr_expect_leq(fs.iterations, BS_NEWTON_WINDOW + 1, "%ld iterations: %s", fs.iterations, fs.steps[0].reason);
  fprintf(stderr, "newton baseline on the stretched cube: %ld iterations, %ld MINRES, %s\n", fs.iterations,
          fs.cg_iterations, fs.steps[0].reason);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}
