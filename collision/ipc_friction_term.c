/* ipc_friction_term.c — IPC's lagged smoothed friction between surfaces in
 * barrier self-contact (bs_ipc_friction.h): the barrier's pairs lagged at
 * xⁿ, per-pair energies in parallel, summed and scattered in pair order. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "bs_ipc.h"
#include "bs_ipc_friction.h"
#include "bs_ipc_term.h"
#include "ipc_internal.h"

#define PAR_MIN 64 /* pairs below which loops run on one thread */
#define PB 13      /* per-pair buffer: energy, gradient (3), Hessian (9) */

/* A pair lagged at xⁿ (bs_ipc_friction.h). */
typedef struct fr_pair {
  int32_t v[4];
  int32_t ee;
  double w[4];   /* closest-point weights          */
  double y0[12]; /* the 4 vertices at xⁿ           */
  double T[6];   /* tangent basis, 3 x 2 row-major */
  double lambda; /* normal force (N)               */
} fr_pair;

typedef struct fr_data {
  bs_term *barrier;
  double mu, eps_v, eps;
  int nthreads;
  fr_pair *p;    /* the lagged pairs */
  int64_t n, cap;
  double *buf;   /* PB per pair      */
  int64_t cap_buf;
  bs_ipc_friction_stats st;
} fr_data;

/* ---- lagging ----------------------------------------------------------------- */

/* Pair q at xⁿ into c (c->lambda = 0: left out). rest: the mesh's rest
 * positions (the mollifier's eps_x). */
static void lag_pair(const bs_ipc_pair *q, const double *xn, const double *rest, double kappa, double dhat,
                     fr_pair *c) {
  memcpy(c->v, q->v, sizeof c->v);
  c->ee = q->ee;
  c->lambda = 0;
  double *y = c->y0, d2, m = 1;
  bs__ipc_gather(xn, q->v, y);
  if (q->ee) {
    double r[12];
    bs__ipc_gather(rest, q->v, r);
    d2 = bs_ipc_ee_d2_full(y, y + 3, y + 6, y + 9, NULL, NULL, NULL);
    bs_ipc_ee_closest_weights(y, y + 3, y + 6, y + 9, c->w);
    m = bs_ipc_mollifier(y, y + 3, y + 6, y + 9, bs_ipc_mollifier_eps(r, r + 3, r + 6, r + 9), NULL, NULL);
  } else {
    d2 = bs_ipc_pt_d2_full(y, y + 3, y + 6, y + 9, NULL, NULL, NULL);
    bs_ipc_pt_closest_weights(y, y + 3, y + 6, y + 9, c->w);
  }
  double bb[3], n[3] = {0, 0, 0};
  if (bs_ipc_barrier(d2, dhat * dhat, bb)) return;
  for (int a = 0; a < 4; a++)
    for (int k = 0; k < 3; k++) n[k] += c->w[a] * y[3 * a + k];
  const double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(l > 0) || !isfinite(l)) return;
  for (int k = 0; k < 3; k++) n[k] /= l;
  bs_ipc_tangent_basis(n, c->T);
  const double lambda = kappa * -bb[1] * 2 * sqrt(d2) * m;
  if (lambda > 0 && isfinite(lambda)) c->lambda = lambda;
}

/* The barrier's pairs at xⁿ lagged (in parallel), those with lambda > 0
 * kept in their order. */
static int lag(fr_data *d, const bs_term *t, bs_error *err) {
  d->n = 0;
  d->eps = 0;
  d->st.pairs_pt = d->st.pairs_ee = 0;
  d->st.normal_force = 0;
  const bs_step_data *step = t->step;
  if (!step || !step->x_n || !(step->dt > 0)) return 0;
  const bs_ipc_pair *q = NULL;
  int64_t n = 0;
  int st = bs_term_ipc_pairs(d->barrier, step->x_n, &q, &n, err);
  if (st) return st;
  bs_ipc_stats bst;
  if ((st = bs_term_ipc_stats(d->barrier, &bst, err))) return st;
  if (bs__ipc_grow((void **)&d->p, &d->cap, n, sizeof(fr_pair)) ||
      bs__ipc_grow((void **)&d->buf, &d->cap_buf, PB * n, sizeof(double)))
    return bs_error_set(err, BS_ENOMEM, "barrier friction: out of memory listing %lld pairs", (long long)n);
  const double *rest = t->fem->mesh->x;
#pragma omp parallel for schedule(static) num_threads(d->nthreads) if (n >= PAR_MIN)
  for (int64_t i = 0; i < n; i++) lag_pair(&q[i], step->x_n, rest, bst.kappa, bst.dhat, &d->p[i]);
  int64_t k = 0;
  for (int64_t i = 0; i < n; i++) {
    if (!(d->p[i].lambda > 0)) continue;
    if (k != i) d->p[k] = d->p[i];
    d->st.normal_force += d->p[k].lambda;
    if (d->p[k].ee) d->st.pairs_ee++;
    else d->st.pairs_pt++;
    k++;
  }
  d->n = k;
  d->eps = d->eps_v * step->dt;
  return 0;
}

static int fr_begin_step(bs_term *t, bs_error *err) { return lag(t->data, t, err); }

/* ---- evaluation ---------------------------------------------------------------- */

