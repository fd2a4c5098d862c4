/* Stability at the extremes (issue 6): the time step from 1/240 s to 1 s (one
 * step per second), set through time.fps with one step per frame, on
 * cube_stretch (4x4x4 cells) and on the collision scene sphere_drop (mesh size
 * 0.2 m, constraint collisions with the ground). Every run must end in a finite
 * state and either converge or report its failure and the reason (the contract
 * of test_extreme_util.h). The optimization integrator must converge in every
 * step and, on sphere_drop, leave no vertex inside the ground; the Newton
 * baseline is held to the contract only and its outcome logged. */
#define _POSIX_C_SOURCE 200809L
#include "test_extreme_util.h"

/* fps (one step per frame) and the frames that cover the end of the stretch
 * (t = 1/24 s) or the ball's impact (t = 0.05 s). */
static const struct {
  const char *fps;
  int frames;
} dts[] = {{"240", 24}, {"24", 3}, {"4", 2}, {"1", 3}};
enum { N_DT = sizeof dts / sizeof dts[0] };

#define CUBE BS_SOURCE_DIR "/data/scenes/cube_stretch.json"
#define BALL BS_SOURCE_DIR "/data/scenes/sphere_drop.json"

static ext_run run_dt(const char *scene, const char *extra, const char *method, int i, const char *name) {
  char sets[512], tag[96];
  /* The baseline is capped at 30 Newton iterations a step: where it fails at
   * large dt it does so within them and the run stays short. */
  snprintf(sets, sizeof sets,
           "%s solver.method=%s time.frames=%d time.fps=%s time.steps_per_frame=1 solver.max_iterations=%d", extra,
           method, dts[i].frames, dts[i].fps, strcmp(method, "newton") ? 200 : 30);
  snprintf(tag, sizeof tag, "%s_%s_dt1_%s", name, method, dts[i].fps);
  return ext_run_scene(scene, sets, tag);
}

Test(extreme_dt, cube_stretch_optimization_converges, .timeout = 600) {
  for (int i = 0; i < N_DT; i++) {
    ext_run r = run_dt(CUBE, "bodies.0.box.cells=[4,4,4]", "optimization", i, "cube_stretch");
    cr_expect_eq(r.failed, 0, "cube_stretch dt=1/%s s: %ld failed steps [%s]", dts[i].fps, r.failed, r.reason);
    cr_expect_eq(r.last_inverted, 0, "cube_stretch dt=1/%s s: %d inverted tets", dts[i].fps, r.last_inverted);
    ext_run_free(&r);
  }
}

Test(extreme_dt, cube_stretch_newton_reports, .timeout = 600) {
  for (int i = 0; i < N_DT; i++) {
    ext_run r = run_dt(CUBE, "bodies.0.box.cells=[4,4,4]", "newton", i, "cube_stretch");
    ext_run_free(&r);
  }
}

Test(extreme_dt, sphere_drop_optimization_converges_without_penetration, .timeout = 600) {
  for (int i = 0; i < N_DT; i++) {
    ext_run r = run_dt(BALL, "bodies.0.mesh_size=0.2", "optimization", i, "sphere_drop");
    cr_expect_eq(r.failed, 0, "sphere_drop dt=1/%s s: %ld failed steps [%s]", dts[i].fps, r.failed, r.reason);
    cr_expect_eq(r.max_penetrating, 0, "sphere_drop dt=1/%s s: %d vertices inside the ground", dts[i].fps,
                 r.max_penetrating);
    ext_run_free(&r);
  }
}

Test(extreme_dt, sphere_drop_newton_reports, .timeout = 600) {
  for (int i = 0; i < N_DT; i++) {
    ext_run r = run_dt(BALL, "bodies.0.mesh_size=0.2", "newton", i, "sphere_drop");
    cr_expect_eq(r.max_penetrating, 0, "sphere_drop newton dt=1/%s s: %d vertices inside the ground", dts[i].fps,
                 r.max_penetrating);
    ext_run_free(&r);
  }
}
