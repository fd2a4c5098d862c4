/* dstep_hooks.c — the constraint hooks of bs_step.h (e.g. bs_obstacles_hooks
 * on dfem->fem) under the distributed integrator (bs_dintegrator_set_hooks):
 * each call on local-mesh copies of the local vectors x and g, its result
 * written back and made consistent on the ghosts; the Hessian projection on
 * each rank's partial Hessian before its assembly. */
#include <string.h>

#include "dstep_internal.h"

int bs_dintegrator_set_hooks(bs_dintegrator *D, const bs_step_hooks *hooks, bs_error *err) {
  if (hooks && hooks->post_solve)
    return bs_error_set(err, BS_EINPUT, "distributed integrator: post-solve hooks (friction) are not supported");
  if (hooks) D->hooks = *hooks;
  else memset(&D->hooks, 0, sizeof D->hooks);
  return BS_OK;
}

static void to_hook(bs_dintegrator *D, const double *x, const double *g) {
  bs_dfem_mesh_vector(D->df, x, D->hxm);
  if (g) bs_dfem_mesh_vector(D->df, g, D->hgm);
}

void bs__dstep_project(bs_dintegrator *D, double *x) {
  if (!D->hooks.project) return;
  to_hook(D, x, NULL);
  D->hooks.project(D->hxm, D->hooks.ctx);
  bs_dfem_from_mesh_vector(D->df, D->hxm, x);
  bs__dstep_note(D, bs_dfem_consistent(D->df, x, &D->cb_err));
}

static void obj_project(double *x, void *ctx) { bs__dstep_project(ctx, x); }

static void obj_register(const double *x, const double *g, void *ctx) {
  bs_dintegrator *D = ctx;
  to_hook(D, x, g);
  D->hooks.register_active(D->hxm, D->hgm, D->hooks.ctx);
}

static void obj_project_gradient(const double *x, double *g, void *ctx) {
  bs_dintegrator *D = ctx;
  to_hook(D, x, g);
  D->hooks.project_gradient(D->hxm, D->hgm, D->hooks.ctx);
  bs_dfem_from_mesh_vector(D->df, D->hgm, g);
  bs__dstep_note(D, bs_dfem_consistent(D->df, g, &D->cb_err));
}

/* Inside bs_dfem_hessian_model: the rank's partial Hessian projected at the
 * point obj_hessian_g was given. */
static void project_partial(bs_bsr *Hm, void *ctx) {
  bs_dintegrator *D = ctx;
  to_hook(D, D->hess_x, D->hess_g);
  D->hooks.project_hessian(D->hxm, D->hgm, Hm, D->hooks.ctx);
}

/* The Hessian (the terms' secant models with opts.penalty_secant), projected
 * by the hook when there is one. */
static int obj_hessian_g(const double *x, const double *g_raw, bs_bsr *H, void *ctx) {
  (void)H; /* the minimizer's (unused) matrix: the dfem assembles its own */
  bs_dintegrator *D = ctx;
  D->hess_x = x, D->hess_g = g_raw;
  int rc = bs_dfem_hessian_model(D->df, x, D->opts.penalty_secant ? g_raw : NULL, D->mask,
                                 D->hooks.project_hessian ? project_partial : NULL, D, &D->cb_err);
  bs__dstep_note(D, rc);
  return rc ? 1 : 0;
}

void bs__dstep_hook_objective(bs_dintegrator *D, bs_objective *o) {
  const bs_step_hooks *h = &D->hooks;
  o->project = h->project ? obj_project : NULL;
  o->register_active = h->register_active ? obj_register : NULL;
  o->project_gradient = h->project_gradient ? obj_project_gradient : NULL;
  o->hessian_g = h->project_hessian || D->opts.penalty_secant ? obj_hessian_g : NULL;
}
