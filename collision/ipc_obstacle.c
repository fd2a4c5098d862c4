/* ipc_obstacle.c — the IPC barrier and lagged friction against obstacles'
 * level sets, and its CCD (bs_ipc_obstacle.h). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_ipc.h"
#include "bs_ipc_obstacle.h"
#include "bs_ipc_term.h"
#include "bs_svd.h"
#include "bs_vec3.h"

typedef struct ob_entry {
  const bs_levelset *ls;
  double mu, lip; /* friction coefficient, |grad phi| bound */
  int index;
} ob_entry;

/* A friction pair lagged at xⁿ: vertex, coefficient mu lambda, basis, point. */
typedef struct fr_pair {
  int32_t v;
  double mul;        /* mu lambda (N) */
  double T[6];       /* 3x2, row-major: T[2 k + j] */
  double r[3];
} fr_pair;

typedef struct obs_data {
  int32_t nv, n_sv;
  int32_t *sv;       /* free surface vertices, ascending */
  int n_ob, cap_ob;
  ob_entry *ob;
  bs_levelset_frame *frames;  /* per obstacle, at the evaluation time (a path's start) */
  bs_levelset_frame *frames1; /* per obstacle, at a path's end (set_path)                */
  bs_levelset_motion_bound *motion; /* per obstacle, over the path's times (set_path)    */
  double dhat, kappa, eps_v;
  int project, adaptive;
  double kappa_max, d2_eps, d2_prev;
  double *pe;        /* per surface vertex: energy, then 3 gradient, 9 Hessian (13) */
  uint8_t *bad;      /* per surface vertex: inside some obstacle */
  double *pmin;      /* per surface vertex: smallest phi */
  int32_t *pcount;   /* per surface vertex: pairs within dhat */
  fr_pair *fr;
  int64_t n_fr, cap_fr;
  bs_ipc_obstacle_stats st;
} obs_data;

#define PE 13

static double eval_time(const bs_term *t) { return t->step ? t->step->time : 0.0; }

static void set_frames(obs_data *d, double time) {
  for (int b = 0; b < d->n_ob; b++) bs_levelset_frame_at(d->ob[b].ls, time, &d->frames[b]);
}

/* The frames at t0 and t1 and the motions' bounds between them, once per
 * path (sweep, carry) rather than once per vertex. */
static void set_path(obs_data *d, double t0, double t1) {
  set_frames(d, t0);
  for (int b = 0; b < d->n_ob && t1 != t0; b++) { /* t1 = t0: the line search's CCD needs the frames only */
    bs_levelset_frame_at(d->ob[b].ls, t1, &d->frames1[b]);
    bs_levelset_motion_bound_over(d->ob[b].ls, t0, t1, &d->motion[b]);
  }
}

static int finite_all(const double *x, size_t n) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(x[i])) return 0;
  return 1;
}

/* ---- one vertex against one obstacle ------------------------------------- */

/* Adds the barrier of phi at a vertex (energy, gradient, Hessian into e[13])
 * when 0 < phi < dhat. need: 0 energy, 1 + gradient, 2 + Hessian. */
static void vertex_barrier(const obs_data *d, double phi, const double g[3], const double Hp[9], int need,
                           double *e) {
  double bb[3];
  if (bs_ipc_barrier(phi * phi, d->dhat * d->dhat, bb)) return;
  const double k = d->kappa;
  e[0] += k * bb[0];
  if (need < 1) return;
  for (int i = 0; i < 3; i++) e[1 + i] += k * bb[1] * 2 * phi * g[i];
  if (need < 2) return;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++)
      e[4 + 3 * i + j] += k * (4 * phi * phi * bb[2] * g[i] * g[j] + 2 * bb[1] * (g[i] * g[j] + phi * Hp[3 * i + j]));
}

/* Vertex j (surface index) at x against every obstacle: e[13] filled, bad,
 * pmin and pcount set. */
static void vertex_all(obs_data *d, const double *x, int32_t j, int need) {
  const double *p = x + 3 * (size_t)d->sv[j];
  double *e = d->pe + PE * (size_t)j;
  memset(e, 0, PE * sizeof(double));
  d->bad[j] = 0;
  d->pmin[j] = INFINITY;
  d->pcount[j] = 0;
  for (int b = 0; b < d->n_ob; b++) {
    double g[3], Hp[9];
    const double phi = bs_levelset_eval_frame(d->ob[b].ls, &d->frames[b], p, need ? g : NULL, need > 1 ? Hp : NULL);
    d->pmin[j] = fmin(d->pmin[j], phi);
    if (!(phi > 0)) {
      d->bad[j] = 1;
      continue;
    }
    if (phi >= d->dhat) continue;
    d->pcount[j]++;
    vertex_barrier(d, phi, g, Hp, need, e);
  }
  if (need > 1 && d->project) bs_sym_psd_project(3, e + 4);
}

