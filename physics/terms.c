/* terms.c — inertia, gravity, elasticity, lagged Rayleigh damping, drag.
 *
 * Each is defined for every x: its callbacks always return BS_TERM_OK, and a
 * non-finite x (or an overflow) gives whatever NaN/Inf the arithmetic makes.
 * The elastic models are finite for every finite F (bs_material.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_element.h"
#include "bs_sum.h"
#include "bs_terms.h"

int bs_term_create(const char *name, const bs_term_ops *ops, const bs_fem *fem, const bs_step_data *step, void *data,
                   bs_term **out, bs_error *err) {
  *out = NULL;
  if (!ops || !ops->value || !ops->gradient || !ops->hessian || !fem) {
    if (data && ops && ops->destroy_data) ops->destroy_data(data);
    return bs_error_set(err, BS_EINPUT, "the %s term needs a fem cache and value, gradient and hessian callbacks",
                        name ? name : "new");
  }
  bs_term *t = calloc(1, sizeof *t);
  if (!t) {
    if (data && ops->destroy_data) ops->destroy_data(data);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the %s term", name);
  }
  t->name = name;
  t->ops = ops;
  t->fem = fem;
  t->step = step;
  t->data = data;
  *out = t;
  return 0;
}

const char *bs_term_status_name(bs_term_status s) {
  return s == BS_TERM_OK ? "ok" : s == BS_TERM_NOT_EVALUABLE ? "not_evaluable" : "?";
}

void bs_term_destroy(bs_term **pt) {
  if (!pt || !*pt) return;
  bs_term *t = *pt;
  if (t->data && t->ops->destroy_data) t->ops->destroy_data(t->data);
  free(t);
  *pt = NULL;
}

/* Adds c * m_v to the diagonal blocks of H. */
static void add_mass_diagonal(const bs_fem *fem, double c, bs_bsr *H) {
#pragma omp parallel for schedule(static) if (fem->n_vertices > 8192)
  for (int32_t v = 0; v < fem->n_vertices; v++) {
    double *blk = H->val + 9 * (size_t)H->diag[v];
    double d = c * fem->mass[v];
    blk[0] += d;
    blk[4] += d;
    blk[8] += d;
  }
}

/* c/2 Σ m_v |x_v − y_v|², gradient c m_v (x_v − y_v). */
static double mass_quadratic(const bs_fem *fem, double c, const double *x, const double *y, double *g) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(fem->n_vertices);
#pragma omp parallel for schedule(static) if (fem->n_vertices > 8192)
  for (int ch = 0; ch < P.count; ch++) {
    double E = 0;
    for (int32_t v = (int32_t)bs_sum_lo(P, ch); v < (int32_t)bs_sum_hi(P, ch); v++) {
      double cm = c * fem->mass[v];
      for (int k = 0; k < 3; k++) {
        double d = x[3 * v + k] - y[3 * v + k];
        E += 0.5 * cm * d * d;
        if (g) g[3 * v + k] += cm * d;
      }
    }
    part[ch] = E;
  }
  return bs_sum_parts(P.count, part);
}

/* ---- inertia ---------------------------------------------------------- */
/* 1/(c Δt²), c the integrator's (bs_step_data.c; 0 reads as 1): for c = 1
 * the product c Δt Δt is Δt Δt exactly, so backward Euler is unchanged. */
static double inertia_weight(const bs_step_data *s) {
  const double c = s->c > 0 ? s->c : 1.0, dt = s->dt;
  return 1.0 / (c * dt * dt);
}
static int inertia_value(const bs_term *t, const double *x, double *E) {
  *E = mass_quadratic(t->fem, inertia_weight(t->step), x, t->step->x_hat, NULL);
  return BS_TERM_OK;
}
static int inertia_gradient(const bs_term *t, const double *x, double *E, double *g) {
  *E = mass_quadratic(t->fem, inertia_weight(t->step), x, t->step->x_hat, g);
  return BS_TERM_OK;
}
static int inertia_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  add_mass_diagonal(t->fem, inertia_weight(t->step), H);
  return BS_TERM_OK;
}
static const bs_term_ops inertia_ops = {inertia_value, inertia_gradient, inertia_hessian, NULL, NULL, NULL, NULL,
                                        NULL, NULL, NULL};

