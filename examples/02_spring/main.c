/* Example 2: an energy term of your own, plugged into the same minimizer.
 *
 * Read it top to bottom; README.md beside it shows what it prints.
 *
 * The term: zero-length springs of stiffness k (N/m) that pull each vertex v
 * of a group G toward its rest position moved by an offset d:
 *
 *     E(x) = k/2 sum_{v in G} |x_v - (X_v + d)|^2,
 *     dE/dx_v = k (x_v - X_v - d),   d2E/dx_v^2 = k I   (v in G; 0 elsewhere).
 *
 * A term gives its value, its gradient (added into g) and its Hessian (added
 * into a 3x3-block sparse matrix with the mesh's pattern), and returns a
 * status: BS_TERM_OK, or BS_TERM_NOT_EVALUABLE for an x outside its domain
 * (never a NaN in-band). We check the derivatives against finite differences,
 * as every term of bigstep is checked, then let the static solver find the
 * minimum of elasticity plus springs: with no other load, the body moves
 * rigidly by d, which we verify.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <bigstep/bigstep.h>

#define CHECK(call)                                   \
  do {                                                \
    if ((call) != 0) {                                \
      fprintf(stderr, "spring: %s\n", err.msg);       \
      exit(1);                                        \
    }                                                 \
  } while (0)

/* Step 1: the term's data and its three callbacks. */
typedef struct spring {
  int32_t n;          /* vertices of the group                 */
  const int32_t *v;   /* their indices (the mesh's group list) */
  const double *rest; /* rest positions, 3 per vertex          */
  double k, d[3];     /* stiffness (N/m), offset (m)           */
} spring;

static int spring_value(const bs_term *t, const double *x, double *E) {
  const spring *s = t->data;
  double e = 0;
  for (int32_t i = 0; i < s->n; i++)
    for (int c = 0; c < 3; c++) {
      const int32_t j = 3 * s->v[i] + c;
      const double r = x[j] - s->rest[j] - s->d[c];
      e += 0.5 * s->k * r * r;
    }
  if (!isfinite(e)) return BS_TERM_NOT_EVALUABLE; /* a non-finite x: say so */
  *E = e;
  return BS_TERM_OK;
}

static int spring_gradient(const bs_term *t, const double *x, double *E, double *g) {
  const spring *s = t->data;
  int st = spring_value(t, x, E);
  if (st) return st;
  for (int32_t i = 0; i < s->n; i++)
    for (int c = 0; c < 3; c++) {
      const int32_t j = 3 * s->v[i] + c;
      g[j] += s->k * (x[j] - s->rest[j] - s->d[c]); /* ADDED into g */
    }
  return BS_TERM_OK;
}

static int spring_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  (void)x; /* the springs' Hessian is constant */
  const spring *s = t->data;
  for (int32_t i = 0; i < s->n; i++) {
    double *B = H->val + 9 * (size_t)H->diag[s->v[i]]; /* the (v, v) block, row-major */
    for (int c = 0; c < 3; c++) B[4 * c] += s->k;
  }
  return BS_TERM_OK;
}

static const bs_term_ops spring_ops = {spring_value, spring_gradient, spring_hessian, NULL, free, NULL, NULL, NULL,
                                       NULL, NULL};

/* Step 2: finite differences. The gradient against central differences of E
 * along a random direction p, and the Hessian against differences of the
 * gradient: |(g(x + h p) - g(x - h p)) / 2h - H p| / |H p|. */
static double frand(unsigned *seed) { return (*seed = *seed * 1103515245u + 12345u) / 4294967296.0 - 0.5; }

