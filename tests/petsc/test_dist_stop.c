/* test_dist_stop: a stop request on the petsc backend (bs_dsim_set_stop),
 * raised on rank 0 only: every rank stops at the same point (no rank waits
 * in a collective call the others never make); a frame cut short is undone
 * bit for bit; the minimizer's check between Newton iterations is collective
 * (every rank's solve ends with BS_MIN_STOPPED); and the run continued after
 * the flag is cleared ends bit for bit where a run never stopped ends, frames
 * (the stretched cube) and statics (the cantilever) alike. */
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dsim.h"
#include "dist_check.h"

static volatile sig_atomic_t flag;

static bs_dsim *make(const char *path, int nsets, const char **sets, bs_scene **sc) {
  bs_error err = {0};
  bs_dsim *d = NULL;
  CHECK_OK(bs_scene_load(path, nsets, sets, sc, &err), err);
  if (*sc) CHECK_OK(bs_dsim_create(*sc, &d, &err), err);
  return d;
}

static size_t n3(const bs_dsim *d) { return 3 * (size_t)d->mesh->n_vertices; }

static void expect_state(const bs_dsim *d, const double *x, const double *v, const char *what) {
  CHECK(memcmp(d->x, x, n3(d) * sizeof(double)) == 0, "%s: x differs", what);
  if (v) CHECK(memcmp(d->v, v, n3(d) * sizeof(double)) == 0, "%s: v differs", what);
}

/* With the flag raised on rank 0 only, one step's solve through the
 * integrator: every rank's ends with BS_MIN_STOPPED at its first check.
 * x, v and the carry are put back afterwards. */
static void expect_collective_solve_stop(bs_dsim *d) {
  bs_error err = {0};
  double *x = malloc(n3(d) * sizeof(double)), *v = malloc(n3(d) * sizeof(double));
  memcpy(x, d->x, n3(d) * sizeof(double));
  memcpy(v, d->v, n3(d) * sizeof(double));
  bs_min_carry c;
  bs_dintegrator_get_carry(d->integrator, &c);
  bs_step_stats st;
  CHECK_OK(bs_dintegrator_step(d->integrator, d->time, d->scene->dt, x, v, &st, &err), err);
  CHECK(st.min.reason == BS_MIN_STOPPED, "the solve ended with reason %d, not stopped", (int)st.min.reason);
  CHECK(st.min.iterations == 0, "%d iterations before the stop", st.min.iterations);
  bs_dintegrator_set_carry(d->integrator, &c);
  free(x), free(v);
}

/* d's state (x, v, time, frame, the minimizer's carry), to put back: one
 * dsim is compared with itself (two dsims of a scene may partition its mesh
 * differently, and so differ in their local vectors and round-off). */
typedef struct state {
  double *x, *v, time;
  int frame;
  bs_min_carry carry;
} state;

static void save(const bs_dsim *d, state *s) {
  s->x = malloc(n3(d) * sizeof(double));
  s->v = malloc(n3(d) * sizeof(double));
  memcpy(s->x, d->x, n3(d) * sizeof(double));
  memcpy(s->v, d->v, n3(d) * sizeof(double));
  s->time = d->time;
  s->frame = d->frame;
  bs_dintegrator_get_carry(d->integrator, &s->carry);
}

static void put_back(bs_dsim *d, const state *s) {
  memcpy(d->x, s->x, n3(d) * sizeof(double));
  memcpy(d->v, s->v, n3(d) * sizeof(double));
  d->time = s->time;
  d->frame = s->frame;
  bs_dintegrator_set_carry(d->integrator, &s->carry);
}

static void forget(state *s) { free(s->x), free(s->v); }

static void stretched_cube_frames(void) {
  const char *sets[] = {"time.frames=3"};
  bs_scene *sc = NULL;
  bs_dsim *d = make("data/scenes/cube_stretch.json", 1, sets, &sc);
  if (!d) goto done;
  bs_error err = {0};
  bs_frame_stats fs;
  state s1, s3;
  CHECK_OK(bs_dsim_set_stop(d, &flag, &err), err);
  flag = 0;
  CHECK_OK(bs_dsim_advance_frame(d, &fs, &err), err);
  save(d, &s1);
  for (int f = 1; f < 3; f++) CHECK_OK(bs_dsim_advance_frame(d, &fs, &err), err);
  save(d, &s3); /* the run never stopped */
  put_back(d, &s1);
  flag = bs_dist_rank() == 0;
  int rc = bs_dsim_advance_frame(d, &fs, &err);
  CHECK(rc == BS_SIM_STOPPED, "frame 2 with rank 0's flag: status %d (%s), not BS_SIM_STOPPED", rc, err.msg);
  CHECK(d->frame == 1 && d->time == s1.time, "frame %d at t %g after the stop, not frame 1", d->frame, d->time);
  expect_state(d, s1.x, s1.v, "after the stop");
  expect_collective_solve_stop(d);
  flag = 0;
  for (int f = 1; f < 3; f++) CHECK_OK(bs_dsim_advance_frame(d, &fs, &err), err);
  CHECK(d->frame == 3 && d->time == s3.time, "frame %d at t %g", d->frame, d->time);
  expect_state(d, s3.x, s3.v, "continued to frame 3 against the run never stopped");
  forget(&s1), forget(&s3);
done:
  bs_dsim_destroy(&d);
  bs_scene_destroy(&sc);
}

static void cantilever_statics(void) {
  const char *sets[] = {"qoi=[]", "output.dir="};
  bs_scene *sc = NULL;
  bs_dsim *d = make("data/scenes/beam_sag.json", 2, sets, &sc);
  if (!d) goto done;
  bs_error err = {0};
  bs_frame_stats fs;
  state s0, s1;
  save(d, &s0);
  CHECK_OK(bs_dsim_statics(d, &fs, &err), err);
  save(d, &s1); /* the solve never stopped */
  put_back(d, &s0);
  CHECK_OK(bs_dsim_set_stop(d, &flag, &err), err);
  flag = bs_dist_rank() == 0;
  int rc = bs_dsim_statics(d, &fs, &err);
  CHECK(rc == BS_SIM_STOPPED, "statics with rank 0's flag: status %d (%s), not BS_SIM_STOPPED", rc, err.msg);
  CHECK(d->frame == 0, "frame %d after the stop", d->frame);
  expect_state(d, s0.x, s0.v, "statics stopped");
  bs_step_stats st; /* the integrator's statics: every rank's first load step stops, the others are not taken */
  CHECK_OK(bs_dintegrator_static(d->integrator, 0.0, 3, d->x, &st, &err), err);
  CHECK(st.min.reason == BS_MIN_STOPPED && st.min.iterations == 0, "statics: reason %d after %d iterations",
        (int)st.min.reason, st.min.iterations);
  put_back(d, &s0);
  flag = 0;
  CHECK_OK(bs_dsim_statics(d, &fs, &err), err);
  CHECK(d->frame == 1 && fs.steps[0].st.min.reason == BS_MIN_CONVERGED, "frame %d, reason %d", d->frame,
        (int)fs.steps[0].st.min.reason);
  expect_state(d, s1.x, s1.v, "statics solved after the stop against the solve never stopped");
  forget(&s0), forget(&s1);
done:
  bs_dsim_destroy(&d);
  bs_scene_destroy(&sc);
}

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"stretched_cube_frames", stretched_cube_frames},
                                    {"cantilever_statics", cantilever_statics}};
  return dist_check_main(argc, argv, tests, 2);
}
