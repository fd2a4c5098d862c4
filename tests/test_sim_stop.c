/* Stopping a run on request (bs_sim_run_with, opts.stop): the flag is read
 * before every step and, through the minimizer, before every Newton
 * iteration; a frame cut short is undone, so that the simulation is at the
 * end of its last complete frame, bit for bit; and the run continued from
 * there (opts.resume) ends in the state of a run never stopped. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "bs_sim.h"
#include "bs_terms.h"
#include "scene_fixture.h"

static volatile sig_atomic_t stop_flag;
static int steps_begun, stop_at;
static int grads, stop_grad; /* gradient evaluations; the one that raises the flag */

/* A term of zero energy that raises the stop flag when step stop_at begins. */
static int zero_value(const bs_term *t, const double *x, double *E) {
  (void)t, (void)x;
  *E = 0;
  return 0;
}
static int zero_gradient(const bs_term *t, const double *x, double *E, double *g) {
  (void)t, (void)x, (void)g;
  if (++grads == stop_grad) stop_flag = 1;
  *E = 0;
  return 0;
}
static int zero_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  (void)t, (void)x, (void)H;
  return 0;
}
static int count_step(bs_term *t, bs_error *err) {
  (void)t, (void)err;
  if (++steps_begun == stop_at) stop_flag = 1;
  return 0;
}
static const bs_term_ops stopper_ops = {zero_value, zero_gradient, zero_hessian, count_step, NULL, NULL, NULL, NULL,
                                        NULL, NULL};

/* The end of frame 1 as the frame callback saw it. */
typedef struct seen {
  int frame;
  double time, *x, *v;
} seen;

static int remember(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  (void)err;
  seen *w = ctx;
  size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  w->frame = fs->frame;
  w->time = s->time;
  memcpy(w->x, s->x, sizeof(double) * n3);
  memcpy(w->v, s->v, sizeof(double) * n3);
  return 0;
}

/* s stopped in frame 2 is where the callback saw frame 1 end, bit for bit. */
static void expect_at_frame_1(const bs_sim *s, const seen *w) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  cr_expect_eq(s->frame, 1);
  cr_expect_eq(w->frame, 1, "the callback saw frame %d last", w->frame);
  cr_expect_eq(s->time, w->time);
  cr_expect_eq(memcmp(s->x, w->x, sizeof(double) * n3), 0, "x is not frame 1's");
  cr_expect_eq(memcmp(s->v, w->v, sizeof(double) * n3), 0, "v is not frame 1's");
}

/* s, continued to the end (o->resume), is in ref's end state (the run never
 * stopped), bit for bit. */
static void expect_same_end(bs_sim *s, const bs_sim *ref, bs_sim_run_opts *o, bs_run_totals *T) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  bs_error err;
  o->resume = 1;
  cr_assert_eq(bs_sim_run_with(s, o, T, &err), 0, "%s", err.msg);
  cr_expect_eq(s->frame, 3);
  cr_expect_eq(memcmp(s->x, ref->x, sizeof(double) * n3), 0, "x differs from the run never stopped");
  cr_expect_eq(memcmp(s->v, ref->v, sizeof(double) * n3), 0, "v differs from the run never stopped");
}

static void tear_down(seen *w, bs_sim **s, bs_sim **ref, bs_scene **sc) {
  free(w->x);
  free(w->v);
  bs_sim_destroy(s);
  bs_sim_destroy(ref);
  bs_scene_destroy(sc);
}

static bs_sim *make_sim(bs_scene *sc) {
  bs_sim *s = NULL;
  bs_term *t = NULL;
  bs_error err;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_create("stopper", &stopper_ops, s->fem, &s->step, NULL, &t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_add_term(s, t, &err), 0, "%s", err.msg);
  return s;
}

/* Counts the steps that started from the previous-step guess (bs_step.h). */
static int count_previous(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  (void)err;
  for (int k = 0; k < fs->n_steps; k++) *(int *)ctx += s->steps[k].st.guess == BS_GUESS_PREVIOUS;
  return 0;
}

/* sc (3 frames of 3 steps) stopped while frame 2 runs: step 5 of 9 raises
 * the flag, step 6 is not taken; continued, the same end state, bit for bit,
 * and the totals of the whole run. *previous: steps of the run never stopped
 * that started from the previous-step guess. */