/* Every surface vertex at x (parallel; per-vertex results); then the
 * statistics in vertex order. Returns 1 when some vertex is inside. */
static int barrier_pass(obs_data *d, const double *x, double time, int need) {
  set_frames(d, time);
  const int32_t n = d->n_sv;
#pragma omp parallel for schedule(static) if (n > 2048)
  for (int32_t j = 0; j < n; j++) vertex_all(d, x, j, need);
  int64_t pairs = 0, inside = 0;
  double m = INFINITY;
  for (int32_t j = 0; j < n; j++) {
    pairs += d->pcount[j];
    inside += d->bad[j];
    m = fmin(m, d->pmin[j]);
  }
  d->st.pairs = pairs;
  d->st.inside = inside;
  d->st.min_distance = m;
  return inside > 0;
}

/* ---- friction ------------------------------------------------------------ */

/* Friction of pair c at x: energy returned; gradient (3) and Hessian (9)
 * added into g and H when non-NULL (bs_ipc_friction_eval). */
static double friction_pair(const fr_pair *c, double eps, const double *x, double *g, double *H) {
  const double *p = x + 3 * (size_t)c->v, dx[3] = {p[0] - c->r[0], p[1] - c->r[1], p[2] - c->r[2]};
  double gl[3], Hl[9];
  const double e = bs_ipc_friction_eval(c->T, dx, c->mul, eps, g ? gl : NULL, H ? Hl : NULL);
  for (int k = 0; g && k < 3; k++) g[k] += gl[k];
  for (int k = 0; H && k < 9; k++) H[k] += Hl[k];
  return e;
}

static int push_pair(obs_data *d, const fr_pair *c) {
  if (d->n_fr == d->cap_fr) {
    const int64_t cap = d->cap_fr ? 2 * d->cap_fr : 64;
    fr_pair *p = realloc(d->fr, sizeof *p * (size_t)cap);
    if (!p) return BS_ENOMEM;
    d->fr = p, d->cap_fr = cap;
  }
  d->fr[d->n_fr++] = *c;
  return 0;
}

/* The lagged friction pairs at xⁿ, obstacles at tⁿ (in obstacle, vertex order). */
static int lag_friction(obs_data *d, const double *xn, double t0, double dt) {
  d->n_fr = 0;
  if (!(dt > 0)) return 0;
  for (int b = 0; b < d->n_ob; b++) {
    const ob_entry *o = &d->ob[b];
    if (!(o->mu > 0)) continue;
    bs_levelset_frame f;
    bs_levelset_frame_at(o->ls, t0, &f);
    for (int32_t j = 0; j < d->n_sv; j++) {
      const int32_t v = d->sv[j];
      const double *p = xn + 3 * (size_t)v;
      double n[3], bb[3];
      const double phi = bs_levelset_eval_frame(o->ls, &f, p, n, NULL);
      if (!(phi > 0) || phi >= d->dhat || bs_ipc_barrier(phi * phi, d->dhat * d->dhat, bb)) continue;
      fr_pair c = {.v = v, .mul = -o->mu * 2 * d->kappa * phi * bb[1]};
      const double l = sqrt(bs_dot3(n, n));
      if (!(l > 0) || !(c.mul > 0)) continue;
      for (int k = 0; k < 3; k++) n[k] /= l;
      bs_ipc_tangent_basis(n, c.T);
      double vo[3], rr[3] = {p[0] - f.c[0], p[1] - f.c[1], p[2] - f.c[2]};
      bs_cross3(f.w, rr, vo);
      for (int k = 0; k < 3; k++) c.r[k] = p[k] + dt * (f.v[k] + vo[k]);
      if (push_pair(d, &c)) return BS_ENOMEM;
    }
  }
  d->st.friction_pairs = d->n_fr;
  return 0;
}

/* ---- the term's operations -------------------------------------------------- */

static int ob_value(const bs_term *t, const double *x, double *E) {
  obs_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv) || barrier_pass(d, x, eval_time(t), 0)) return BS_TERM_NOT_EVALUABLE;
  double e = 0;
  for (int32_t j = 0; j < d->n_sv; j++) e += d->pe[PE * (size_t)j];
  for (int64_t i = 0; i < d->n_fr; i++) e += friction_pair(&d->fr[i], d->eps_v * t->step->dt, x, NULL, NULL);
  *E = e;
  return BS_TERM_OK;
}

