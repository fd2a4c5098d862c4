/* test_dist_fem: the terms on a distributed mesh (bs_dfem.h) against the
 * serial bs_fem on the same box and configuration, on 1 and 2 ranks: energy
 * and gradient (1e-12 relative), Hessian-vector products (1e-12), fixed
 * vertices (identity rows), every material model, and a finite-difference
 * check of the distributed gradient. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dfem.h"
#include "dist_check.h"

#define SPEC "box:6x3x3:1.2x0.6x0.6"

/* A smooth, non-trivial field of the serial vertex id (3 per vertex). */
static void field(int64_t id, const double *X, double amp, double phase, double out[3]) {
  for (int k = 0; k < 3; k++) out[k] = (X ? X[k] : 0) + amp * sin(0.37 * (double)id + 1.1 * k + phase);
}

typedef struct side {
  bs_step_data step;
  double *x_hat, *x_n;
  bs_term *terms[3];
} side;

static int make_terms(const bs_fem *fem, side *s, bs_error *err) {
  const double g[3] = {0, -9.8, 0};
  s->step.dt = 1.0 / 24;
  s->step.x_hat = s->x_hat;
  s->step.x_n = s->x_n;
  s->step.load = 1;
  int rc = bs_term_inertia_create(fem, &s->step, &s->terms[0], err);
  if (!rc) rc = bs_term_gravity_create(fem, &s->step, g, &s->terms[1], err);
  if (!rc) rc = bs_term_elastic_create(fem, 0, &s->terms[2], err);
  return rc;
}

static void free_side(side *s) {
  for (int i = 0; i < 3; i++) bs_term_destroy(&s->terms[i]);
  free(s->x_hat);
  free(s->x_n);
}

typedef struct fixture {
  bs_mesh *m;
  bs_fem *fem;
  bs_dmesh *dm;
  bs_dfem *df;
  side ser, dis;
  double *xs, *xd; /* the configuration: serial order, local-vector order */
} fixture;

static int setup(fixture *f, bs_model model, bs_error *err) {
  memset(f, 0, sizeof *f);
  bs_material mat;
  const int tag = 1;
  int rc = bs_material_init(model, 1e5, 0.3, 1000, &mat, err);
  if (!rc) rc = bs_mesh_load(SPEC, NULL, &f->m, err);
  if (!rc) rc = bs_fem_create(f->m, 1, &mat, NULL, &f->fem, err);
  if (!rc) rc = bs_dmesh_load(SPEC, 0, &f->dm, err);
  if (!rc) rc = bs_dfem_create(f->dm, 1, &mat, &tag, &f->df, err);
  if (rc) return rc;
  int32_t ns = f->m->n_vertices, nd = f->dm->n_vertices, nm = f->dm->local->n_vertices;
  f->xs = calloc(3 * (size_t)ns, sizeof(double));
  f->xd = calloc(3 * (size_t)nd, sizeof(double));
  f->ser.x_hat = calloc(3 * (size_t)ns, sizeof(double));
  f->ser.x_n = calloc(3 * (size_t)ns, sizeof(double));
  f->dis.x_hat = calloc(3 * (size_t)nm, sizeof(double));
  f->dis.x_n = calloc(3 * (size_t)nm, sizeof(double));
  double *tmp = calloc(3 * (size_t)nd, sizeof(double));
  for (int32_t v = 0; v < ns; v++) {
    field(v, f->m->x + 3 * v, 0.03, 0, f->xs + 3 * v);
    field(v, f->m->x + 3 * v, 0.02, 2, f->ser.x_hat + 3 * v);
    field(v, f->m->x + 3 * v, 0.01, 4, f->ser.x_n + 3 * v);
  }
  for (int32_t v = 0; v < nd; v++) memcpy(f->xd + 3 * v, f->xs + 3 * f->dm->orig_id[v], 3 * sizeof(double));
  for (int32_t v = 0; v < nd; v++) memcpy(tmp + 3 * v, f->ser.x_hat + 3 * f->dm->orig_id[v], 3 * sizeof(double));
  bs_dfem_mesh_vector(f->df, tmp, f->dis.x_hat);
  for (int32_t v = 0; v < nd; v++) memcpy(tmp + 3 * v, f->ser.x_n + 3 * f->dm->orig_id[v], 3 * sizeof(double));
  bs_dfem_mesh_vector(f->df, tmp, f->dis.x_n);
  free(tmp);
  rc = make_terms(f->fem, &f->ser, err);
  if (!rc) rc = make_terms(f->df->fem, &f->dis, err);
  if (!rc) bs_dfem_set_terms(f->df, 3, f->dis.terms, 0);
  return rc;
}

