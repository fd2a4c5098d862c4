/* test_tet10_order.c — the convergence order of tet10 on a smooth problem.
 *
 * A manufactured solution of linear elasticity on the unit cube: the
 * displacement u(X) = a phi(X), phi = sin(pi x) sin(pi y) sin(pi z), which
 * vanishes on the boundary (every face is fixed), under the body force
 * b = -div sigma(u) = -(mu lap u + (lambda + mu) grad div u), added to the
 * scene as a caller's energy term -sum_a f_a . (x_a - X_a) with the
 * consistent load f_a = int N_a b dV (14-point rule, degree 5). The static
 * solution of the whole pipeline (scene, quadratic mesh, fem, minimizer) is
 * compared with u in L2 (the 14-point rule again, per element) at 2, 4 and 8
 * cells per side: P2 elements converge at order 3 in L2 (and 2 in H1), so the
 * observed order between the two finer meshes must be near 3. */
#define _GNU_SOURCE /* M_PI */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_mesh.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_terms.h"
#include "bs_tet10.h"
#include "sim_util.h"

static const double amp[3] = {1e-3, -2e-3, 1.5e-3}; /* a (m)          */
static const double E_young = 1e6, nu = 0.3;          /* the material   */

/* phi and its second derivatives at p (the cube's coordinates, [0, 1]^3). */
static double phi_hess(const double p[3], double H[3][3]) {
  double s[3], c[3];
  for (int i = 0; i < 3; i++) {
    s[i] = sin(M_PI * p[i]);
    c[i] = cos(M_PI * p[i]);
  }
  const double ph = s[0] * s[1] * s[2], pi2 = M_PI * M_PI;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      if (i == j) H[i][j] = -pi2 * ph;
      else H[i][j] = pi2 * c[i] * c[j] * s[3 - i - j];
    }
  return ph;
}

/* b = -(mu lap u + (lambda + mu) grad div u) at p. */
static void body_force(const double p[3], double b[3]) {
  const double mu = E_young / (2 * (1 + nu)), lam = E_young * nu / ((1 + nu) * (1 - 2 * nu));
  double H[3][3];
  phi_hess(p, H);
  const double lap = H[0][0] + H[1][1] + H[2][2];
  for (int i = 0; i < 3; i++) {
    double gd = 0;
    for (int j = 0; j < 3; j++) gd += amp[j] * H[i][j];
    b[i] = -(mu * amp[i] * lap + (lam + mu) * gd);
  }
}

/* ---- the load as a caller's term: E = -f . (x - X) ---- */

typedef struct load {
  const double *X, *f;
  int64_t n3;
} load;

static int load_value(const bs_term *t, const double *x, double *E) {
  const load *L = t->data;
  double e = 0;
  for (int64_t i = 0; i < L->n3; i++) e -= L->f[i] * (x[i] - L->X[i]);
  *E = e;
  return BS_TERM_OK;
}
static int load_gradient(const bs_term *t, const double *x, double *E, double *g) {
  const load *L = t->data;
  for (int64_t i = 0; i < L->n3; i++) g[i] -= L->f[i];
  return load_value(t, x, E);
}
static int load_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  (void)t, (void)x, (void)H;
  return BS_TERM_OK;
}
static const bs_term_ops load_ops = {load_value, load_gradient, load_hessian, NULL, NULL, NULL, NULL, NULL, NULL, NULL};

/* Element t's 10 rest nodes, its 14-point rest cache; the cube's corner lo. */
static void element(const bs_sim *s, int32_t t, double X[30], bs_tet10_rest *r) {
  for (int a = 0; a < 10; a++) memcpy(X + 3 * a, s->x0 + 3 * (size_t)s->mesh->tets10[10 * t + a], 3 * sizeof(double));
  bs_error err;
  cr_assert_eq(bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, r, &err), 0, "%s", err.msg);
}

/* Quadrature point q of the element with nodes X: its shape values N and
 * its position p in the cube's coordinates (lo its corner). */
static void point(const bs_tet10_rule *R, int q, const double X[30], const double lo[3], double N[10], double p[3]) {
  bs_tet10_shape(R->xi[q], N);
  bs_tet10_map(X, R->xi[q], p);
  for (int i = 0; i < 3; i++) p[i] -= lo[i];
}

static void consistent_load(const bs_sim *s, const double lo[3], double *f) {
  const bs_tet10_rule *R = bs_tet10_rule_get(BS_TET10_RULE_14PT_DEG5);
  for (int32_t t = 0; t < s->mesh->n_tets; t++) {
    double X[30], N[10], p[3], b[3];
    bs_tet10_rest r;
    element(s, t, X, &r);
    for (int q = 0; q < R->n_points; q++) {
      point(R, q, X, lo, N, p);
      body_force(p, b);
      for (int a = 0; a < 10; a++)
        for (int i = 0; i < 3; i++) f[3 * (size_t)s->mesh->tets10[10 * t + a] + i] += r.wdetJ[q] * N[a] * b[i];
    }
  }
}