static int ob_gradient(const bs_term *t, const double *x, double *E, double *g) {
  obs_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv) || barrier_pass(d, x, eval_time(t), 1)) return BS_TERM_NOT_EVALUABLE;
  double e = 0;
  for (int32_t j = 0; j < d->n_sv; j++) {
    const double *pe = d->pe + PE * (size_t)j;
    e += pe[0];
    for (int k = 0; k < 3; k++) g[3 * (size_t)d->sv[j] + k] += pe[1 + k];
  }
  for (int64_t i = 0; i < d->n_fr; i++)
    e += friction_pair(&d->fr[i], d->eps_v * t->step->dt, x, g + 3 * (size_t)d->fr[i].v, NULL);
  *E = e;
  return BS_TERM_OK;
}

static int ob_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  obs_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv) || barrier_pass(d, x, eval_time(t), 2)) return BS_TERM_NOT_EVALUABLE;
  for (int32_t j = 0; j < d->n_sv; j++) {
    double *B = H->val + 9 * (size_t)H->diag[d->sv[j]];
    const double *pe = d->pe + PE * (size_t)j;
    for (int k = 0; k < 9; k++) B[k] += pe[4 + k];
  }
  for (int64_t i = 0; i < d->n_fr; i++)
    friction_pair(&d->fr[i], d->eps_v * t->step->dt, x, NULL, H->val + 9 * (size_t)H->diag[d->fr[i].v]);
  return BS_TERM_OK;
}

/* ---- CCD --------------------------------------------------------------------- */

double bs_ipc_obstacle_lipschitz(const bs_levelset *ls, double *slope) {
  if (slope) *slope = 0;
  if (!ls || ls->kind != BS_LS_GRID) return 1.0;
  const int32_t nx = ls->n[0], ny = ls->n[1], nz = ls->n[2];
  const size_t st[3] = {1, (size_t)nx, (size_t)nx * (size_t)ny};
  double L[3] = {0, 0, 0}, V[3] = {0, 0, 0}; /* coefficient and value differences per axis */
  for (int32_t k = 0; k < nz; k++)
    for (int32_t j = 0; j < ny; j++)
      for (int32_t i = 0; i < nx; i++) {
        const size_t a = (size_t)i + st[1] * (size_t)j + st[2] * (size_t)k;
        const int32_t idx[3] = {i, j, k};
        for (int ax = 0; ax < 3; ax++) {
          if (idx[ax] + 1 >= ls->n[ax]) continue;
          V[ax] = fmax(V[ax], fabs(ls->values[a + st[ax]] - ls->values[a]));
          L[ax] = fmax(L[ax], fabs(ls->coef[a + st[ax]] - ls->coef[a]));
        }
      }
  for (int ax = 0; ax < 3; ax++) V[ax] /= ls->h, L[ax] = fmax(L[ax] / ls->h, V[ax]);
  if (slope) *slope = fmax(V[0], fmax(V[1], V[2]));
  return sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]) + 1.0;
}

/* The rate at which phi can fall along d (rounded up): the half-space's exact
 * -n.d (its phi is linear), else lip |d|. */
static double fall_rate(const bs_levelset *ls, const bs_levelset_frame *f, double lip, const double d[3]) {
  const double up = 1 + 16 * DBL_EPSILON, nd = sqrt(bs_dot3(d, d));
  if (ls->kind == BS_LS_HALFSPACE) {
    const double n[3] = {f->M[2], f->M[5], f->M[8]}, s = ls->complement ? -1.0 : 1.0;
    return fmax(0.0, -s * bs_dot3(n, d)) * up + 16 * DBL_EPSILON * nd;
  }
  return lip * nd * up;
}

/* The path the CCD follows: the point x0 + a d against the level set at the
 * frame f (dt = 0) or at time t0 + a dt; cs bounds |c| + the shape's size
 * over the path (for the rounding bound). */
typedef struct ccd_path {
  const bs_levelset *ls;
  const bs_levelset_frame *f;
  double t0, dt, cs;
  const double *x0, *d;
} ccd_path;

/* The rounding bound of phi at the point y of path p: 2^-40 (|y| + cs),
 * about 2000 ulps of the magnitudes involved (for grids also the largest
 * |node value|, in cs). */
static double path_delta(const ccd_path *p, const double y[3]) { return ldexp(sqrt(bs_dot3(y, y)) + p->cs, -40); }