static void teardown(fixture *f) {
  free_side(&f->ser);
  free_side(&f->dis);
  bs_dfem_destroy(&f->df);
  bs_dmesh_destroy(&f->dm);
  bs_fem_destroy(&f->fem);
  bs_mesh_destroy(&f->m);
  free(f->xs);
  free(f->xd);
}

static double serial_energy(fixture *f, const double *x, double *g) {
  double E = 0;
  for (int i = 0; i < 3; i++) {
    double e = 0;
    if (g) f->ser.terms[i]->ops->gradient(f->ser.terms[i], x, &e, g);
    else f->ser.terms[i]->ops->value(f->ser.terms[i], x, &e);
    E += e;
  }
  return E;
}

/* max over local vertices of |d_v - s_orig(v)| / max |s|, over the ranks. */
static double vec_error(const fixture *f, const double *d, const double *s, int32_t ns) {
  double err = 0, scale = 0;
  for (int64_t i = 0; i < 3 * (int64_t)ns; i++) scale = fmax(scale, fabs(s[i]));
  for (int32_t v = 0; v < f->dm->n_vertices; v++)
    for (int k = 0; k < 3; k++) err = fmax(err, fabs(d[3 * v + k] - s[3 * f->dm->orig_id[v] + k]));
  MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return err / fmax(scale, 1e-300);
}

static void energy_gradient_match(void) {
  static const bs_model models[] = {BS_MODEL_FIXED_COROTATED, BS_MODEL_COROTATED, BS_MODEL_NEO_HOOKEAN,
                                    BS_MODEL_STABLE_NEO_HOOKEAN, BS_MODEL_LINEAR};
  for (int k = 0; k < 5; k++) {
    fixture f;
    bs_error err = {0};
    int rc = setup(&f, models[k], &err);
    CHECK_OK(rc, err);
    if (!rc) {
      int32_t ns = f.m->n_vertices;
      double *gs = calloc(3 * (size_t)ns, sizeof(double)), *gd = calloc(3 * (size_t)f.dm->n_vertices, sizeof(double));
      double Es = serial_energy(&f, f.xs, NULL), Ed = 0, Eg = 0;
      CHECK_OK(bs_dfem_value(f.df, f.xd, &Ed, &err), err);
      CHECK_REL(Ed, Es, 1e-12, bs_model_name(models[k]));
      serial_energy(&f, f.xs, gs);
      CHECK_OK(bs_dfem_gradient(f.df, f.xd, &Eg, gd, &err), err);
      CHECK_REL(Eg, Es, 1e-12, "energy with the gradient");
      double e = vec_error(&f, gd, gs, ns);
      CHECK(e <= 1e-12, "%s: gradient error %.3g", bs_model_name(models[k]), e);
      free(gs);
      free(gd);
    }
    teardown(&f);
  }
}

/* H v of the distributed matrix vs the serial bs_bsr; with the group xmin
 * fixed, fixed rows are v itself and free rows the serial masked product. */
