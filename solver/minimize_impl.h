/* minimize_impl.h — internals shared by minimize.c, linesearch.c and newton.c
 * (not a public header: include bs_minimize.h). */
#ifndef BS_MINIMIZE_IMPL_H
#define BS_MINIMIZE_IMPL_H

#include "bs_minimize.h"
#include "bs_vecops.h"

#define BS_MIN_TEXT 512

struct bs_minimizer {
  int32_t n;                  /* blocks                                              */
  int64_t n3;                 /* 3n                                                  */
  bs_minimize_opts opts;
  bs_bsr *H;                  /* Hessian storage with the pattern of create          */
  bs_linsolve *lin[BS_LIN_KINDS]; /* workspaces by bs_lin_kind (CG and MINRES always)    */
  int amg_reset;              /* 1: set up the AMG before the next solve             */
  int amg_calls;              /* bs_minimize calls started since the last setup      */
  double g0_norm;             /* ||g|| at the first iterate of the current solve (sigma_auto) */
  double tau;                 /* tau_eff of the current solve (bs__tolerance)         */
  int cg_cap;                 /* Krylov iterations per system of the current solve     */
  int floor_run;              /* noise-level iterations in a row (rounding floor watch) */
  double floor_best;          /* ||g|| at the first of them (or the last halving)       */
  double g_prev, eta_prev;    /* ||g|| and the CG tolerance of the previous iteration   */
  int prev_full;              /* the previous solve converged by full steps only       */
  double prev_eta;            /* and its last forcing term                              */
  int all_full;               /* every iteration of this solve so far was full          */
  int last_full;              /* the previous iteration took the full Newton step: a   */
                              /* Newton direction, no indefinite exit, alpha = 1 at    */
                              /* its first trial (opts.forcing_ew = 2)                 */
                              /* (opts.forcing_ew)                                       */
  int convex;                 /* 1: the next Newton system is the convexified Hessian */
                              /* (opts.convexify; reset at each solve's start)        */
  double tr_radius;           /* trust_region: the current radius Delta               */
  int64_t free_vertices;      /* vertices the mask leaves free (set at a solve's start) */
  double amg_base;            /* cost per decade of the first solve after setup (0: none yet) */
  /* 3n vectors: raw gradient of E' at x, gradient of E at x (masked, projected),
   * direction, right-hand side, trial point, raw and projected gradient there. */
  double *g_raw, *g, *d, *r, *y, *gy_raw, *gy;
  char text[BS_MIN_TEXT];     /* stats.reason_text points here                      */
  int has_vops;               /* 1: vops set (bs_minimizer_set_vecops)               */
  volatile sig_atomic_t *stop; /* bs_minimizer_set_stop's flag, or NULL                */
  bs_vecops vops;
};

/* Through m->vops when set (vecops.c): a.b over 3n, "flag on some process",
 * a sum over the processes; else the local values. */
double bs__mdot(const bs_minimizer *m, const double *a, const double *b);
int bs__many(const bs_minimizer *m, int flag);
double bs__msum(const bs_minimizer *m, double v);

/* Vector kernels over N = 3n doubles (OpenMP, static schedule). */
double bs__dot(int64_t N, const double *a, const double *b);
/* Copies src to dst, zeroing the dofs of fixed vertices. */
void bs__mask_copy(int32_t n, const uint8_t *mask, const double *src, double *dst);
/* dst_v = src_v for every fixed vertex v (no-op when mask is NULL). */
void bs__restore_fixed(int32_t n, const uint8_t *mask, const double *src, double *dst);
/* Index of the first non-finite entry on a free vertex, -1 if none. */
int64_t bs__first_nonfinite(int32_t n, const uint8_t *mask, const double *v);

/* Validates options; BS_EINPUT names the field. */
int bs__opts_check(const bs_minimize_opts *o, bs_error *err);
/* Common argument checks of bs_minimize / bs_newton. */
int bs__obj_check(const bs_minimizer *m, const bs_objective *obj, const double *x, bs_error *err);
/* Sets reason and a formatted reason text (stored in m->text). */
/* What a linear solve's status rc (its error in e2) means for iteration it:
 * 0 go on; 1 the solve's system was not finite (reason BS_MIN_NONFINITE
 * set); else rc itself (< 0), with err = e2 prefixed "WHO iteration IT:
 * SOLVER solve". */
int bs__solve_outcome(bs_minimizer *m, bs_minimize_stats *st, int rc, const bs_error *e2, int it, const char *who,
                      const char *solver, bs_error *err);