int bs_term_inertia_create(const bs_fem *fem, const bs_step_data *step, bs_term **out, bs_error *err) {
  int st = bs_term_create("inertia", &inertia_ops, fem, step, NULL, out, err);
  if (!st) (*out)->kind = BS_TERM_INERTIA, (*out)->dynamic_only = (*out)->quadratic = 1;
  return st;
}

/* ---- gravity ---------------------------------------------------------- */
/* The nodes' weights of the body load: the lumped mass (tet4), or the
 * consistent load's rho int N_v dX (tet10, bs_fem.h). */
static const double *gravity_weights(const bs_fem *fem) { return fem->load ? fem->load : fem->mass; }
static double gravity_load(const bs_term *t) { return t->step ? t->step->load : 1.0; }
static int gravity_value(const bs_term *t, const double *x, double *Eout) {
  const double *gd = t->data;
  double s = gravity_load(t), g[3] = {s * gd[0], s * gd[1], s * gd[2]};
  const bs_fem *fem = t->fem;
  const double *w = gravity_weights(fem);
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(fem->n_vertices);
#pragma omp parallel for schedule(static) if (fem->n_vertices > 8192)
  for (int c = 0; c < P.count; c++) {
    double E = 0;
    for (int32_t v = (int32_t)bs_sum_lo(P, c); v < (int32_t)bs_sum_hi(P, c); v++)
      E -= w[v] * (g[0] * x[3 * v] + g[1] * x[3 * v + 1] + g[2] * x[3 * v + 2]);
    part[c] = E;
  }
  *Eout = bs_sum_parts(P.count, part);
  return BS_TERM_OK;
}
static int gravity_gradient(const bs_term *t, const double *x, double *E, double *grad) {
  const double *gd = t->data;
  double s = gravity_load(t), g[3] = {s * gd[0], s * gd[1], s * gd[2]};
  const bs_fem *fem = t->fem;
  const double *w = gravity_weights(fem);
#pragma omp parallel for schedule(static) if (fem->n_vertices > 8192)
  for (int32_t v = 0; v < fem->n_vertices; v++)
    for (int k = 0; k < 3; k++) grad[3 * v + k] -= w[v] * g[k];
  return gravity_value(t, x, E);
}
static int gravity_hessian(const bs_term *t, const double *x, bs_bsr *H) { return BS_TERM_OK; }
static const bs_term_ops gravity_ops = {gravity_value, gravity_gradient, gravity_hessian, NULL, free, NULL, NULL,
                                        NULL, NULL, NULL};

int bs_term_gravity_create(const bs_fem *fem, const bs_step_data *step, const double g[3], bs_term **out,
                           bs_error *err) {
  for (int k = 0; k < 3; k++)
    if (!isfinite(g[k])) return bs_error_set(err, BS_EINPUT, "gravity component %d is not finite (%g)", k, g[k]);
  double *gc = malloc(3 * sizeof(double));
  if (!gc) return bs_error_set(err, BS_ENOMEM, "out of memory creating the gravity term");
  memcpy(gc, g, 3 * sizeof(double));
  int st = bs_term_create("gravity", &gravity_ops, fem, step, gc, out, err);
  if (!st) (*out)->kind = BS_TERM_GRAVITY, (*out)->quadratic = (*out)->external = 1;
  return st;
}

/* ---- elasticity ------------------------------------------------------- */
static int elastic_value(const bs_term *t, const double *x, double *E) {
  *E = bs_fem_elastic_energy(t->fem, x);
  return BS_TERM_OK;
}
static int elastic_gradient(const bs_term *t, const double *x, double *E, double *g) {
  *E = bs_fem_elastic_gradient(t->fem, x, g);
  return BS_TERM_OK;
}
/* The elastic term's data: its definiteness fix, and for BS_PSD_AUTO the
 * per-material volume bound it sets at each Hessian. */
typedef struct elastic_data {
  int mode;
  double *vmax;
} elastic_data;

static void elastic_free(void *p) {
  elastic_data *d = p;
  if (!d) return;
  free(d->vmax);
  free(d);
}

