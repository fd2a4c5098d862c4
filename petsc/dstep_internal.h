/* dstep_internal.h — private to petsc/: the petsc backend of the integrator
 * (bs_step_backend.h), shared by dstep.c (creation, the vector operations,
 * the linear solver) and dstep_run.c (the backend's evaluations and hooks). */
#ifndef BS_DSTEP_INTERNAL_H
#define BS_DSTEP_INTERNAL_H

#include "bs_dstep.h"

struct bs_dintegrator {
  bs_integrator *integ;        /* the one integrator (physics/bs_step.h)       */
  bs_dfem *df;
  int n_all;                /* the dfem's terms when created: restored      */
  bs_term *const *all;      /* after every evaluation of a list             */
  int statics_all;
  bs_bsr *diag;             /* the minimizer's (unused) Hessian pattern     */
  bs_vecops vecops;
  bs_dlin *lin;
  bs_dpc pc;                /* the preconditioner of min.linear             */
  double amg_dt;            /* GAMG: the dt its matrix was built for (-1: none) */
  double *mass;             /* per local vertex, summed over the ranks      */
  double *x_hat_m, *x_n_m;  /* local-mesh order: what the terms read        */
  double *hxm, *hgm;        /* local-mesh copies of x and g for the hooks   */
  double *gtmp;             /* a local vector: the gradient for a projected Hessian */
  const bs_step_hooks *hess_hooks; /* the point of the projected Hessian    */
  const double *hess_x, *hess_g;
  int cb_rc;                /* the first error inside a vector operation    */
  bs_error cb_err;
};

/* The backend's evaluations, hooks and reductions into B (dstep_run.c). */
void bs__dstep_backend_ops(bs_step_backend *B);

#endif