/* A certified lower bound of phi at the path's point a: phi evaluated there
 * minus its rounding bound (path_delta). */
static double path_lower(const ccd_path *p, double a) {
  const double y[3] = {p->x0[0] + a * p->d[0], p->x0[1] + a * p->d[1], p->x0[2] + a * p->d[2]};
  const double delta = path_delta(p, y);
  if (p->dt == 0) return bs_levelset_eval_frame(p->ls, p->f, y, NULL, NULL) - delta;
  bs_levelset_frame g;
  bs_levelset_frame_at(p->ls, p->t0 + a * p->dt, &g);
  return bs_levelset_eval_frame(p->ls, &g, y, NULL, NULL) - delta;
}

/* The additive CCD (bs_ipc_obstacle.h) along p with phi's rate D (>= 0,
 * rounded up). A start whose bound is within 1/s^2 of its own rounding
 * certifies nothing: 0. */
static double ccd_core(const ccd_path *p, double D, double s, int max_iter) {
  const double lo0 = path_lower(p, 0), delta0 = path_delta(p, p->x0);
  if (!(lo0 > delta0 / (s * s))) return 0;
  if (!(D > 0)) return 1;
  const double gap = s * lo0;
  double t = 0, P = lo0;
  for (int it = 0; it < max_iter; it++) {
    const double tn = t + (1 - s) * P / D;
    if (tn >= 1) return 1;
    if (it > 0 || t > 0) { /* evaluate the end (the first step ends >= gap by the bound) */
      const double lo = path_lower(p, tn);
      if (!(lo >= gap)) return t;
      P = lo;
    } else {
      P = s * P; /* the bound at the first step's end */
    }
    t = tn;
  }
  return t;
}

/* The largest |parameter| of the shape (a grid's extent): a scale of phi's rounding. */
static double shape_size(const bs_levelset *ls) {
  double size = fmax(fabs(ls->param[0]), fmax(fabs(ls->param[1]), fabs(ls->param[2])));
  if (ls->kind == BS_LS_GRID) size = fmax(size, fabs(ls->h) * (ls->n[0] + ls->n[1] + ls->n[2]));
  return size;
}

double bs_ccd_levelset(const bs_levelset *ls, const bs_levelset_frame *f, double lip, const double x0[3],
                       const double d[3], double s, int max_iter) {
  if (!finite_all(x0, 3) || !finite_all(d, 3) || !(s > 0 && s < 1) || max_iter < 1) return 0;
  const ccd_path p = {ls, f, 0, 0, sqrt(bs_dot3(f->c, f->c)) + shape_size(ls), x0, d};
  return ccd_core(&p, fall_rate(ls, f, lip, d), s, max_iter);
}

/* The CCD against a moving shape (bs_ipc_obstacle.h, "Moving obstacles"):
 * phi's rate along the path is at most lip times the point's speed in the
 * shape's frame, |d - dt v_b(x0 + a d, t0 + a dt)|, bounded from its value
 * at a = 0 and the motion's bounds (bs_levelset_motion_bound_over). */
static double ccd_moving(const bs_levelset *ls, double lip, const bs_levelset_frame *f0, const bs_levelset_frame *f1,
                         const bs_levelset_motion_bound *mb, const double x0[3], const double d[3], double t0,
                         double t1, double s, int max_iter) {
  if (!finite_all(x0, 3) || !finite_all(d, 3) || !isfinite(t0) || !isfinite(t1) || !(s > 0 && s < 1) || max_iter < 1)
    return 0;
  const double dt = t1 - t0, ad = fabs(dt), nd = sqrt(bs_dot3(d, d));
  double r0[3], u[3], wr[3], rel[3];
  for (int k = 0; k < 3; k++) r0[k] = x0[k] - f0->c[k];
  bs_cross3(f0->w, r0, wr);
  for (int k = 0; k < 3; k++) u[k] = f0->v[k] + wr[k], rel[k] = d[k] - dt * u[k];
  const double r = sqrt(bs_dot3(r0, r0)) + nd + mb->v * ad;
  const double R = sqrt(bs_dot3(rel, rel)) + ad * (mb->dv + mb->dw * r + mb->w * (nd + mb->v * ad));
  const double D = lip * R * (1 + 64 * DBL_EPSILON) + 16 * DBL_EPSILON * (nd + ad * (mb->v + mb->w * r));
  const double cmax = fmax(sqrt(bs_dot3(f0->c, f0->c)), sqrt(bs_dot3(f1->c, f1->c))) + mb->v * ad; /* |c| on the path */
  const ccd_path p = {ls, NULL, t0, dt, cmax + shape_size(ls), x0, d};
  return ccd_core(&p, D, s, max_iter);
}