void bs__set_reason(bs_minimizer *m, bs_minimize_stats *st, bs_min_reason r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* 1 with st's reason BS_MIN_STOPPED when m's stop flag is set (iteration it
 * at ||g|| = gnorm), else 0. */
int bs__stopped(bs_minimizer *m, bs_minimize_stats *st, int it, double gnorm);

/* Projects x in place with the objective's hook (if any), keeping fixed dofs at
 * their values in `fixed_src` (which may alias nothing in x). Timed into t_eval. */
void bs__project(const bs_objective *obj, double *x, const double *fixed_src, bs_minimize_stats *st);

/* Gradient of E' at x into m->g_raw (E into *E). Returns 0 if evaluable and
 * finite; otherwise 1 and *bad is the first non-finite dof (-1 for E or a
 * failed call). Timed into t_eval. */
int bs__gradient(bs_minimizer *m, const bs_objective *obj, const double *x, double *E, double *g_raw,
                 int64_t *bad, bs_minimize_stats *st);

/* Step 1-2 of an iteration: register_active(x, g_raw), then g = mask(g_raw) and
 * project_gradient(x, g). Returns ||g||. */
double bs__constrained_gradient(bs_minimizer *m, const bs_objective *obj, const double *x,
                                const double *g_raw, double *g, bs_minimize_stats *st, int do_register);

/* Line search result. */
typedef struct bs__ls_result {
  bs_lsearch_status status; /* how it ended (bs_minimize.h)                               */
  int evals;      /* trial points                                                        */
  double alpha, phi, dphi;
  double bound;   /* the step bound the search ran under (+Inf: none)                  */
  int limited;    /* 1: the bound shortened a trial step (stats.ccd_limited)            */
} bs__ls_result;

/* Rounding level of E below which changes of E are not resolved. */
double bs__noise_level(double E);
/* tau_eff = max(tol, rtol g0, load_rtol obj->load_norm) (bs_minimize.h). */
double bs__tolerance(const bs_minimize_opts *o, const bs_objective *obj, double g0);

/* Strong Wolfe line search along m->d from x (phi0 = E(x), dphi0 = g.d < 0)
 * on [0, amax] (amax >= 0; +Inf: no bound; bs_minimize.h "Step bound").
 * On any status but BS_LSEARCH_NO_DECREASE: m->y = P(x + alpha d), m->gy_raw
 * its raw gradient, m->gy the masked projected gradient, phi and dphi their
 * values. */
void bs__line_search(bs_minimizer *m, const bs_objective *obj, const double *x, double phi0,
                     double dphi0, double amax, bs_minimize_stats *st, bs__ls_result *res);
/* obj->max_step's bound along m->d from x (+Inf without the hook; 0 when it
 * fails or returns NaN or a negative value), timed into t_eval. */
double bs__step_bound(bs_minimizer *m, const bs_objective *obj, const double *x, bs_minimize_stats *st);

/* Step 4 (minimize.c): H d = -g on the free dofs into m->d, with the
 * forcing term of iteration it. 0, 1 when the solve produced a non-finite
 * value (reason set), or a negative error. */
int bs__newton_direction(bs_minimizer *m, const bs_objective *obj, const double *x, double gnorm, int it,
                         bs_minimize_stats *st, bs_min_iter *rec, bs_error *err);
/* The rounding-floor watch (minimize.c) for an iteration whose direction
 * predicts the decrease -dphi0: 1 (reason set) when the solve ends there. */
int bs__at_floor(bs_minimizer *m, const bs_objective *obj, bs_minimize_stats *st, int it, double E, double gnorm,
                 double dphi0, bs_direction dir);
/* The accepted iteration handed to obj->trace (before x moves to m->y). */
void bs__trace_step(const bs_minimizer *m, const bs_objective *obj, const double *x, double E, double dphi0,
                    const bs__ls_result *ls, bs_min_iter *rec);
/* Steps 4-9 of a trust-region iteration (trust_region.c, bs_minimize.h
 * "Trust region") at x with energy *E and ||g|| = gnorm (m->g, m->g_raw
 * and m->H at x): 0 when a step was taken (x, *E and m->g_raw at the new
 * point), 1 when the solve ends (reason set), < 0 an error. */
int bs__tr_iteration(bs_minimizer *m, const bs_objective *obj, double *x, double *E, double gnorm, int it,
                     bs_minimize_stats *st, bs_min_iter *rec, bs_error *err);
#endif