/* ||u_h - u||_L2 and ||u||_L2 over the cube (14-point rule per element). */
static double l2_error(const bs_sim *s, const double lo[3], double *norm_u) {
  const bs_tet10_rule *R = bs_tet10_rule_get(BS_TET10_RULE_14PT_DEG5);
  double e2 = 0, u2 = 0;
  for (int32_t t = 0; t < s->mesh->n_tets; t++) {
    double X[30], N[10], p[3], H[3][3];
    bs_tet10_rest r;
    element(s, t, X, &r);
    for (int q = 0; q < R->n_points; q++) {
      point(R, q, X, lo, N, p);
      const double ph = phi_hess(p, H);
      for (int i = 0; i < 3; i++) {
        double uh = 0;
        for (int a = 0; a < 10; a++) {
          const size_t n = (size_t)s->mesh->tets10[10 * t + a];
          uh += N[a] * (s->x[3 * n + i] - s->x0[3 * n + i]);
        }
        e2 += r.wdetJ[q] * (uh - amp[i] * ph) * (uh - amp[i] * ph);
        u2 += r.wdetJ[q] * amp[i] * ph * amp[i] * ph;
      }
    }
  }
  *norm_u = sqrt(u2);
  return sqrt(e2);
}

static const char *const cube_scene =
    "{\"time\": {\"fps\": 1, \"frames\": 1, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"newton\", \"linear\": \"cholmod\", \"tolerance\": 1e-8, \"mode\": \"static\"},\n"
    " \"gravity\": [0, 0, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [%d, %d, %d], \"size\": [1, 1, 1]}, \"element\": \"tet10\",\n"
    "   \"material\": {\"model\": \"linear\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}, {\"group\": \"xmax\", \"fixed\": true},\n"
    "                {\"group\": \"ymin\", \"fixed\": true}, {\"group\": \"ymax\", \"fixed\": true},\n"
    "                {\"group\": \"zmin\", \"fixed\": true}, {\"group\": \"zmax\", \"fixed\": true}]}]}\n";

/* The relative L2 error of the static solution on n^3 cells; *nodes out. */
static double solve_cube(int n, int32_t *nodes) {
  char text[2048];
  snprintf(text, sizeof text, cube_scene, n, n, n);
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "cube", &sc);
  bs_term *t = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert(s->mesh->tets10, "the mesh is not quadratic");
  const int64_t n3 = 3 * (int64_t)s->mesh->n_vertices;
  double lo[3], hi[3], *f = calloc((size_t)n3, sizeof(double));
  cr_assert(f);
  bs_bbox(s->mesh->n_vertices, s->x0, lo, hi);
  cr_assert_float_eq(hi[0] - lo[0], 1.0, 1e-12);
  consistent_load(s, lo, f);
  load L = {s->x0, f, n3};
  cr_assert_eq(bs_term_create("manufactured_load", &load_ops, s->fem, &s->step, &L, &t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_add_term(s, t, &err), 0, "%s", err.msg);
  bs_frame_stats fs;
  cr_assert_eq(bs_sim_statics(s, &fs, &err), 0, "%s", err.msg);
  cr_assert_eq(fs.failed, 0, "the static solve on %d^3 cells failed: %s", n, fs.steps[0].reason);
  double norm_u;
  const double e = l2_error(s, lo, &norm_u);
  *nodes = s->mesh->n_vertices;
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  free(f);
  return e / norm_u;
}

Test(tet10_order, manufactured_solution_converges_at_order_three_in_l2) {
  const int cells[3] = {2, 4, 8};
  double e[3];
  int32_t nodes[3];
  for (int k = 0; k < 3; k++) e[k] = solve_cube(cells[k], &nodes[k]);
  const double p1 = log2(e[0] / e[1]), p2 = log2(e[1] / e[2]);
  cr_log_info("tet10 manufactured solution, relative L2 error: %.3e (%d nodes), %.3e (%d), %.3e (%d); order %.2f, %.2f",
              e[0], nodes[0], e[1], nodes[1], e[2], nodes[2], p1, p2);
  cr_expect(p2 > 2.7 && p2 < 3.5, "observed L2 order %.2f between 4 and 8 cells per side, expected ~3", p2);
  cr_expect(p1 > 2.0, "observed L2 order %.2f between 2 and 4 cells per side", p1);
  cr_expect_lt(e[2], 5e-3, "relative L2 error %.3e on 8^3 cells", e[2]);
}