double bs_ccd_levelset_moving(const bs_levelset *ls, double lip, const double x0[3], const double d[3], double t0,
                              double t1, double s, int max_iter) {
  if (!isfinite(t0) || !isfinite(t1)) return 0;
  bs_levelset_frame f0, f1;
  bs_levelset_frame_at(ls, t0, &f0);
  bs_levelset_frame_at(ls, t1, &f1);
  bs_levelset_motion_bound mb;
  bs_levelset_motion_bound_over(ls, t0, t1, &mb);
  return ccd_moving(ls, lip, &f0, &f1, &mb, x0, d, t0, t1, s, max_iter);
}

/* One surface vertex's certified fraction of the path (p + a dv, time
 * t0 + a (t1 - t0)) against every obstacle, with the frames and bounds of
 * set_path (dv may be NULL: p fixed; t0 = t1: the line search's CCD, the
 * obstacles fixed at t0). */
static double vertex_path(const obs_data *d, const double *p, const double *dv, double t0, double t1) {
  static const double zero[3] = {0, 0, 0};
  const double *m = dv ? dv : zero;
  const int still = m[0] == 0 && m[1] == 0 && m[2] == 0;
  double a = 1;
  for (int b = 0; b < d->n_ob && a > 0; b++) {
    const ob_entry *o = &d->ob[b];
    if (bs_levelset_motion(o->ls) != BS_LS_STATIC && t1 != t0)
      a = fmin(a, ccd_moving(o->ls, o->lip, &d->frames[b], &d->frames1[b], &d->motion[b], p, m, t0, t1, BS_IPC_CCD_S,
                             BS_IPC_CCD_ITER));
    else if (!still)
      a = fmin(a, bs_ccd_levelset(o->ls, &d->frames[b], o->lip, p, m, BS_IPC_CCD_S, BS_IPC_CCD_ITER));
  }
  return a;
}

/* The smallest vertex_path over the free surface vertices into *frac (1
 * when nothing moves); 1 (not evaluable) for a non-finite x, dx or time. */
static int path_impl(const bs_term *t, const double *x, const double *dx, double t0, double t1, double *frac) {
  obs_data *d = t->data;
  const size_t n3 = 3 * (size_t)d->nv;
  if (!finite_all(x, n3) || (dx && !finite_all(dx, n3)) || !isfinite(t0) || !isfinite(t1)) return 1;
  set_path(d, t0, t1);
  const int32_t n = d->n_sv;
#pragma omp parallel for schedule(dynamic, 64) if (n > 1024)
  for (int32_t j = 0; j < n; j++) {
    const size_t v = (size_t)d->sv[j];
    d->pmin[j] = vertex_path(d, x + 3 * v, dx ? dx + 3 * v : NULL, t0, t1);
  }
  double a = 1;
  for (int32_t j = 0; j < n; j++) a = fmin(a, d->pmin[j]);
  *frac = a;
  d->st.ccd_calls++;
  d->st.ccd_limited += a < 1;
  return 0;
}

static int ob_max_step(const bs_term *t, const double *x, const double *dx, double *alpha) {
  const double time = eval_time(t);
  return path_impl(t, x, dx, time, time, alpha) ? BS_TERM_NOT_EVALUABLE : BS_TERM_OK;
}

static int ob_sweep(const bs_term *t, const double *x, const double *dx, double t0, double t1, double *frac) {
  return path_impl(t, x, dx, t0, t1, frac) ? BS_TERM_NOT_EVALUABLE : BS_TERM_OK;
}

/* Where the rigid motion of frame f0 to frame f1 takes the point p:
 * M1 M0^T (p - c0) + c1. */
static void carry_point(const bs_levelset_frame *f0, const bs_levelset_frame *f1, const double p[3], double q[3]) {
  double y[3];
  for (int k = 0; k < 3; k++)
    y[k] = f0->M[k] * (p[0] - f0->c[0]) + f0->M[3 + k] * (p[1] - f0->c[1]) + f0->M[6 + k] * (p[2] - f0->c[2]);
  for (int k = 0; k < 3; k++) q[k] = f1->c[k] + f1->M[3 * k] * y[0] + f1->M[3 * k + 1] * y[1] + f1->M[3 * k + 2] * y[2];
}

/* Vertex j's carrier: the moving obstacle within dhat of it at the frames
 * set (the nearest), or -1. */