/* BS_PSD_AUTO: a tet's mu dt^2 / (rho h^2) >= R with h = (6 sqrt 2 V)^(1/3)
 * (the edge of the regular tet of its rest volume V) is V <= vmax =
 * (mu dt^2 / (R rho))^(3/2) / (6 sqrt 2); every tet in a static solve. */
static int elastic_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  const elastic_data *d = t->data;
  if (d->mode != BS_PSD_AUTO) {
    bs_fem_elastic_hessian(t->fem, x, d->mode, 1.0, H);
    return BS_TERM_OK;
  }
  const double dt = t->step ? t->step->dt : 0.0;
  for (int m = 0; m < t->fem->n_materials; m++) {
    const bs_material *mat = &t->fem->materials[m];
    d->vmax[m] = dt > 0 ? pow(mat->mu * dt * dt / (BS_PSD_AUTO_RATIO * mat->density), 1.5) / (6.0 * sqrt(2.0))
                        : INFINITY;
  }
  bs_fem_elastic_hessian_auto(t->fem, x, d->vmax, 1.0, H);
  return BS_TERM_OK;
}
static const bs_term_ops elastic_ops = {elastic_value, elastic_gradient, elastic_hessian, NULL, elastic_free, NULL,
                                        NULL, NULL, NULL, NULL};

int bs_term_elastic_create_step(const bs_fem *fem, const bs_step_data *step, bs_psd_mode project_psd, bs_term **out,
                                bs_error *err) {
  if (project_psd < BS_PSD_NONE || project_psd > BS_PSD_AUTO)
    return bs_error_set(err, BS_EINPUT, "elasticity term: project_psd %d is not a bs_psd_mode", project_psd);
  if (project_psd == BS_PSD_AUTO && !step)
    return bs_error_set(err, BS_EINPUT, "elasticity term: project_psd auto needs the step data (its dt)");
  elastic_data *d = calloc(1, sizeof *d);
  if (!d) return bs_error_set(err, BS_ENOMEM, "out of memory creating the elasticity term");
  d->mode = project_psd;
  if (project_psd == BS_PSD_AUTO && !(d->vmax = calloc((size_t)fem->n_materials, sizeof *d->vmax))) {
    elastic_free(d);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the elasticity term");
  }
  int st = bs_term_create("elasticity", &elastic_ops, fem, step, d, out, err);
  if (st) return st;
  (*out)->kind = BS_TERM_ELASTICITY;
  (*out)->quadratic = 1;
  for (int i = 0; i < fem->n_materials; i++)
    if (fem->materials[i].model != BS_MODEL_LINEAR) (*out)->quadratic = 0;
  return 0;
}

int bs_term_elastic_create(const bs_fem *fem, bs_psd_mode project_psd, bs_term **out, bs_error *err) {
  return bs_term_elastic_create_step(fem, NULL, project_psd, out, err);
}

/* ---- lagged Rayleigh damping ------------------------------------------ */
typedef struct damping_data {
  bs_bsr *D;     /* Σ k H⁺(xⁿ), assembled at begin_step                   */
  double *k;     /* per material                                           */
  double *work;  /* 3n: D (x − xⁿ)                                          */
  double *d;     /* 3n: x − xⁿ                                              */
} damping_data;

static void damping_free(void *p) {
  damping_data *d = p;
  bs_bsr_destroy(&d->D);
  free(d->k);
  free(d->work);
  free(d->d);
  free(d);
}

static int damping_begin(bs_term *t, bs_error *err) {
  damping_data *dd = t->data;
  bs_bsr_zero(dd->D);
  /* k_m H⁺(xⁿ) over the tets of each material m (k_m = 0: skipped) */
  bs_fem_elastic_hessian_scaled(t->fem, t->step->x_n, 1, dd->k, dd->D);
  return 0;
}

