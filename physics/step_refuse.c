/* step_refuse.c — the one list of what a backend of the integrator does not
 * run (bs_step_refuse, bs_step_backend.h). */
#include <stdio.h>

#include "bs_step.h"
#include "bs_step_backend.h"

/* What no backend runs with a second-order integrator (bs_step.h). */
static int refuse_integrator(const bs_step_features *f, const char *where, bs_error *err) {
  if (f->integrator == BS_INTEGRATOR_BACKWARD_EULER || f->postprocess_obstacle < 0) return 0;
  return bs_error_set(err, BS_EINPUT,
                      "%s: obstacles.%d.collision: postprocess collisions move x after the solve, which the history "
                      "of solver.integrator %s does not follow (use penalty or constraint)",
                      where, f->postprocess_obstacle, bs_time_integrator_name((bs_time_integrator)f->integrator));
}

int bs_step_refuse(const bs_step_features *f, unsigned caps, const char *where, const char *name, bs_error *err) {
  int rc = refuse_integrator(f, where, err);
  if (rc) return rc;
  char key[64] = "";
  const char *why = NULL;
  if (f->self_collision && !(caps & BS_STEP_CAN_SELF_COLLISION))
    snprintf(key, sizeof key, "self_collision"), why = "self-collision is not supported";
  else if (f->postprocess_obstacle >= 0 && !(caps & BS_STEP_CAN_POST_SOLVE))
    snprintf(key, sizeof key, "obstacles.%d.collision", f->postprocess_obstacle),
        why = "postprocess collisions are not supported";
  else if (f->friction_obstacle >= 0 && !(caps & BS_STEP_CAN_POST_SOLVE))
    snprintf(key, sizeof key, "obstacles.%d.friction", f->friction_obstacle), why = "friction is not supported";
  else if (f->post_solve && !(caps & BS_STEP_CAN_POST_SOLVE))
    snprintf(key, sizeof key, "post-solve hooks"), why = "friction and postprocess collisions are not supported";
  else if (f->method != BS_METHOD_OPTIMIZATION && !(caps & BS_STEP_CAN_NEWTON))
    snprintf(key, sizeof key, "solver.method"), why = "only the optimization integrator runs";
  else if (f->linear != BS_LIN_CG && f->linear != BS_LIN_PCG && f->linear != BS_LIN_AMG && !(caps & BS_STEP_CAN_DIRECT))
    snprintf(key, sizeof key, "solver.linear"), why = "only cg, pcg and amg are available";
  else if (f->globalization != BS_GLOBAL_LINE_SEARCH && !(caps & BS_STEP_CAN_TRUST_REGION))
    snprintf(key, sizeof key, "solver.globalization"), why = "only line_search runs (Steihaug's CG is serial)";
  else if (f->linear == BS_LIN_AMG && !f->amg_at_rest && !(caps & BS_STEP_CAN_AMG_CURRENT))
    snprintf(key, sizeof key, "solver.amg_matrix"), why = "the AMG is built from the rest-state Hessian only (\"rest\")";
  else if (f->trace && !(caps & BS_STEP_CAN_TRACE))
    snprintf(key, sizeof key, "trace"), why = "the per-iteration trace is not supported";
  if (!why) return 0;
  return bs_error_set(err, BS_EINPUT, "%s: %s: %s with solver.backend %s", where, key, why, name);
}
