/* dstep_internal.h — private to petsc/: the distributed integrator's state,
 * shared by dstep.c (creation, the objective) and dstep_run.c (the solves). */
#ifndef BS_DSTEP_INTERNAL_H
#define BS_DSTEP_INTERNAL_H

#include "bs_dstep.h"

struct bs_dintegrator {
  bs_dfem *df;
  bs_step_data *step;
  bs_integrator_opts opts;
  uint8_t *mask;
  bs_script_fn script;
  void *script_ctx;
  int n_terms;              /* the dfem's terms when created               */
  bs_term *const *terms;
  bs_term **potential;      /* every term but inertia (f(xⁿ))              */
  int n_potential;
  bs_minimizer *min;
  bs_bsr *diag;             /* the minimizer's (unused) Hessian pattern     */
  bs_dlin *lin;
  bs_dpc pc;                /* the preconditioner of min.linear             */
  double amg_dt;            /* GAMG: the dt its matrix was built for (-1: none) */
  double *x_hat_m, *x_n_m;  /* local-mesh order: what the terms read        */
  double *x_n, *g1, *g2, *grad, *mass; /* local vectors; mass 1 per vertex */
  bs_term **external;       /* the external loads (load_rtol's norm)        */
  int n_external;
  bs_step_hooks hooks;      /* constraint hooks on the local mesh (or none) */
  double *hxm, *hgm;        /* local-mesh copies of x and g for the hooks   */
  const double *hess_x, *hess_g; /* the point of the projected Hessian      */
  int cb_rc;                /* the first error inside a callback            */
  bs_error cb_err;
};

/* The objective the minimizer sees (dstep.c). */
void bs__dstep_objective(bs_dintegrator *D, bs_objective *o);

/* A callback's status kept as the first error (dstep.c). */
void bs__dstep_note(bs_dintegrator *D, int rc);

/* The objective's constraint callbacks (project, register_active,
 * project_gradient, hessian_g) when hooks are set (dstep_hooks.c). */
void bs__dstep_hook_objective(bs_dintegrator *D, bs_objective *o);

/* x <- P(x) (a local vector, made consistent) when hooks are set; an error
 * goes to D->cb_rc / cb_err (dstep_hooks.c). */
void bs__dstep_project(bs_dintegrator *D, double *x);

#endif
