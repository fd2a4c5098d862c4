/* test_extreme_util.h — shared helpers of the stability-at-the-extremes tests
 * (tests/test_extreme_*.c, issue 6): load a scene with overrides, run it
 * through the library (bs_sim_run, sim_util.h) and check the run's contract:
 *  - the state (x and v) and the frame measures (energies, min det F, depth)
 *    are finite after every frame;
 *  - every step's reason is a bs_min_reason (and its own text (bs_sim_step.reason)
 *    starts with its name), and the run either converged in every step
 *    (totals.failed 0, every reason BS_MIN_CONVERGED) or reported its failure
 *    (totals.failed = the steps not converged > 0, with the first failed
 *    frame and step and a reason text naming why: max_iter, stalled,
 *    line_search, nonfinite). */
#ifndef BS_TEST_EXTREME_UTIL_H
#define BS_TEST_EXTREME_UTIL_H

#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim_util.h"

typedef struct ext_run {
  long steps, failed;      /* steps run and steps with a non-converged reason          */
  long totals_failed;      /* bs_run_totals.failed                                      */
  long newton;             /* Newton iterations summed over the steps                   */
  int frames;              /* frames after frame 0                                      */
  int last_inverted;       /* inverted tets after the last frame                        */
  int max_penetrating;     /* max over frames >= 1 of the vertices inside obstacles     */
  int first_clean;         /* first frame >= 1 with no inverted tet (-1: none)          */
  double last_min_detF;    /* min det F after the last frame                            */
  double max_grad;         /* largest final |grad E| of a step                          */
  char reason[256];        /* first failure reason, else the last step's reason         */
} ext_run;

static inline void ext_run_free(ext_run *r) { (void)r; }

/* The reason names of bs_min_reason (solver/bs_minimize.h) that end a failed step. */
static inline int ext_failure_reason(const char *s) {
  static const char *const names[] = {"max_iter:", "stalled:", "line_search:", "nonfinite:", "steps_done:", "diverged:"};
  for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
    if (!strncmp(s, names[i], strlen(names[i]))) return 1;
  return 0;
}

/* Runs SCENE with the overrides SETS (space-separated "key=value") and checks
 * the contract above. */
static inline ext_run ext_run_scene(const char *scene, const char *sets, const char *tag) {
  ext_run r;
  memset(&r, 0, sizeof r);
  sim_rec rec;
  bs_run_totals T;
  sim_run_scene(scene, sets, NULL, &rec, &T, 0, NULL);
  cr_assert(!rec.nonfinite, "%s: %s", tag, rec.nonfinite_msg);
  cr_assert(!rec.bad_reason, "%s: no known reason: %s", tag, rec.bad_reason_msg);
  r.steps = rec.steps;
  r.failed = rec.failed;
  r.totals_failed = T.failed;
  r.newton = rec.newton;
  r.frames = rec.frames;
  r.last_inverted = rec.last_inverted;
  r.max_penetrating = rec.max_penetrating;
  r.first_clean = rec.first_clean;
  r.last_min_detF = rec.last_min_detF;
  r.max_grad = rec.max_grad;
  snprintf(r.reason, sizeof r.reason, "%s", rec.reason);
  cr_assert(r.steps > 0, "%s: no step ran", tag);
  cr_assert_eq(T.steps, r.steps, "%s: totals count %ld steps, the frames %ld", tag, T.steps, r.steps);
  cr_assert_eq(T.failed, r.failed, "%s: totals say %ld failed steps, the step reasons %ld", tag, T.failed, r.failed);
  cr_assert_eq(rec.failed_flag, r.failed, "%s: %ld steps flagged failed, %ld not converged", tag, rec.failed_flag,
               r.failed);
  if (r.failed > 0) {
    cr_assert(T.first_fail_frame >= 1 && T.first_fail_frame <= r.frames && T.first_fail_step >= 0,
              "%s: first failure at frame %d step %d", tag, T.first_fail_frame, T.first_fail_step);
    cr_assert(ext_failure_reason(T.first_fail_reason), "%s: the first failure's reason names no cause: '%s'", tag,
              T.first_fail_reason);
  }
  cr_log_info("%-44s steps %3ld  failed %3ld  Newton/step %6.1f  max|gradE| %9.2e  last inverted %4d  "
              "first clean %3d  penetrating %d  [%s]\n",
              tag, r.steps, r.failed, (double)r.newton / (double)r.steps, r.max_grad, r.last_inverted, r.first_clean,
              r.max_penetrating, r.reason);
  return r;
}

/* The paper's figures 8 and 9 at test size: SCENE (random_cube or point_cube) on
 * 4x4x4 cells with MODEL at Young's modulus E, for as many frames as the paper's
 * recovery times allow at that stiffness (1e4 Pa: 60 frames; 1e5: 15; stiffer:
 * 3). The run must keep the contract and end with no inverted tet. */
static inline void ext_recover(const char *scene, const char *model, const char *E) {
  double e = strtod(E, NULL);
  int frames = e < 3e4 ? 60 : e < 1e6 ? 15 : 3;
  char path[512], sets[512], tag[96];
  snprintf(path, sizeof path, "%s/data/scenes/%s.json", BS_SOURCE_DIR, scene);
  snprintf(sets, sizeof sets,
           "time.frames=%d bodies.0.box.cells=[4,4,4] bodies.0.material.model=%s bodies.0.material.youngs=%s", frames,
           model, E);
  snprintf(tag, sizeof tag, "%s_%s_E%s", scene, model, E);
  ext_run r = ext_run_scene(path, sets, tag);
  cr_expect_eq(r.last_inverted, 0, "%s %s E=%s: %d tets still inverted after %d frames (min det F %g) [%s]", scene,
               model, E, r.last_inverted, r.frames, r.last_min_detF, r.reason);
  ext_run_free(&r);
}

#endif