/* Pair c at x: energy, and the gradient (3) and Hessian (9) in its relative
 * displacement with want >= 1, 2, into b[PB]. */
static void pair_eval(const fr_data *d, const fr_pair *c, const double *x, int want, double *b) {
  double dx[3] = {0, 0, 0};
  for (int a = 0; a < 4; a++) {
    const double *p = x + 3 * (size_t)c->v[a];
    for (int k = 0; k < 3; k++) dx[k] += c->w[a] * (p[k] - c->y0[3 * a + k]);
  }
  b[0] = bs_ipc_friction_eval(c->T, dx, d->mu * c->lambda, d->eps, want >= 1 ? b + 1 : NULL,
                              want >= 2 ? b + 4 : NULL);
}

/* Every pair into d->buf (in parallel); the energy summed in pair order.
 * 0, or 1 when it is not finite. */
static int pair_loop(fr_data *d, const double *x, int want, double *E) {
  const int64_t n = d->n;
#pragma omp parallel for schedule(static) num_threads(d->nthreads) if (n >= PAR_MIN)
  for (int64_t i = 0; i < n; i++) pair_eval(d, &d->p[i], x, want, d->buf + PB * i);
  double s = 0;
  for (int64_t i = 0; i < n; i++) s += d->buf[PB * i];
  *E = s;
  return !isfinite(s);
}

static int fr_value(const bs_term *t, const double *x, double *E) {
  return pair_loop(t->data, x, 0, E) ? BS_TERM_NOT_EVALUABLE : BS_TERM_OK;
}

static int fr_gradient(const bs_term *t, const double *x, double *E, double *g) {
  fr_data *d = t->data;
  if (pair_loop(d, x, 1, E)) return BS_TERM_NOT_EVALUABLE;
  for (int64_t i = 0; i < d->n; i++) {
    const fr_pair *c = &d->p[i];
    const double *gl = d->buf + PB * i + 1;
    for (int a = 0; a < 4; a++)
      for (int k = 0; k < 3; k++) g[3 * (size_t)c->v[a] + k] += c->w[a] * gl[k];
  }
  return BS_TERM_OK;
}

static int fr_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  fr_data *d = t->data;
  double E;
  if (pair_loop(d, x, 2, &E)) return BS_TERM_NOT_EVALUABLE;
  int64_t missing = 0;
  for (int64_t i = 0; i < d->n; i++) {
    const fr_pair *c = &d->p[i];
    const double *Hl = d->buf + PB * i + 4;
    for (int a = 0; a < 4; a++)
      for (int b = 0; b < 4; b++) {
        const double s = c->w[a] * c->w[b];
        double B[9];
        for (int k = 0; k < 9; k++) B[k] = s * Hl[k];
        missing += bs_bsr_add_block(H, c->v[a], c->v[b], B) == BS_BSR_DROPPED;
      }
  }
  d->st.missing_blocks = missing;
  return BS_TERM_OK;
}

/* ---- creation -------------------------------------------------------------------- */

static void fr_free(void *p) {
  fr_data *d = p;
  if (!d) return;
  free(d->p);
  free(d->buf);
  free(d);
}

/* The Hessian is PSD as it stands (bs_ipc_friction.h). */
static const bs_term_ops fr_ops = {fr_value, fr_gradient, fr_hessian, fr_begin_step, fr_free, fr_hessian, NULL, NULL,
                                   NULL, NULL};

int bs_term_ipc_friction_create(bs_term *barrier, double mu, double eps_v, bs_term **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "barrier friction: out is NULL");
  *out = NULL;
  if (!bs_term_is_ipc(barrier)) return bs_error_set(err, BS_EINPUT, "barrier friction: not a barrier contact term");
  if (!(mu > 0) || !isfinite(mu))
    return bs_error_set(err, BS_EINPUT, "barrier friction: mu must be finite and > 0, got %g", mu);
  if (!(eps_v > 0) || !isfinite(eps_v))
    return bs_error_set(err, BS_EINPUT, "barrier friction: eps_v must be finite and > 0 (m/s), got %g", eps_v);
  fr_data *d = bs_calloc(1, sizeof *d, "the barrier friction term", err);
  if (!d) return BS_ENOMEM;
  d->barrier = barrier;
  d->mu = mu;
  d->eps_v = eps_v;
  d->st.mu = mu;
  d->nthreads = 1;
#ifdef _OPENMP
  d->nthreads = omp_get_max_threads();
#endif
  bs_term *t = calloc(1, sizeof *t);
  if (!t) {
    fr_free(d);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the barrier friction term");
  }
  t->name = "barrier_friction";
  t->kind = BS_TERM_BARRIER_CONTACT;
  t->ops = &fr_ops;
  t->fem = barrier->fem;
  t->step = barrier->step;
  t->dynamic_only = 1;
  t->hessian_extra = barrier->hessian_extra;
  t->data = d;
  *out = t;
  return 0;
}

int bs_term_is_ipc_friction(const bs_term *t) { return t && t->ops == &fr_ops; }

int bs_term_ipc_friction_stats(const bs_term *t, bs_ipc_friction_stats *out, bs_error *err) {
  if (!bs_term_is_ipc_friction(t)) return bs_error_set(err, BS_EINPUT, "not a barrier friction term");
  const fr_data *d = t->data;
  *out = d->st;
  out->eps = d->eps;
  return 0;
}