static int carrier(const obs_data *d, const double *x, int32_t j) {
  const double *p = x + 3 * (size_t)d->sv[j];
  int best = -1;
  double m = d->dhat;
  for (int b = 0; b < d->n_ob; b++) {
    if (bs_levelset_motion(d->ob[b].ls) == BS_LS_STATIC) continue;
    const double phi = bs_levelset_eval_frame(d->ob[b].ls, &d->frames[b], p, NULL, NULL);
    if (phi > 0 && phi < m) m = phi, best = b;
  }
  return best;
}

static int ob_carry(const bs_term *t, const double *x, double t0, double t1, double *z, uint8_t *carried) {
  obs_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv) || !isfinite(t0) || !isfinite(t1)) return BS_TERM_NOT_EVALUABLE;
  set_path(d, t0, t1);
  const int32_t n = d->n_sv;
#pragma omp parallel for schedule(static) if (n > 2048)
  for (int32_t j = 0; j < n; j++) d->pcount[j] = carrier(d, x, j); /* pcount as scratch: the carrier */
  for (int32_t j = 0; j < n; j++) {
    const int b = d->pcount[j];
    if (b < 0) continue;
    const size_t v = (size_t)d->sv[j];
    double q[3];
    carry_point(&d->frames[b], &d->frames1[b], x + 3 * v, q);
    for (int k = 0; k < 3; k++) z[3 * v + k] = q[k] - x[3 * v + k];
    carried[v] = 1;
  }
  return BS_TERM_OK;
}

/* ---- step start -------------------------------------------------------------- */

/* At xⁿ: the distances for the adaptive kappa, measured with the obstacles
 * at tⁿ⁺¹, or at tⁿ when a moving obstacle has passed over a vertex by
 * tⁿ⁺¹ (the integrator then sweeps it through the step: ob_sweep); then
 * the friction pairs (obstacles at tⁿ, with the kappa in force). */
static int ob_begin_step(bs_term *t, bs_error *err) {
  obs_data *d = t->data;
  if (!t->step || !t->step->x_n) return 0;
  const double *xn = t->step->x_n;
  if (!finite_all(xn, 3 * (size_t)d->nv)) return bs_error_set(err, BS_ENUMERIC, "barrier obstacles: x^n is not finite");
  if (barrier_pass(d, xn, t->step->time, 0) && barrier_pass(d, xn, t->step->time - t->step->dt, 0))
    return bs_error_set(err, BS_EINPUT,
                        "barrier obstacles: %lld free surface vertices are inside an obstacle at the step's start",
                        (long long)d->st.inside);
  if (d->adaptive) {
    const double dh2 = d->dhat * d->dhat, m = fmax(d->st.min_distance, 0);
    const double d2 = fmin(m * m, dh2);
    d->kappa = bs_ipc_kappa_update(d->kappa, d->kappa_max, d->d2_prev, d2, d->d2_eps);
    d->d2_prev = d2;
  }
  if (lag_friction(d, xn, t->step->time - t->step->dt, t->step->dt))
    return bs_error_set(err, BS_ENOMEM, "barrier obstacles: out of memory listing the friction pairs");
  return 0;
}

/* ---- creation ------------------------------------------------------------------ */

static void ob_free(void *p) {
  obs_data *d = p;
  if (!d) return;
  free(d->sv);
  free(d->ob);
  free(d->frames);
  free(d->frames1);
  free(d->motion);
  free(d->pe);
  free(d->bad);
  free(d->pmin);
  free(d->pcount);
  free(d->fr);
  free(d);
}

/* The exact Hessian is PSD for the friction; the barrier's blocks projected. */
static int ob_hessian_convex(const bs_term *t, const double *x, bs_bsr *H) {
  obs_data *d = t->data;
  const int keep = d->project;
  d->project = 1;
  const int rc = ob_hessian(t, x, H);
  d->project = keep;
  return rc;
}

static const bs_term_ops ob_ops = {ob_value,          ob_gradient, ob_hessian,  ob_begin_step,   ob_free,
                                   ob_hessian_convex, NULL,        ob_max_step, ob_sweep, ob_carry};