/* 1/(2Δt) dᵀ D d with d = x − xⁿ; D d left in work. */
static double damping_eval(const bs_term *t, const double *x) {
  damping_data *dd = t->data;
  size_t n3 = 3 * (size_t)t->fem->n_vertices;
  const double *xn = t->step->x_n;
  for (size_t i = 0; i < n3; i++) dd->d[i] = x[i] - xn[i];
  bs_bsr_mul(dd->D, NULL, dd->d, dd->work);
  double E = 0;
  for (size_t i = 0; i < n3; i++) E += dd->d[i] * dd->work[i];
  return E / (2.0 * t->step->dt);
}
static int damping_value(const bs_term *t, const double *x, double *E) {
  *E = damping_eval(t, x);
  return BS_TERM_OK;
}
static int damping_gradient(const bs_term *t, const double *x, double *E, double *g) {
  damping_data *dd = t->data;
  *E = damping_eval(t, x);
  size_t n3 = 3 * (size_t)t->fem->n_vertices;
  double c = 1.0 / t->step->dt;
  for (size_t i = 0; i < n3; i++) g[i] += c * dd->work[i];
  return BS_TERM_OK;
}
static int damping_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  damping_data *dd = t->data;
  double c = 1.0 / t->step->dt;
  const int64_t nv = 9 * H->nnzb;
  const double *Dv = dd->D->val;
#pragma omp parallel for schedule(static) if (nv > 65536)
  for (int64_t i = 0; i < nv; i++) H->val[i] += c * Dv[i];
  return BS_TERM_OK;
}
static const bs_term_ops damping_ops = {damping_value, damping_gradient, damping_hessian, damping_begin,
                                        damping_free, NULL, NULL, NULL, NULL, NULL};

int bs_term_damping_create(const bs_fem *fem, const bs_step_data *step, const double *k, bs_term **out,
                           bs_error *err) {
  for (int m = 0; m < fem->n_materials; m++)
    if (!(k[m] >= 0) || !isfinite(k[m]))
      return bs_error_set(err, BS_EINPUT, "damping coefficient of material %d must be finite and >= 0, got %g", m,
                          k[m]);
  damping_data *dd = calloc(1, sizeof *dd);
  size_t n3 = 3 * (size_t)fem->n_vertices;
  if (!dd) return bs_error_set(err, BS_ENOMEM, "out of memory creating the damping term");
  dd->k = malloc(sizeof(double) * (size_t)fem->n_materials);
  dd->work = malloc(sizeof(double) * (n3 ? n3 : 1));
  dd->d = malloc(sizeof(double) * (n3 ? n3 : 1));
  int st = 0;
  if (!dd->k || !dd->work || !dd->d) st = bs_error_set(err, BS_ENOMEM, "out of memory creating the damping term");
  if (!st) st = bs_fem_matrix(fem, &dd->D, err);
  if (st) {
    damping_free(dd);
    return st;
  }
  memcpy(dd->k, k, sizeof(double) * (size_t)fem->n_materials);
  st = bs_term_create("damping", &damping_ops, fem, step, dd, out, err);
  if (!st) (*out)->kind = BS_TERM_DAMPING, (*out)->dynamic_only = (*out)->quadratic = 1;
  return st;
}

/* ---- drag --------------------------------------------------------------- */
static int drag_value(const bs_term *t, const double *x, double *E) {
  double k = *(const double *)t->data;
  *E = mass_quadratic(t->fem, k / t->step->dt, x, t->step->x_n, NULL);
  return BS_TERM_OK;
}
static int drag_gradient(const bs_term *t, const double *x, double *E, double *g) {
  double k = *(const double *)t->data;
  *E = mass_quadratic(t->fem, k / t->step->dt, x, t->step->x_n, g);
  return BS_TERM_OK;
}
static int drag_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  double k = *(const double *)t->data;
  add_mass_diagonal(t->fem, k / t->step->dt, H);
  return BS_TERM_OK;
}
static const bs_term_ops drag_ops = {drag_value, drag_gradient, drag_hessian, NULL, free, NULL, NULL, NULL, NULL, NULL};

int bs_term_drag_create(const bs_fem *fem, const bs_step_data *step, double k, bs_term **out, bs_error *err) {
  if (!(k >= 0) || !isfinite(k)) return bs_error_set(err, BS_EINPUT, "drag coefficient must be finite and >= 0, got %g", k);
  double *kc = malloc(sizeof(double));
  if (!kc) return bs_error_set(err, BS_ENOMEM, "out of memory creating the drag term");
  *kc = k;
  int st = bs_term_create("drag", &drag_ops, fem, step, kc, out, err);
  if (!st) (*out)->kind = BS_TERM_DRAG, (*out)->dynamic_only = (*out)->quadratic = 1;
  return st;
}