static void cut_short_and_continue(bs_scene *sc, int *previous) {
  bs_error err;
  bs_sim *ref = make_sim(sc);
  stop_flag = 0, steps_begun = 0, stop_at = -1;
  bs_run_totals Tref, T;
  *previous = 0;
  cr_assert_eq(bs_sim_run(ref, count_previous, previous, &Tref, &err), 0, "%s", err.msg);
  bs_sim *s = make_sim(sc);
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  seen w = {.x = calloc(n3, sizeof(double)), .v = calloc(n3, sizeof(double))};
  stop_flag = 0, steps_begun = 0, stop_at = 5;
  bs_sim_run_opts o = {.on_frame = remember, .ctx = &w, .stop = &stop_flag};
  cr_assert_eq(bs_sim_run_with(s, &o, &T, &err), BS_SIM_STOPPED);
  cr_expect_eq(steps_begun, 5);
  expect_at_frame_1(s, &w);
  cr_expect_eq(T.steps, 3);
  stop_flag = 0;
  expect_same_end(s, ref, &o, &T);
  cr_expect_eq(T.steps, Tref.steps);
  cr_expect_eq(T.iterations, Tref.iterations);
  tear_down(&w, &s, &ref, &sc);
}

Test(sim_stop, a_frame_cut_short_is_undone_and_the_run_continues_bit_for_bit) {
  bs_scene *sc = bs_test_box_scene(3, 24.0, 3);
  bs_error err;
  sc->gravity[1] = -9.8;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  int previous;
  cut_short_and_continue(sc, &previous);
  cr_expect_eq(previous, 0, "without friction the previous-step guess is never offered");
}

/* The box on a floor with friction 0.5, pushed along x at 2 m/s by a
 * kinematic penalty box (fig14's striker in small): friction changes v after
 * every step, so steps start from the previous-step guess (measured: all but
 * the first), whose state the undo restores too (without it the continued
 * run differs). */
Test(sim_stop, a_frame_cut_short_with_friction_continues_bit_for_bit) {
  bs_scene *sc = bs_test_box_scene(3, 24.0, 3);
  bs_scene_obstacle *floor = NULL, *striker = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_add_obstacle(sc, BS_SHAPE_PLANE, &floor, &err), 0, "%s", err.msg);
  floor->friction = 0.5;
  cr_assert_eq(bs_scene_add_obstacle(sc, BS_SHAPE_BOX, &striker, &err), 0, "%s", err.msg);
  const double c[3] = {-0.26, 0.5, 0.5};
  for (int k = 0; k < 3; k++) striker->center[k] = c[k], striker->half_extents[k] = 0.25;
  striker->velocity[0] = 2;
  striker->collision = BS_COLLIDE_PENALTY;
  striker->stiffness = 1e8;
  striker->friction = 0.2;
  sc->gravity[1] = -9.8;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  int previous;
  cut_short_and_continue(sc, &previous);
  cr_expect_gt(previous, 0, "no step started from the previous-step guess");
}

/* A spinning box (20 rad/s, 1 step per frame: 0.83 rad per step) takes
 * several Newton iterations per step. The flag raised by a gradient
 * evaluation in the middle of frame 2's solve stops that solve at its next
 * iteration (not at its end); frame 2 is undone, the minimizer's carry too,
 * and the continued run ends bit for bit as the run never stopped. */