static int build_vertices(obs_data *d, const bs_mesh *m, const uint8_t *mask, bs_error *err) {
  uint8_t *is = bs_calloc((size_t)m->n_vertices + 1, 1, "the barrier obstacles' surface", err);
  if (!is) return BS_ENOMEM;
  for (int32_t i = 0; i < 3 * m->n_faces; i++) is[m->faces[i]] = 1;
  for (int32_t v = 0; v < m->n_vertices; v++) is[v] = is[v] && (!mask || mask[v]);
  for (int32_t v = 0; v < m->n_vertices; v++) d->n_sv += is[v];
  const size_t n = (size_t)d->n_sv + 1;
  d->sv = bs_calloc(n, sizeof(int32_t), "the barrier obstacles' surface", err);
  d->pe = bs_calloc(n * PE, sizeof(double), "the barrier obstacles' buffers", err);
  d->bad = bs_calloc(n, 1, "the barrier obstacles' buffers", err);
  d->pmin = bs_calloc(n, sizeof(double), "the barrier obstacles' buffers", err);
  d->pcount = bs_calloc(n, sizeof(int32_t), "the barrier obstacles' buffers", err);
  int st = !d->sv || !d->pe || !d->bad || !d->pmin || !d->pcount ? BS_ENOMEM : 0;
  for (int32_t v = 0, j = 0; !st && v < m->n_vertices; v++)
    if (is[v]) d->sv[j++] = v;
  free(is);
  return st;
}

int bs_term_ipc_obstacle_create(const bs_fem *fem, const bs_step_data *step, const uint8_t *mask, double dhat,
                                double kappa, bs_term **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "barrier obstacles: out is NULL");
  *out = NULL;
  if (!fem || !fem->mesh) return bs_error_set(err, BS_EINPUT, "barrier obstacles: no fem");
  if (!(dhat > 0) || !isfinite(dhat))
    return bs_error_set(err, BS_EINPUT, "barrier obstacles: dhat must be finite and > 0 (m), got %g", dhat);
  if (!(kappa >= 0) || !isfinite(kappa))
    return bs_error_set(err, BS_EINPUT, "barrier obstacles: kappa must be finite and >= 0, got %g", kappa);
  const bs_mesh *m = fem->mesh;
  if (m->n_faces < 1) return bs_error_set(err, BS_EINPUT, "barrier obstacles: the mesh has no boundary triangles");
  obs_data *d = bs_calloc(1, sizeof *d, "the barrier obstacles term", err);
  if (!d) return BS_ENOMEM;
  d->nv = m->n_vertices;
  d->dhat = dhat;
  d->kappa = kappa;
  d->eps_v = BS_IPC_OBSTACLE_EPS_V;
  d->d2_prev = dhat * dhat;
  d->project = 1;
  int st = build_vertices(d, m, mask, err);
  bs_term *t = st ? NULL : calloc(1, sizeof *t);
  if (!st && !t) st = bs_error_set(err, BS_ENOMEM, "out of memory creating the barrier obstacles term");
  if (st) {
    ob_free(d);
    return st;
  }
  t->name = "barrier_obstacles";
  t->kind = BS_TERM_BARRIER_CONTACT;
  t->ops = &ob_ops;
  t->fem = fem;
  t->step = step;
  t->data = d;
  d->st.min_distance = INFINITY;
  *out = t;
  return 0;
}

int bs_term_is_ipc_obstacle(const bs_term *t) { return t && t->ops == &ob_ops; }

static int not_ob(const bs_term *t, bs_error *err) {
  return bs_term_is_ipc_obstacle(t) ? 0 : bs_error_set(err, BS_EINPUT, "not a barrier obstacles term");
}

int bs_term_ipc_obstacle_add(bs_term *t, const bs_levelset *ls, double mu, int index, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  if (!ls) return bs_error_set(err, BS_EINPUT, "obstacle %d: no level set", index);
  const char *kind = bs_levelset_kind_name(bs_levelset_kind(ls));
  if (!(mu >= 0) || !isfinite(mu))
    return bs_error_set(err, BS_EINPUT, "obstacle %d (%s): friction = %g must be finite and >= 0", index, kind, mu);
  double slope = 0;
  const double lip = bs_ipc_obstacle_lipschitz(ls, &slope);
  if (!(slope <= BS_IPC_OBSTACLE_MAX_SLOPE))
    return bs_error_set(err, BS_EINPUT,
                        "obstacle %d (%s): collision \"barrier\" needs a signed distance, but the grid's values "
                        "change by up to %g h between nodes (a distance changes by at most h; limit %g h)",
                        index, kind, slope, BS_IPC_OBSTACLE_MAX_SLOPE);
  obs_data *d = t->data;
  if (d->n_ob == d->cap_ob) {
    const int cap = d->cap_ob ? 2 * d->cap_ob : 4;
    ob_entry *o = realloc(d->ob, sizeof *o * (size_t)cap);
    if (o) d->ob = o;
    bs_levelset_frame *f = realloc(d->frames, sizeof *f * (size_t)cap);
    if (f) d->frames = f;
    bs_levelset_frame *f1 = realloc(d->frames1, sizeof *f1 * (size_t)cap);
    if (f1) d->frames1 = f1;
    bs_levelset_motion_bound *mb = realloc(d->motion, sizeof *mb * (size_t)cap);
    if (mb) d->motion = mb;
    if (!o || !f || !f1 || !mb) return bs_error_set(err, BS_ENOMEM, "obstacle %d (%s): out of memory", index, kind);
    d->cap_ob = cap;
  }
  d->ob[d->n_ob++] = (ob_entry){ls, mu, lip, index};
  return 0;
}

