/* penalty.c — object penalty collisions, Phi = k (-phi)^3 inside (paper
 * section 5.2; see bs_penalty.h for the sign and the derivatives). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_penalty.h"
#include "bs_sum.h"

typedef struct penalty_data {
  const bs_levelset *ls;
  double k;
  int32_t n;        /* vertices in the set                          */
  int32_t *verts;   /* the set; NULL: all, vertex i is entry i      */
} penalty_data;

static void penalty_free(void *p) {
  penalty_data *d = p;
  if (!d) return;
  free(d->verts);
  free(d);
}

static double step_time(const bs_term *t) { return t->step ? t->step->time : 0.0; }
static int32_t vertex_of(const penalty_data *d, int32_t i) { return d->verts ? d->verts[i] : i; }

/* phi at xp, with its gradient (and Hessian) only where phi < 0: the value
 * alone costs a tenth of a grid level set's full interpolation, and most
 * vertices are outside. The same phi either way (the same sums). Where a
 * grid's coefficient ranges already say phi >= 0, +Inf in its place (the
 * callers only ask phi < 0). */
static double phi_at(const bs_levelset *ls, const bs_levelset_frame *f, const double *xp, double grad[3],
                     double hess[9]) {
  if (bs_levelset_surely_outside_frame(ls, f, xp)) return INFINITY;
  const double phi = bs_levelset_eval_frame(ls, f, xp, NULL, NULL);
  if (!(phi < 0) || (!grad && !hess)) return phi;
  return bs_levelset_eval_frame(ls, f, xp, grad, hess);
}

/* Energy of all vertices (summed as in bs_sum.h: the same bits with any
 * thread count), gradient added into g when non-NULL. */
static double penalty_eval(const bs_term *t, const double *x, double *g) {
  penalty_data *d = t->data;
  bs_levelset_frame f;
  bs_levelset_frame_at(d->ls, step_time(t), &f);
  const double k = d->k;
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(d->n);
#pragma omp parallel for schedule(static) if (d->n > 4096)
  for (int c = 0; c < P.count; c++) {
    double E = 0;
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); i++) {
      int32_t v = vertex_of(d, i);
      double grad[3];
      double phi = phi_at(d->ls, &f, x + 3 * (size_t)v, g ? grad : NULL, NULL);
      if (!(phi < 0)) continue;
      E -= k * phi * phi * phi;
      if (g)
        for (int a = 0; a < 3; a++) g[3 * (size_t)v + a] -= 3 * k * phi * phi * grad[a];
    }
    part[c] = E;
  }
  return bs_sum_parts(P.count, part);
}

/* Defined for every x: a vertex where phi is NaN (a NaN position) adds
 * nothing, one at phi = -Inf adds +Inf; always BS_TERM_OK. */
static int penalty_value(const bs_term *t, const double *x, double *E) {
  *E = penalty_eval(t, x, NULL);
  return BS_TERM_OK;
}
static int penalty_gradient(const bs_term *t, const double *x, double *E, double *g) {
  *E = penalty_eval(t, x, g);
  return BS_TERM_OK;
}

/* The coefficient of grad phi grad phi^T in the secant model (bs_penalty.h)
 * of a vertex at depth -phi whose whole gradient is gv: 3 k (depth + depth*),
 * depth* = sqrt(F / (3 k |grad phi|)) from the other terms' push inwards F
 * (0 when they pull outwards). */
static double secant_coef(double k, double phi, const double grad[3], const double gv[3]) {
  const double gn = sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
  double F = 0; /* (gv - the penalty's own gradient) . grad phi / |grad phi| */
  for (int a = 0; a < 3; a++) F += (gv[a] + 3 * k * phi * phi * grad[a]) * grad[a];
  const double ds = gn > 0 && F > 0 ? sqrt(F / gn / (3 * k * gn)) : 0;
  return isfinite(ds) ? 3 * k * (ds - phi) : -6 * k * phi;
}

/* The exact Hessian (g NULL) or the secant model given g, added into H. */
static void penalty_model(const bs_term *t, const double *x, const double *g, bs_bsr *H) {
  const penalty_data *d = t->data;
  bs_levelset_frame f;
  bs_levelset_frame_at(d->ls, step_time(t), &f);
  const double k = d->k;
#pragma omp parallel for schedule(static)
  for (int32_t i = 0; i < d->n; i++) {
    int32_t v = vertex_of(d, i);
    double grad[3], hess[9];
    double phi = phi_at(d->ls, &f, x + 3 * (size_t)v, grad, hess);
    if (!(phi < 0)) continue;
    const double c = g ? secant_coef(k, phi, grad, g + 3 * (size_t)v) : -6 * k * phi;
    double *blk = H->val + 9 * (size_t)H->diag[v];
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++) blk[3 * a + b] += c * grad[a] * grad[b] - 3 * k * phi * phi * hess[3 * a + b];
  }
}

static int penalty_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  penalty_model(t, x, NULL, H);
  return BS_TERM_OK;
}
static int penalty_hessian_g(const bs_term *t, const double *x, const double *g, bs_bsr *H) {
  penalty_model(t, x, g, H);
  return BS_TERM_OK;
}

static const bs_term_ops penalty_ops = {penalty_value, penalty_gradient, penalty_hessian, NULL, penalty_free, NULL,
                                        penalty_hessian_g, NULL, NULL, NULL};

