/* Stability at the extremes (issue 6): Young's modulus from 1e2 to 1e12 Pa at
 * the scene's density (1000 kg/m^3), and Poisson's ratio up to 0.499 (at a soft
 * and a stiff modulus), on cube_stretch with 4x4x4 cells for three frames at one
 * step per 24 Hz frame. The optimization integrator must converge in every step
 * with no inverted tet; the Newton baseline is held to the contract of
 * test_extreme_util.h (finite state, convergence or a reported failure with its
 * reason) and its outcome logged. */
#define _POSIX_C_SOURCE 200809L
#include "test_extreme_util.h"

#define CUBE BS_SOURCE_DIR "/data/scenes/cube_stretch.json"

static const char *const youngs[] = {"1e2", "1e4", "1e6", "1e8", "1e10", "1e12"};
static const char *const poisson[] = {"0.45", "0.49", "0.499"};
static const char *const poisson_youngs[] = {"1e5", "1e9"};

static ext_run run_material(const char *method, const char *E, const char *nu) {
  char sets[512], tag[96];
  snprintf(sets, sizeof sets,
           "bodies.0.box.cells=[4,4,4] solver.method=%s time.frames=3 bodies.0.material.youngs=%s "
           "bodies.0.material.poisson=%s solver.max_iterations=%d",
           method, E, nu, strcmp(method, "newton") ? 200 : 30);
  snprintf(tag, sizeof tag, "cube_stretch_%s_E%s_nu%s", method, E, nu);
  return ext_run_scene(CUBE, sets, tag);
}

Test(extreme_material, youngs_optimization_converges, .timeout = 600) {
  for (size_t i = 0; i < sizeof youngs / sizeof youngs[0]; i++) {
    ext_run r = run_material("optimization", youngs[i], "0.3");
    cr_expect_eq(r.failed, 0, "E=%s: %ld failed steps [%s]", youngs[i], r.failed, r.reason);
    cr_expect_eq(r.last_inverted, 0, "E=%s: %d inverted tets", youngs[i], r.last_inverted);
    ext_run_free(&r);
  }
}

Test(extreme_material, youngs_newton_reports, .timeout = 600) {
  for (size_t i = 0; i < sizeof youngs / sizeof youngs[0]; i++) {
    ext_run r = run_material("newton", youngs[i], "0.3");
    ext_run_free(&r);
  }
}

Test(extreme_material, poisson_optimization_converges, .timeout = 600) {
  for (size_t j = 0; j < sizeof poisson_youngs / sizeof poisson_youngs[0]; j++)
    for (size_t i = 0; i < sizeof poisson / sizeof poisson[0]; i++) {
      ext_run r = run_material("optimization", poisson_youngs[j], poisson[i]);
      cr_expect_eq(r.failed, 0, "E=%s nu=%s: %ld failed steps [%s]", poisson_youngs[j], poisson[i], r.failed,
                   r.reason);
      cr_expect_eq(r.last_inverted, 0, "E=%s nu=%s: %d inverted tets", poisson_youngs[j], poisson[i],
                   r.last_inverted);
      ext_run_free(&r);
    }
}

Test(extreme_material, poisson_newton_reports, .timeout = 600) {
  for (size_t j = 0; j < sizeof poisson_youngs / sizeof poisson_youngs[0]; j++)
    for (size_t i = 0; i < sizeof poisson / sizeof poisson[0]; i++) {
      ext_run r = run_material("newton", poisson_youngs[j], poisson[i]);
      ext_run_free(&r);
    }
}