static void fd_check(const bs_term *t, int32_t nv, const double *x0, double *grad_err, double *hess_err) {
  const size_t n = 3 * (size_t)nv;
  double *x = malloc(n * sizeof *x), *p = malloc(n * sizeof *p), *gp = calloc(n, sizeof *gp),
         *gm = calloc(n, sizeof *gm), *g = calloc(n, sizeof *g), Ep, Em, E;
  unsigned seed = 7;
  for (size_t i = 0; i < n; i++) {
    x[i] = x0[i] + 0.1 * frand(&seed);
    p[i] = frand(&seed);
  }
  /* Each callback returns a status: check it, as the minimizer does. */
  if (t->ops->gradient(t, x, &E, g) != BS_TERM_OK) exit(1);
  const double h = 1e-5;
  double gdotp = 0;
  for (size_t i = 0; i < n; i++) gdotp += g[i] * p[i];
  for (size_t i = 0; i < n; i++) x[i] += h * p[i];
  if (t->ops->gradient(t, x, &Ep, gp) != BS_TERM_OK) exit(1);
  for (size_t i = 0; i < n; i++) x[i] -= 2 * h * p[i];
  if (t->ops->gradient(t, x, &Em, gm) != BS_TERM_OK) exit(1);
  for (size_t i = 0; i < n; i++) x[i] += h * p[i];
  *grad_err = fabs((Ep - Em) / (2 * h) - gdotp) / fabs(gdotp);
  bs_bsr *H = NULL;
  bs_error err;
  CHECK(bs_fem_matrix(t->fem, &H, &err));
  if (t->ops->hessian(t, x, H) != BS_TERM_OK) exit(1);
  double *Hp = calloc(n, sizeof *Hp), num = 0, den = 0;
  bs_bsr_mul(H, NULL, p, Hp);
  for (size_t i = 0; i < n; i++) {
    const double fd = (gp[i] - gm[i]) / (2 * h);
    num += (fd - Hp[i]) * (fd - Hp[i]);
    den += Hp[i] * Hp[i];
  }
  *hess_err = sqrt(num / den);
  bs_bsr_destroy(&H);
  free(x), free(p), free(gp), free(gm), free(g), free(Hp);
}

int main(void) {
  bs_error err;
  /* Step 3: a scene built in C: a unit cube of 4^3 cells, neo-Hookean, no
     gravity, solved statically. No group is scripted: only our springs hold
     the body, so without them the problem would have no unique minimum. */
  bs_scene *sc = NULL;
  bs_scene_body *b = NULL;
  CHECK(bs_scene_create(&sc, &err));
  CHECK(bs_scene_add_body(sc, "box", &b, &err));
  b->materials[0] = (bs_scene_material){.model = BS_MODEL_NEO_HOOKEAN, .youngs = 1e5, .poisson = 0.3,
                                        .density = 1000};
  sc->gravity[1] = 0;
  sc->mode = BS_MODE_STATIC;
  sc->solver.min.tol = 1e-9;
  CHECK(bs_scene_validate(sc, &err));
  bs_sim *s = NULL;
  CHECK(bs_sim_create(sc, &s, &err));

  /* Step 4: the term on the group "xmax" (the face x = 1 of the box), made on
     the simulation's fem cache and handed over: the simulation owns it now. */
  const bs_group *face = bs_mesh_group(s->mesh, "xmax");
  spring *sp = malloc(sizeof *sp);
  *sp = (spring){.n = face->n_vertices, .v = face->vertices, .rest = s->x0, .k = 1e4, .d = {0.2, -0.1, 0.05}};
  bs_term *t = NULL;
  CHECK(bs_term_create("spring", &spring_ops, s->fem, &s->step, sp, &t, &err));
  double ge, he;
  fd_check(t, s->mesh->n_vertices, s->x0, &ge, &he);
  printf("finite differences: gradient relative error %.1e, Hessian relative error %.1e\n", ge, he);
  CHECK(bs_sim_add_term(s, t, &err));

  /* Step 5: the static solve, then the answer: every vertex moved by d. */
  bs_frame_stats fs;
  CHECK(bs_sim_statics(s, &fs, &err));
  double worst = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(s->x[3 * v + c] - s->x0[3 * v + c] - sp->d[c]));
  printf("static solve: %s in %ld Newton iterations, |grad E| %.1e N\n", fs.failed ? "FAILED" : "converged",
         fs.iterations, fs.grad_max);
  printf("largest distance from the rigid motion by d: %.1e m\n", worst);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return fs.failed != 0;
}