Test(sim_stop, a_solve_is_stopped_between_newton_iterations) {
  bs_scene *sc = bs_test_box_scene(3, 24.0, 1);
  bs_error err;
  sc->bodies[0].angular_velocity[2] = 20;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  bs_sim *ref = make_sim(sc);
  const size_t n3 = 3 * (size_t)ref->mesh->n_vertices;
  seen w = {.x = calloc(n3, sizeof(double)), .v = calloc(n3, sizeof(double))};
  stop_flag = 0, steps_begun = 0, stop_at = -1, grads = 0, stop_grad = -1;
  bs_run_totals Tref, T;
  cr_assert_eq(bs_sim_advance_frame(ref, &(bs_frame_stats){0}, &err), 0, "%s", err.msg);
  const int g1 = grads;
  cr_assert_eq(bs_sim_advance_frame(ref, &(bs_frame_stats){0}, &err), 0, "%s", err.msg);
  const int g2 = grads, it2 = ref->steps[0].st.min.iterations;
  cr_assert(it2 >= 4, "frame 2 took %d Newton iterations (a few wanted)", it2);
  bs_sim_destroy(&ref);
  ref = make_sim(sc);
  grads = 0;
  cr_assert_eq(bs_sim_run(ref, NULL, NULL, &Tref, &err), 0, "%s", err.msg);
  bs_sim *s = make_sim(sc);
  stop_flag = 0, grads = 0, stop_grad = g1 + (g2 - g1) / 2;
  bs_sim_run_opts o = {.on_frame = remember, .ctx = &w, .stop = &stop_flag};
  cr_assert_eq(bs_sim_run_with(s, &o, &T, &err), BS_SIM_STOPPED);
  cr_expect(grads < g2, "%d gradient evaluations: the solve ran to its end (%d)", grads, g2);
  cr_expect_eq(s->steps[0].st.min.reason, BS_MIN_STOPPED, "%s", s->steps[0].st.min.reason_text);
  expect_at_frame_1(s, &w);
  stop_flag = 0, stop_grad = -1;
  expect_same_end(s, ref, &o, &T);
  cr_expect_eq(T.iterations, Tref.iterations);
  tear_down(&w, &s, &ref, &sc);
}

Test(sim_stop, restore_checks_its_input) {
  bs_scene *sc = bs_test_box_scene(3, 24.0, 1);
  bs_sim *s = make_sim(sc);
  bs_error err;
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  double *x = malloc(sizeof(double) * n3), *v = calloc(n3, sizeof(double));
  memcpy(x, s->x0, sizeof(double) * n3);
  cr_expect_eq(bs_sim_restore(s, 4, x, v, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "frame 4 is outside"), "%s", err.msg);
  v[7] = NAN;
  cr_expect_eq(bs_sim_restore(s, 2, x, v, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "not finite at vertex 2"), "%s", err.msg);
  v[7] = 0.25;
  cr_expect_eq(bs_sim_restore(s, 2, x, v, &err), 0, "%s", err.msg);
  cr_expect_eq(s->frame, 2);
  cr_expect_eq(s->time, 2 / 24.0);
  cr_expect_eq(s->v[7], 0.25);
  free(x);
  free(v);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* bs_sim_take_step: frame 1 taken one step at a time, and frame 2 begun with
 * one step and completed by bs_sim_advance_frame, end where two whole frames
 * do, bit for bit, with the same frame sums; substep counts the steps taken. */
Test(sim_stop, steps_taken_one_at_a_time_give_the_whole_frames_bit_for_bit) {
  bs_scene *sc = bs_test_box_scene(3, 24.0, 3);
  bs_error err;
  sc->gravity[1] = -9.8;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  bs_sim *ref = make_sim(sc), *s = make_sim(sc);
  bs_frame_stats fr, fs;
  long iterations = 0;
  cr_assert_eq(bs_sim_advance_frame(ref, &fr, &err), 0, "%s", err.msg);
  for (int k = 0, done = 0; k < 3; k++) {
    cr_expect_eq(s->substep, k);
    cr_assert_eq(bs_sim_take_step(s, &done, &fs, &err), 0, "%s", err.msg);
    cr_expect_eq(done, k == 2, "step %d", k);
    iterations += s->steps[k].st.min.iterations;
  }
  cr_expect_eq(s->substep, 0);
  cr_expect_eq(s->frame, 1);
  cr_expect_eq(s->time, ref->time);
  cr_expect_eq(fs.iterations, fr.iterations);
  cr_expect_eq(fs.iterations, iterations);
  int done = 1;
  cr_assert_eq(bs_sim_take_step(s, &done, NULL, &err), 0, "%s", err.msg);
  cr_expect_eq(done, 0);
  cr_expect_eq(s->substep, 1);
  cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_advance_frame(ref, &fr, &err), 0, "%s", err.msg);
  cr_expect_eq(s->substep, 0);
  cr_expect_eq(s->frame, 2);
  cr_expect_eq(fs.iterations, fr.iterations);
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  cr_expect_eq(memcmp(s->x, ref->x, sizeof(double) * n3), 0, "x differs");
  cr_expect_eq(memcmp(s->v, ref->v, sizeof(double) * n3), 0, "v differs");
  bs_sim_destroy(&s);
  bs_sim_destroy(&ref);
  bs_scene_destroy(&sc);
}