int bs_term_penalty_create_subset(const bs_fem *fem, const bs_step_data *step, const bs_levelset *ls, double k,
                                  int32_t n_vertices, const int32_t *vertices, bs_term **out, bs_error *err) {
  if (!fem || !ls || !out) return bs_error_set(err, BS_EINPUT, "penalty term: fem, level set and out must be non-NULL");
  if (!isfinite(k) || !(k > 0))
    return bs_error_set(err, BS_EINPUT, "penalty stiffness k = %g: must be finite and > 0 (J/m^3)", k);
  if (vertices && (n_vertices < 0 || n_vertices > fem->n_vertices))
    return bs_error_set(err, BS_EINPUT, "penalty term: %d vertices given for a mesh of %d", (int)n_vertices,
                        (int)fem->n_vertices);
  penalty_data *d = bs_calloc(1, sizeof *d, "the penalty term", err);
  if (!d) return BS_ENOMEM;
  d->ls = ls;
  d->k = k;
  d->n = vertices ? n_vertices : fem->n_vertices;
  int st = 0;
  if (vertices) {
    uint8_t *seen = bs_calloc((size_t)fem->n_vertices + 1, 1, "the penalty vertex set", err);
    d->verts = bs_calloc((size_t)d->n + 1, sizeof(int32_t), "the penalty vertex set", err);
    if (!seen || !d->verts) st = BS_ENOMEM;
    for (int32_t i = 0; !st && i < d->n; i++) {
      int32_t v = vertices[i];
      if (v < 0 || v >= fem->n_vertices)
        st = bs_error_set(err, BS_EINPUT, "penalty vertices[%d] = %d: out of range [0, %d)", (int)i, (int)v,
                          (int)fem->n_vertices);
      else if (seen[v])
        st = bs_error_set(err, BS_EINPUT, "penalty vertices[%d] = %d: repeated", (int)i, (int)v);
      else
        seen[v] = 1, d->verts[i] = v;
    }
    free(seen);
  }
  bs_term *t = NULL;
  if (!st) {
    t = calloc(1, sizeof *t);
    if (!t) st = bs_error_set(err, BS_ENOMEM, "out of memory creating the penalty term");
  }
  if (st) {
    penalty_free(d);
    return st;
  }
  t->name = "penalty";
  t->kind = BS_TERM_PENALTY;
  t->ops = &penalty_ops;
  t->fem = fem;
  t->step = step;
  t->data = d;
  *out = t;
  return 0;
}

int bs_term_penalty_create(const bs_fem *fem, const bs_step_data *step, const bs_levelset *ls, double k,
                           bs_term **out, bs_error *err) {
  return bs_term_penalty_create_subset(fem, step, ls, k, 0, NULL, out, err);
}

int bs_term_is_penalty(const bs_term *t) { return t && t->ops == &penalty_ops; }

const bs_levelset *bs_term_penalty_levelset(const bs_term *t) {
  return bs_term_is_penalty(t) ? ((const penalty_data *)t->data)->ls : NULL;
}

double bs_term_penalty_stiffness(const bs_term *t) {
  return bs_term_is_penalty(t) ? ((const penalty_data *)t->data)->k : 0.0;
}

double bs_penalty_point_force(const bs_levelset *ls, double k, double time, const double x[3], double f[3]) {
  double grad[3];
  double phi = bs_levelset_eval(ls, time, x, grad, NULL);
  double s = phi < 0 ? 3 * k * phi * phi : 0.0;
  for (int a = 0; a < 3; a++) f[a] = s * grad[a];
  return phi;
}

static int need_penalty(const bs_term *t, const char *what, bs_error *err) {
  if (!bs_term_is_penalty(t))
    return bs_error_set(err, BS_EINPUT, "%s: term \"%s\" is not a penalty term", what, t && t->name ? t->name : "NULL");
  return 0;
}

int bs_term_penalty_forces(const bs_term *t, const double *x, double *f, bs_error *err) {
  int st = need_penalty(t, "penalty forces", err);
  if (st) return st;
  const penalty_data *d = t->data;
  bs_levelset_frame fr;
  bs_levelset_frame_at(d->ls, step_time(t), &fr);
  memset(f, 0, 3 * (size_t)t->fem->n_vertices * sizeof(double));
  const double k = d->k;
#pragma omp parallel for schedule(static)
  for (int32_t i = 0; i < d->n; i++) {
    int32_t v = vertex_of(d, i);
    double grad[3];
    double phi = phi_at(d->ls, &fr, x + 3 * (size_t)v, grad, NULL);
    if (phi < 0)
      for (int a = 0; a < 3; a++) f[3 * (size_t)v + a] = 3 * k * phi * phi * grad[a];
  }
  return 0;
}

int bs_term_penalty_stats(const bs_term *t, const double *x, int32_t *count, double *max_depth, bs_error *err) {
  int st = need_penalty(t, "penalty stats", err);
  if (st) return st;
  const penalty_data *d = t->data;
  bs_levelset_frame fr;
  bs_levelset_frame_at(d->ls, step_time(t), &fr);
  int32_t c = 0;
  double depth = 0;
#pragma omp parallel for schedule(static) reduction(+ : c) reduction(max : depth)
  for (int32_t i = 0; i < d->n; i++) {
    double phi = bs_levelset_eval_frame(d->ls, &fr, x + 3 * (size_t)vertex_of(d, i), NULL, NULL);
    if (phi < 0) {
      c++;
      if (-phi > depth) depth = -phi;
    }
  }
  if (count) *count = c;
  if (max_depth) *max_depth = depth;
  return 0;
}