static void hessian_vector_match(void) {
  fixture f;
  bs_error err = {0};
  int rc = setup(&f, BS_MODEL_NEO_HOOKEAN, &err);
  CHECK_OK(rc, err);
  int32_t ns = rc ? 0 : f.m->n_vertices, nd = rc ? 0 : f.dm->n_vertices;
  for (int fixed = 0; !rc && fixed < 2; fixed++) {
    uint8_t *ms = malloc((size_t)ns), *md = malloc((size_t)nd);
    memset(ms, 1, (size_t)ns);
    const bs_group *gx = bs_mesh_group(f.m, "xmin");
    for (int32_t i = 0; fixed && i < gx->n_vertices; i++) ms[gx->vertices[i]] = 0;
    for (int32_t v = 0; v < nd; v++) md[v] = ms[f.dm->orig_id[v]];
    double *vs = calloc(3 * (size_t)ns, sizeof(double)), *ys = calloc(3 * (size_t)ns, sizeof(double));
    double *vd = calloc(3 * (size_t)nd, sizeof(double)), *yd = calloc(3 * (size_t)nd, sizeof(double));
    for (int32_t v = 0; v < ns; v++) field(v, NULL, 1.0, 7, vs + 3 * v);
    for (int32_t v = 0; v < nd; v++) memcpy(vd + 3 * v, vs + 3 * f.dm->orig_id[v], 3 * sizeof(double));
    bs_bsr *H = NULL;
    CHECK_OK(bs_fem_matrix(f.fem, &H, &err), err);
    for (int i = 0; i < 3; i++) f.ser.terms[i]->ops->hessian(f.ser.terms[i], f.xs, H);
    bs_bsr_mul(H, ms, vs, ys);
    for (int32_t v = 0; v < ns; v++)
      if (!ms[v]) memcpy(ys + 3 * v, vs + 3 * v, 3 * sizeof(double));
    CHECK_OK(bs_dfem_hessian(f.df, f.xd, fixed ? md : NULL, &err), err);
    Vec a, b;
    MatCreateVecs(f.df->H, &a, &b);
    CHECK_OK(bs_dfem_to_global(f.df, vd, a, &err), err);
    MatMult(f.df->H, a, b);
    CHECK_OK(bs_dfem_from_global(f.df, b, yd, &err), err);
    double e = vec_error(&f, yd, ys, ns);
    CHECK(e <= 1e-12, "fixed %d: H v error %.3g", fixed, e);
    VecDestroy(&a);
    VecDestroy(&b);
    bs_bsr_destroy(&H);
    free(ms), free(md), free(vs), free(ys), free(vd), free(yd);
  }
  teardown(&f);
}

/* (E(x + h d) - E(x - h d)) / 2h = g.d on the distributed side alone. */
static void gradient_finite_difference(void) {
  fixture f;
  bs_error err = {0};
  int rc = setup(&f, BS_MODEL_STABLE_NEO_HOOKEAN, &err);
  CHECK_OK(rc, err);
  if (!rc) {
    int32_t nd = f.dm->n_vertices;
    double *d = calloc(3 * (size_t)nd, sizeof(double)), *g = calloc(3 * (size_t)nd, sizeof(double));
    double *xp = calloc(3 * (size_t)nd, sizeof(double)), *xm = calloc(3 * (size_t)nd, sizeof(double));
    for (int32_t v = 0; v < nd; v++) field(f.dm->orig_id[v], NULL, 1.0, 3, d + 3 * v);
    const double h = 1e-6;
    for (int64_t i = 0; i < 3 * (int64_t)nd; i++) xp[i] = f.xd[i] + h * d[i], xm[i] = f.xd[i] - h * d[i];
    double E, Ep, Em, gd;
    CHECK_OK(bs_dfem_gradient(f.df, f.xd, &E, g, &err), err);
    CHECK_OK(bs_dfem_value(f.df, xp, &Ep, &err), err);
    CHECK_OK(bs_dfem_value(f.df, xm, &Em, &err), err);
    CHECK_OK(bs_dfem_dot(f.df, g, d, &gd, &err), err);
    CHECK_REL((Ep - Em) / (2 * h), gd, 1e-6, "central difference vs g.d");
    free(d), free(g), free(xp), free(xm);
  }
  teardown(&f);
}

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"energy_gradient_match", energy_gradient_match},
                                    {"hessian_vector_match", hessian_vector_match},
                                    {"gradient_finite_difference", gradient_finite_difference}};
  return dist_check_main(argc, argv, tests, 3);
}