int bs_term_ipc_obstacle_set_kappa(bs_term *t, double kappa, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  if (!(kappa >= 0) || !isfinite(kappa))
    return bs_error_set(err, BS_EINPUT, "barrier obstacles: kappa must be finite and >= 0, got %g", kappa);
  ((obs_data *)t->data)->kappa = kappa;
  return 0;
}

int bs_term_ipc_obstacle_set_project(bs_term *t, int on, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  ((obs_data *)t->data)->project = on != 0;
  return 0;
}

int bs_term_ipc_obstacle_set_adaptive(bs_term *t, double kappa_max, double d2_eps, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  if (!(kappa_max >= 0) || !isfinite(kappa_max) || !(d2_eps > 0) || !isfinite(d2_eps))
    return bs_error_set(err, BS_EINPUT,
                        "barrier obstacles: adaptive kappa needs kappa_max >= 0 and d2_eps > 0 finite, got %g and %g",
                        kappa_max, d2_eps);
  obs_data *d = t->data;
  d->adaptive = kappa_max > 0;
  d->kappa_max = kappa_max;
  d->d2_eps = d2_eps;
  return 0;
}

int bs_term_ipc_obstacle_set_friction(bs_term *t, double eps_v, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  if (!(eps_v > 0) || !isfinite(eps_v))
    return bs_error_set(err, BS_EINPUT, "barrier obstacles: eps_v must be finite and > 0 (m/s), got %g", eps_v);
  ((obs_data *)t->data)->eps_v = eps_v;
  return 0;
}

int bs_term_ipc_obstacle_kappa_init(bs_term *t, const double *x, const double *grad_energy, double kappa_min,
                                    double kappa_max, double *kappa, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  obs_data *d = t->data;
  const size_t n3 = 3 * (size_t)d->nv;
  const double keep = d->kappa;
  d->kappa = 1;
  const int bad = !finite_all(x, n3) || barrier_pass(d, x, eval_time(t), 1);
  d->kappa = keep;
  if (bad)
    return bs_error_set(err, BS_ENUMERIC, "barrier obstacles: %lld free surface vertices are inside an obstacle",
                        (long long)d->st.inside);
  double *gb = bs_calloc(n3 + 1, sizeof(double), "the barrier gradient", err);
  if (!gb) return BS_ENOMEM;
  for (int32_t j = 0; j < d->n_sv; j++)
    for (int k = 0; k < 3; k++) gb[3 * (size_t)d->sv[j] + k] = d->pe[PE * (size_t)j + 1 + k];
  d->kappa = bs_ipc_kappa_initial(n3, grad_energy, gb, kappa_min, kappa_max);
  free(gb);
  if (kappa) *kappa = d->kappa;
  return 0;
}

int bs_term_ipc_obstacle_stats(const bs_term *t, bs_ipc_obstacle_stats *out, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  const obs_data *d = t->data;
  *out = d->st;
  out->kappa = d->kappa;
  out->dhat = d->dhat;
  out->eps_v = d->eps_v;
  return 0;
}

int bs_term_ipc_obstacle_detect(bs_term *t, const double *x, bs_ipc_obstacle_stats *out, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  obs_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv)) return bs_error_set(err, BS_ENUMERIC, "barrier obstacles: x is not finite");
  barrier_pass(d, x, eval_time(t), 0);
  if (out) bs_term_ipc_obstacle_stats(t, out, err);
  return 0;
}

int bs_term_ipc_obstacle_max_step(bs_term *t, const double *x, const double *dx, double *alpha, bs_error *err) {
  if (not_ob(t, err)) return BS_EINPUT;
  const double time = eval_time(t);
  if (path_impl(t, x, dx, time, time, alpha))
    return bs_error_set(err, BS_ENUMERIC, "barrier obstacles: CCD on non-finite positions or motion");
  return 0;
}
