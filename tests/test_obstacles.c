/* Collisions with obstacles (paper 3.2, 5.1, 5.2, Figure 10): the projection
 * lands on phi = 0 and is idempotent, scripted vertices stay; the projected
 * gradient and Hessian are the derivatives of E'(P(x)) (finite differences,
 * O(h^2), the curvature term matters on a sphere); a body dropped on the
 * ground with constraint / penalty / postprocess collisions; a hit at
 * 1e3 m/s; Coulomb friction (deceleration mu g, no energy gain, positions
 * untouched, mu = 0 inert); error messages; the fem split over two
 * "processes" by owned vertices sums to the unsplit answers. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_obstacles.h"
#include "bs_penalty.h"
#include "bs_step.h"
#include "bs_terms.h"
#include "bs_vec3.h"
#include "test_term_eval.h"

typedef struct sim {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_material mat;
  bs_step_data step;
  bs_term *own[3];
  int n_own;
  bs_term *terms[8];
  int n_terms;
  bs_obstacles *obs;
  bs_integrator *I;
  bs_step_hooks hooks;
  uint8_t *mask;
  double *x, *v;
  int32_t nv;
} sim;

static void sim_create(sim *s, const double lo[3], const double hi[3], int nc, double youngs, const double g[3]) {
  bs_error err;
  memset(s, 0, sizeof *s);
  cr_assert_eq(bs_mesh_create_box(lo, hi, nc, nc, nc, &s->mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, youngs, 0.3, 1000, &s->mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(s->mesh, 1, &s->mat, NULL, &s->fem, &err), 0, "%s", err.msg);
  s->nv = s->fem->n_vertices;
  cr_assert_eq(bs_term_inertia_create(s->fem, &s->step, &s->own[s->n_own++], &err), 0, "%s", err.msg);
  if (g) cr_assert_eq(bs_term_gravity_create(s->fem, &s->step, g, &s->own[s->n_own++], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_elastic_create(s->fem, 0, &s->own[s->n_own++], &err), 0, "%s", err.msg);
  s->mask = malloc((size_t)s->nv);
  memset(s->mask, 1, (size_t)s->nv);
  s->x = malloc(sizeof(double) * 3 * (size_t)s->nv);
  s->v = calloc(3 * (size_t)s->nv, sizeof(double));
  memcpy(s->x, s->mesh->x, sizeof(double) * 3 * (size_t)s->nv);
  cr_assert_eq(bs_obstacles_create(s->fem, &s->step, s->mask, &s->obs, &err), 0, "%s", err.msg);
}

/* After the obstacles are added: the integrator with the penalty terms and hooks. */
static void sim_finish(sim *s, double tol, int with_post_solve) {
  bs_error err;
  for (int i = 0; i < s->n_own; i++) s->terms[s->n_terms++] = s->own[i];
  bs_term *const *pt;
  int np = bs_obstacles_terms(s->obs, &pt);
  for (int i = 0; i < np; i++) s->terms[s->n_terms++] = pt[i];
  bs_integrator_opts o;
  bs_integrator_opts_default(&o);
  o.min.tol = tol;
  cr_assert_eq(bs_integrator_create(s->fem, &s->step, s->n_terms, s->terms, s->mask, NULL, NULL, &o, &s->I, &err), 0,
               "%s", err.msg);
  bs_obstacles_hooks(s->obs, &s->hooks);
  if (!with_post_solve) s->hooks.post_solve = NULL;
  bs_integrator_set_hooks(s->I, &s->hooks);
}

static void sim_destroy(sim *s) {
  bs_integrator_destroy(&s->I);
  bs_obstacles_destroy(&s->obs);
  for (int i = 0; i < s->n_own; i++) bs_term_destroy(&s->own[i]);
  bs_fem_destroy(&s->fem);
  bs_mesh_destroy(&s->mesh);
  free(s->mask);
  free(s->x);
  free(s->v);
}

static void add(sim *s, bs_levelset *ls, bs_collide_mode mode, double k, double mu) {
  bs_error err;
  cr_assert_eq(bs_obstacles_add(s->obs, ls, mode, k, mu, &err), 0, "%s", err.msg);
}

static bs_levelset *ground(double y) {
  bs_levelset *ls;
  bs_error err;
  double n[3] = {0, 1, 0};
  cr_assert_eq(bs_levelset_create_halfspace(n, y, &ls, &err), 0, "%s", err.msg);
  return ls;
}

/* grad E'(x) over all terms of s (unprojected). */
static double sim_gradient(sim *s, const double *x, double *g) {
  memset(g, 0, sizeof(double) * 3 * (size_t)s->nv);
  double E = 0;
  for (int i = 0; i < s->n_terms; i++) E += term_gradient(s->terms[i], x, g);
  return E;
}

static double sim_value(sim *s, const double *x) {
  double E = 0;
  for (int i = 0; i < s->n_terms; i++) E += term_value(s->terms[i], x);
  return E;
}

static double urand(unsigned *st) {
  *st = *st * 1103515245u + 12345u;
  return ((*st >> 8) & 0xffffff) / (double)0x1000000;
}

/* ---- mode names, errors ------------------------------------------------------ */

Test(obstacles, mode_parse) {
  bs_collide_mode m;
  bs_error err;
  cr_assert_eq(bs_collide_mode_parse("constraint", &m, &err), 0);
  cr_assert_eq(m, BS_COLLIDE_CONSTRAINT);
  cr_assert_eq(bs_collide_mode_parse("penalty", &m, &err), 0);
  cr_assert_eq(m, BS_COLLIDE_PENALTY);
  cr_assert_eq(bs_collide_mode_parse("postprocess", &m, &err), 0);
  cr_assert_eq(m, BS_COLLIDE_POSTPROCESS);
  cr_assert_str_eq(bs_collide_mode_name(BS_COLLIDE_POSTPROCESS), "postprocess");
  cr_assert_eq(bs_collide_mode_parse("springs", &m, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "'springs'"), "%s", err.msg);
}

Test(obstacles, errors_name_the_obstacle) {
  sim s;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  sim_create(&s, lo, hi, 1, 1e4, NULL);
  bs_error err;
  add(&s, ground(-1), BS_COLLIDE_CONSTRAINT, 0, 0.1); /* obstacle 0 */
  /* a grid level set as a constraint: refused, naming obstacle 1 and its kind */
  double o3[3] = {-1, -1, -1}, vals[8];
  int32_t n3[3] = {2, 2, 2};
  for (int i = 0; i < 8; i++) vals[i] = 0.5;
  bs_levelset *grid;
  cr_assert_eq(bs_levelset_grid_from_values(o3, 2.0, n3, vals, &grid, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_obstacles_add(s.obs, grid, BS_COLLIDE_CONSTRAINT, 0, 0, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacle 1 (grid)") && strstr(err.msg, "analytic"), "%s", err.msg);
  /* negative friction */
  cr_assert_eq(bs_obstacles_add(s.obs, ground(-2), BS_COLLIDE_PENALTY, 1e5, -0.5, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacle 1 (halfspace)") && strstr(err.msg, "friction = -0.5"), "%s", err.msg);
  /* a bad penalty stiffness is reported with the obstacle's name */
  cr_assert_eq(bs_obstacles_add(s.obs, ground(-2), BS_COLLIDE_PENALTY, -3, 0, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacle 1 (halfspace)"), "%s", err.msg);
  cr_assert_eq(bs_obstacles_count(s.obs), 1);
  /* a grid is fine as a penalty */
  cr_assert_eq(bs_levelset_grid_from_values(o3, 2.0, n3, vals, &grid, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_obstacles_add(s.obs, grid, BS_COLLIDE_PENALTY, 1e5, 0, &err), 0, "%s", err.msg);
  bs_term *const *pt;
  cr_assert_eq(bs_obstacles_terms(s.obs, &pt), 1);
  cr_assert(bs_term_is_penalty(pt[0]));
  sim_destroy(&s);
  bs_obstacles_destroy(&s.obs); /* NULL is accepted */
}

/* ---- projection ------------------------------------------------------------- */

static void check_projection(bs_levelset *ls, const char *what) {
  sim s;
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  sim_create(&s, lo, hi, 4, 1e4, NULL); /* 125 vertices, used as a point cloud */
  for (int32_t p = 0; p < s.nv; p += 7) s.mask[p] = 0;
  bs_obstacles_destroy(&s.obs);
  bs_error err;
  cr_assert_eq(bs_obstacles_create(s.fem, &s.step, s.mask, &s.obs, &err), 0, "%s", err.msg);
  s.step.time = 0.25;
  const bs_levelset *L = ls;
  add(&s, ls, BS_COLLIDE_CONSTRAINT, 0, 0);
  unsigned seed = 7;
  double *x = s.x, *x0 = malloc(sizeof(double) * 3 * (size_t)s.nv), *x1 = malloc(sizeof(double) * 3 * (size_t)s.nv);
  for (int32_t i = 0; i < 3 * s.nv; i++) x[i] = -1.5 + 3 * urand(&seed);
  memcpy(x0, x, sizeof(double) * 3 * (size_t)s.nv);
  bs_obstacles_project(x, s.obs);
  int moved = 0, kept = 0;
  for (int32_t p = 0; p < s.nv; p++) {
    double phi0 = bs_levelset_eval(L, s.step.time, x0 + 3 * p, NULL, NULL);
    double phi1 = bs_levelset_eval(L, s.step.time, x + 3 * p, NULL, NULL);
    double dx = fabs(x[3 * p] - x0[3 * p]) + fabs(x[3 * p + 1] - x0[3 * p + 1]) + fabs(x[3 * p + 2] - x0[3 * p + 2]);
    if (!s.mask[p]) {
      cr_assert_eq(dx, 0, "%s: scripted vertex %d moved", what, p);
    } else if (phi0 < 0) {
      cr_assert(fabs(phi1) < 1e-12, "%s: vertex %d lands at phi = %g", what, p, phi1);
      moved++;
    } else {
      cr_assert_eq(dx, 0, "%s: feasible vertex %d moved", what, p);
      kept++;
    }
  }
  cr_assert(moved > 5 && kept > 5, "%s: %d moved, %d kept: the cloud must straddle the surface", what, moved, kept);
  /* idempotent */
  memcpy(x1, x, sizeof(double) * 3 * (size_t)s.nv);
  bs_obstacles_project(x1, s.obs);
  for (int32_t i = 0; i < 3 * s.nv; i++) cr_assert(fabs(x1[i] - x[i]) < 1e-12, "%s: P(P(x)) != P(x) at dof %d", what, i);
  int32_t cnt;
  double depth;
  bs_obstacles_penetration(s.obs, s.step.time, x, 0, &cnt, &depth);
  cr_assert(depth < 1e-12, "%s: depth %g after projection", what, depth);
  bs_obstacles_penetration(s.obs, s.step.time, x0, 0, &cnt, &depth);
  cr_assert(cnt >= moved && depth > 0.05, "%s: audit before projection: %d inside, depth %g", what, cnt, depth);
  free(x0);
  free(x1);
  sim_destroy(&s);
}

Test(obstacles, projection_lands_on_surface_and_is_idempotent) {
  bs_error err;
  bs_levelset *ls;
  double c[3] = {0.1, -0.2, 0.05}, half[3] = {0.6, 0.4, 0.8}, n[3] = {0.3, 1, -0.2}, w[3] = {0, 0, 1}, vel[3] = {0.2, 0, 0};
  cr_assert_eq(bs_levelset_create_sphere(c, 0.9, &ls, &err), 0);
  check_projection(ls, "sphere");
  cr_assert_eq(bs_levelset_create_box(c, half, &ls, &err), 0);
  cr_assert_eq(bs_levelset_set_velocity(ls, vel, w, &err), 0); /* evaluated at t = 0.25 */
  check_projection(ls, "moving box");
  cr_assert_eq(bs_levelset_create_halfspace(n, 0.1, &ls, &err), 0);
  check_projection(ls, "half-space");
  cr_assert_eq(bs_levelset_create_sphere(c, 1.2, &ls, &err), 0);
  bs_levelset_set_complement(ls, 1);
  check_projection(ls, "complement of a sphere (bowl)");
}

/* ---- derivatives of E = E' o P ------------------------------------------------ */

/* The exact grad E(y) = J_P(y)^T g'(P(y)) for one sphere, with J_P(y) =
 * I - n n^T - phi A at y for the pairs P projects (active or violated). */
static void exact_grad_E(sim *s, const bs_levelset *ls, const double *y, double *gE, double *py, double *gp) {
  memcpy(py, y, sizeof(double) * 3 * (size_t)s->nv);
  bs_obstacles_project(py, s->obs);
  sim_gradient(s, py, gp);
  memcpy(gE, gp, sizeof(double) * 3 * (size_t)s->nv);
  for (int32_t p = 0; p < s->nv; p++) {
    double n[3], A[9];
    double phi = bs_levelset_eval(ls, s->step.time, y + 3 * p, n, A);
    int moved = py[3 * p] != y[3 * p] || py[3 * p + 1] != y[3 * p + 1] || py[3 * p + 2] != y[3 * p + 2];
    if (!moved && phi != 0) continue;
    const double *g = gp + 3 * p;
    double gn = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
    for (int k = 0; k < 3; k++) {
      double Ag = A[3 * k] * g[0] + A[3 * k + 1] * g[1] + A[3 * k + 2] * g[2];
      gE[3 * p + k] = g[k] - gn * n[k] - phi * Ag;
    }
  }
}

/* A 2x2x2-cell body pressed onto a sphere (constraint): step data with
 * x_hat a little above the rest shape, dt = 1/24, and a feasible x (the body
 * perturbed, its bottom layer pushed into the sphere and projected). Returns
 * the sphere; xn, xh are the step's (freed by the caller). */
static const bs_levelset *sphere_contact(sim *s, double **xn, double **xh, unsigned *seed) {
  double lo[3] = {-0.2, 0.0, -0.2}, hi[3] = {0.2, 0.3, 0.2}, grav[3] = {0, -40, 0};
  sim_create(s, lo, hi, 2, 2e3, grav);
  const double R = 0.5, cen[3] = {0, -R, 0};
  bs_levelset *ls;
  bs_error err;
  cr_assert_eq(bs_levelset_create_sphere(cen, R, &ls, &err), 0);
  add(s, ls, BS_COLLIDE_CONSTRAINT, 0, 0);
  sim_finish(s, 1e-6, 1);
  size_t n3 = 3 * (size_t)s->nv;
  *xn = malloc(sizeof(double) * n3);
  *xh = malloc(sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) {
    (*xn)[i] = s->mesh->x[i];
    (*xh)[i] = s->mesh->x[i] + 0.01 * (urand(seed) - 0.5);
  }
  s->step.dt = 1.0 / 24;
  s->step.time = 1.0 / 24;
  s->step.x_n = *xn;
  s->step.x_hat = *xh;
  s->step.load = 1;
  double *x = s->x;
  for (size_t i = 0; i < n3; i++) x[i] = s->mesh->x[i] + 0.004 * (urand(seed) - 0.5);
  for (int32_t p = 0; p < s->nv; p++)
    if (s->mesh->x[3 * p + 1] == 0) x[3 * p + 1] -= 0.05; /* into the sphere */
  bs_obstacles_project(x, s->obs);
  return ls;
}

/* Whether vertex p of x is in an active pair of the sphere (touching within
 * tol, g'.n >= 0); asserts feasibility; n: the normal. */
static int sphere_active(const sim *s, const bs_levelset *L, const double *x, const double *g, int32_t p,
                         double tol, int *touch, double n[3]) {
  double phi = bs_levelset_eval(L, s->step.time, x + 3 * p, n, NULL);
  cr_assert(phi > -1e-12, "x not feasible at vertex %d (phi %g)", p, phi);
  *touch = fabs(phi) < tol;
  return *touch && bs_dot3(g + 3 * p, n) >= 0;
}

/* A random direction, zero on touching-but-inactive vertices (which could
 * separate or be projected: E has a kink there), on the tangent space of the
 * active pairs (J d = d: where the hook's H is exact). Returns the number of
 * touching-but-inactive vertices. */
static int tangent_direction(sim *s, const bs_levelset *L, const double *g, double tol, unsigned *seed, double *d) {
  int touching_inactive = 0;
  for (int32_t p = 0; p < s->nv; p++) {
    double n[3];
    int touch, act = sphere_active(s, L, s->x, g, p, tol, &touch, n);
    for (int k = 0; k < 3; k++) d[3 * p + k] = (touch && !act) ? 0 : urand(seed) - 0.5;
    touching_inactive += touch && !act;
  }
  bs_obstacles_project_gradient(s->x, d, s->obs);
  return touching_inactive;
}

/* J^T H' J d, the Hessian without the curvature term, for contrast (v: scratch). */
static void hessian_without_curvature(sim *s, const double *d, double *v, double *out) {
  bs_error err;
  memcpy(v, d, sizeof(double) * 3 * (size_t)s->nv);
  bs_obstacles_project_gradient(s->x, v, s->obs); /* J symmetric per vertex */
  bs_bsr *H2;
  cr_assert_eq(bs_fem_matrix(s->fem, &H2, &err), 0);
  for (int i = 0; i < s->n_terms; i++) term_hessian(s->terms[i], s->x, H2);
  bs_bsr_mul(H2, NULL, v, out);
  bs_obstacles_project_gradient(s->x, out, s->obs);
  bs_bsr_destroy(&H2);
}

/* Rows and columns along an active normal are zero: (H v)_p . n_p = 0 for any
 * v (the paper's full curvature term C couples n_p to the tangent plane,
 * C n = -A g'). v, Hv: scratch. */
static void check_normal_rows(sim *s, const bs_levelset *L, const bs_bsr *H, const double *g, double tol,
                              unsigned *seed, double *v, double *Hv) {
  size_t n3 = 3 * (size_t)s->nv;
  for (size_t i = 0; i < n3; i++) v[i] = urand(seed) - 0.5;
  bs_bsr_mul(H, NULL, v, Hv);
  double hv_max = 0, hv_n = 0;
  for (size_t i = 0; i < n3; i++) hv_max = fmax(hv_max, fabs(Hv[i]));
  for (int32_t p = 0; p < s->nv; p++) {
    double n[3];
    int touch;
    if (sphere_active(s, L, s->x, g, p, tol, &touch, n)) hv_n = fmax(hv_n, fabs(bs_dot3(Hv + 3 * p, n)));
  }
  cr_log_info("normal rows: max |(H v)_p . n_p| %.3e against max |H v| %.3e\n", hv_n, hv_max);
  cr_assert(hv_n <= 1e-12 * hv_max, "an active normal's row is not zero: %g against %g", hv_n, hv_max);
}

/* The FD check at one h along d: value, slope and Hessian of E = E' o P. */
typedef struct fd_check {
  sim *s;
  const bs_levelset *L;
  const double *g, *d, *Hd, *HdJ; /* g': the raw gradient at x */
  double E0, gEd, dHd, nHd;
  double *w1, *w2, *w3, *w4, *gE; /* scratch */
} fd_check;

/* Relative errors at h: eg (slope), ev (d^T H d), eh (H d against J^T of the
 * gradient's central difference), ec (the same for J^T H' J d). */
static void fd_errors(const fd_check *c, double h, double *eg, double *ev, double *eh, double *ec) {
  sim *s = c->s;
  const double *x = s->x;
  size_t n3 = 3 * (size_t)s->nv;
  for (size_t i = 0; i < n3; i++) {
    c->w1[i] = x[i] + h * c->d[i];
    c->w2[i] = x[i] - h * c->d[i];
  }
  memcpy(c->w3, c->w1, sizeof(double) * n3); /* value FD of E'(P(.)) */
  bs_obstacles_project(c->w3, s->obs);
  double Ep = sim_value(s, c->w3);
  memcpy(c->w3, c->w2, sizeof(double) * n3);
  bs_obstacles_project(c->w3, s->obs);
  double Em = sim_value(s, c->w3);
  *eg = fabs((Ep - Em) / (2 * h) - c->gEd) / fabs(c->gEd);
  *ev = fabs((Ep - 2 * c->E0 + Em) / (h * h) - c->dHd) / fabs(c->dHd);
  /* gradient FD: exact grad E at x +- h d */
  double *gp = malloc(sizeof(double) * n3);
  exact_grad_E(s, c->L, c->w1, gp, c->w3, c->w4);
  exact_grad_E(s, c->L, c->w2, c->gE, c->w3, c->w4);
  for (size_t i = 0; i < n3; i++) gp[i] = (gp[i] - c->gE[i]) / (2 * h);
  /* FD mutated the recorded pairs: restore the labels at x, then compare on
   * the tangent space (J^T of the FD Hessian column) */
  bs_obstacles_register_active(x, c->g, s->obs);
  bs_obstacles_project_gradient(x, gp, s->obs);
  double e = 0, ecu = 0;
  for (size_t i = 0; i < n3; i++) {
    e += (gp[i] - c->Hd[i]) * (gp[i] - c->Hd[i]);
    ecu += (gp[i] - c->HdJ[i]) * (gp[i] - c->HdJ[i]);
  }
  free(gp);
  *eh = sqrt(e) / c->nHd;
  *ec = sqrt(ecu) / c->nHd;
}

Test(obstacles, projected_gradient_and_hessian_match_finite_differences) {
  sim s;
  double *xn, *xh;
  unsigned seed = 3;
  const bs_levelset *L = sphere_contact(&s, &xn, &xh, &seed);
  size_t n3 = 3 * (size_t)s.nv;
  const double *x = s.x;
  double *g = malloc(sizeof(double) * n3), *gE = malloc(sizeof(double) * n3), *d = malloc(sizeof(double) * n3);
  double *w1 = malloc(sizeof(double) * n3), *w2 = malloc(sizeof(double) * n3), *w3 = malloc(sizeof(double) * n3);
  double *w4 = malloc(sizeof(double) * n3), *Hd = malloc(sizeof(double) * n3), *HdJ = malloc(sizeof(double) * n3);
  sim_gradient(&s, x, g);
  bs_obstacles_register_active(x, g, s.obs);
  int32_t na = bs_obstacles_active_count(s.obs);
  cr_assert(na >= 5, "only %d active pairs: the test needs vertices pressed on the sphere", na);
  const double tol = 1e-9;
  int touching_inactive = tangent_direction(&s, L, g, tol, &seed, d);
  /* grad E = J^T g' from the hook */
  memcpy(gE, g, sizeof(double) * n3);
  bs_obstacles_project_gradient(x, gE, s.obs);
  double gEd = 0;
  for (size_t i = 0; i < n3; i++) gEd += gE[i] * d[i];
  /* Hessian of E from the hook */
  bs_bsr *H;
  bs_error err;
  cr_assert_eq(bs_fem_matrix(s.fem, &H, &err), 0, "%s", err.msg);
  for (int i = 0; i < s.n_terms; i++) term_hessian(s.terms[i], x, H);
  bs_obstacles_project_hessian(x, g, H, s.obs);
  cr_assert_eq(bs_bsr_check(H, 1e-12, &err), 0, "%s", err.msg);
  bs_bsr_mul(H, NULL, d, Hd);
  hessian_without_curvature(&s, d, w2, HdJ);
  double dHd = 0, nHd = 0;
  for (size_t i = 0; i < n3; i++) {
    dHd += d[i] * Hd[i];
    nHd += Hd[i] * Hd[i];
  }
  fd_check c = {&s, L, g, d, Hd, HdJ, sim_value(&s, x), gEd, dHd, sqrt(nHd), w1, w2, w3, w4, gE};
  double hs[3] = {2e-4, 1e-4, 5e-5}, eg[3], eh[3], ev[3], ecurv = 0;
  for (int r = 0; r < 3; r++) fd_errors(&c, hs[r], &eg[r], &ev[r], &eh[r], &ecurv);
  check_normal_rows(&s, L, H, g, tol, &seed, w3, w4);
  for (int r = 0; r < 3; r++)
    cr_log_info("h %.1e: gradient %.3e, Hessian %.3e, d^T H d %.3e\n", hs[r], eg[r], eh[r], ev[r]);
  cr_log_info("without the curvature term: %.3e; touching inactive %d, active %d\n", ecurv, touching_inactive, na);
  for (int r = 1; r < 3; r++) {
    cr_assert(eg[r] < 1e-6 || eg[r] < eg[r - 1] / 3, "gradient FD error %g -> %g not O(h^2)", eg[r - 1], eg[r]);
    cr_assert(eh[r] < 1e-6 || eh[r] < eh[r - 1] / 3, "Hessian FD error %g -> %g not O(h^2)", eh[r - 1], eh[r]);
    cr_assert(ev[r] < 1e-5 || ev[r] < ev[r - 1] / 3, "d^T H d FD error %g -> %g not O(h^2)", ev[r - 1], ev[r]);
  }
  cr_assert(eg[2] < 1e-5 && eh[2] < 1e-4 && ev[2] < 1e-3, "errors %g %g %g", eg[2], eh[2], ev[2]);
  cr_assert(ecurv > 100 * eh[2], "the curvature term should matter on a sphere: %g vs %g", ecurv, eh[2]);
  bs_bsr_destroy(&H);
  free(xn);
  free(xh);
  free(g);
  free(gE);
  free(d);
  free(w1);
  free(w2);
  free(w3);
  free(w4);
  free(Hd);
  free(HdJ);
  sim_destroy(&s);
}

/* ---- a body dropped on the ground -------------------------------------------- */

typedef struct drop_result {
  int failures, iterations;
  double min_phi, max_depth, final_vy;
} drop_result;

static drop_result drop(bs_collide_mode mode, int steps, double vy0) {
  sim s;
  double lo[3] = {-0.1, 0.05, -0.1}, hi[3] = {0.1, 0.25, 0.1}, grav[3] = {0, -9.8, 0};
  sim_create(&s, lo, hi, 3, 1e5, grav);
  add(&s, ground(0), mode, 1e7, 0);
  sim_finish(&s, 1e-5, 1);
  for (int32_t p = 0; p < s.nv; p++) s.v[3 * p + 1] = vy0;
  drop_result r = {0, 0, INFINITY, 0, 0};
  const double dt = 1.0 / 24;
  bs_error err;
  for (int n = 0; n < steps; n++) {
    bs_step_stats st;
    cr_assert_eq(bs_integrator_step(s.I, n * dt, dt, s.x, s.v, &st, &err), 0, "%s", err.msg);
    r.failures += st.failed;
    r.iterations += st.min.iterations;
    if (st.failed) cr_log_warn("%s step %d: %s\n", bs_collide_mode_name(mode), n, st.min.reason_text);
    for (int32_t p = 0; p < s.nv; p++) r.min_phi = fmin(r.min_phi, s.x[3 * p + 1]);
    int32_t cnt;
    double depth;
    bs_obstacles_penetration(s.obs, (n + 1) * dt, s.x, 0, &cnt, &depth);
    r.max_depth = fmax(r.max_depth, depth);
  }
  double vy = 0;
  for (int32_t p = 0; p < s.nv; p++) vy += s.fem->mass[p] * s.v[3 * p + 1];
  r.final_vy = vy / s.fem->total_mass;
  sim_destroy(&s);
  return r;
}

Test(obstacles, ball_drop_constraint_penalty_postprocess) {
  drop_result c = drop(BS_COLLIDE_CONSTRAINT, 40, -2);
  drop_result p = drop(BS_COLLIDE_PENALTY, 40, -2);
  drop_result q = drop(BS_COLLIDE_POSTPROCESS, 40, -2);
  cr_log_info("constraint: %d failures, %d iterations, min y %.3e\n", c.failures, c.iterations, c.min_phi);
  cr_log_info("penalty: %d failures, %d iterations, min y %.3e, max depth %.3e\n", p.failures, p.iterations,
              p.min_phi, p.max_depth);
  cr_log_info("postprocess: %d failures, %d iterations, min y %.3e after each push\n", q.failures, q.iterations,
              q.min_phi);
  cr_assert_eq(c.failures, 0, "constraint: %d steps failed", c.failures);
  cr_assert(c.min_phi >= -1e-10, "constraint: a vertex went below the ground (%g)", c.min_phi);
  cr_assert(fabs(c.final_vy) < 0.05, "constraint: the body should come to rest, vy = %g", c.final_vy);
  cr_assert_eq(p.failures, 0, "penalty: %d steps failed", p.failures);
  cr_assert(p.max_depth > 0 && p.max_depth < 0.02, "penalty: depth %g", p.max_depth);
  cr_assert_eq(q.failures, 0, "postprocess: %d steps failed", q.failures);
  cr_assert(q.min_phi >= -1e-10, "postprocess: pushes leave %g", q.min_phi);
}

Test(obstacles, hit_at_1000_m_per_s) {
  drop_result c = drop(BS_COLLIDE_CONSTRAINT, 6, -1e3); /* the hit, then 5 steps of recovery */
  cr_log_info("1e3 m/s: %d failures, %d iterations, min y %.3e\n", c.failures, c.iterations, c.min_phi);
  cr_assert(c.min_phi >= -1e-10, "penetration %g after the step", c.min_phi);
  cr_assert_eq(c.failures, 0);
}

/* ---- friction ------------------------------------------------------------------ */

static void slide(bs_collide_mode mode, double mu, int steps, double dt, double *vx, int *changed_x, double *ke_gain,
                  double *max_dv_mu0) {
  sim s;
  double lo[3] = {-0.1, 0.0, -0.1}, hi[3] = {0.1, 0.1, 0.1}, grav[3] = {0, -9.8, 0};
  sim_create(&s, lo, hi, 2, 1e6, grav);
  add(&s, ground(0), mode, 1e8, mu);
  sim_finish(&s, 1e-5, 0); /* friction applied below, by hand, to watch it */
  for (int32_t p = 0; p < s.nv; p++) s.v[3 * p] = 2.0;
  size_t n3 = 3 * (size_t)s.nv;
  double *g = malloc(sizeof(double) * n3), *xb = malloc(sizeof(double) * n3), *vb = malloc(sizeof(double) * n3);
  bs_error err;
  *changed_x = 0;
  *ke_gain = -INFINITY;
  *max_dv_mu0 = 0;
  for (int n = 0; n < steps; n++) {
    bs_step_stats st;
    cr_assert_eq(bs_integrator_step(s.I, n * dt, dt, s.x, s.v, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.failed, 0, "%s step %d: %s", bs_collide_mode_name(mode), n, st.min.reason_text);
    sim_gradient(&s, s.x, g);
    memcpy(xb, s.x, sizeof(double) * n3);
    memcpy(vb, s.v, sizeof(double) * n3);
    double ke0 = 0, ke1 = 0;
    cr_assert_eq(bs_obstacles_post_solve(s.step.x_n, s.x, g, s.v, dt, s.obs, &err), 0, "%s", err.msg);
    for (int32_t p = 0; p < s.nv; p++)
      for (int k = 0; k < 3; k++) {
        ke0 += 0.5 * s.fem->mass[p] * vb[3 * p + k] * vb[3 * p + k];
        ke1 += 0.5 * s.fem->mass[p] * s.v[3 * p + k] * s.v[3 * p + k];
      }
    if (memcmp(xb, s.x, sizeof(double) * n3) != 0) *changed_x = 1;
    *ke_gain = fmax(*ke_gain, ke1 - ke0);
    for (size_t i = 0; i < n3; i++) *max_dv_mu0 = fmax(*max_dv_mu0, fabs(s.v[i] - vb[i]));
    double m = 0;
    for (int32_t p = 0; p < s.nv; p++) m += s.fem->mass[p] * s.v[3 * p];
    vx[n] = m / s.fem->total_mass;
  }
  free(g);
  free(xb);
  free(vb);
  sim_destroy(&s);
}

/* A box sliding at 2 m/s on the ground, mu = 0.5. At dt = 1/240 s it
 * decelerates at mu g and stops when mu g t exceeds v0 (t = 0.408 s). At
 * dt = 1/24 s the first step removes mu g dt too; later the per-vertex clamp
 * (friction only removes the contact vertices' own tangential velocity, the
 * limitation the paper states at the end of 5.3) slows the deceleration. */
static void check_slide(bs_collide_mode mode, const char *what) {
  enum { N = 130, N24 = 12 };
  double vx[N], ke, dv0;
  int cx;
  const double mu = 0.5, g = 9.8, v0 = 2.0;
  double dt = 1.0 / 240;
  slide(mode, mu, N, dt, vx, &cx, &ke, &dv0);
  cr_assert_eq(cx, 0, "%s: friction moved a vertex", what);
  cr_assert(ke <= 1e-12, "%s: friction added kinetic energy (%g J)", what, ke);
  double prev = v0;
  int stop = -1;
  for (int n = 0; n < N; n++) {
    cr_assert(vx[n] <= prev + 1e-9, "%s: speed increased at step %d (%g -> %g)", what, n, prev, vx[n]);
    prev = vx[n];
    if (stop < 0 && vx[n] < 0.01 * v0) stop = n;
  }
  double a = (v0 - vx[59]) / (60 * dt), t_stop = (stop + 1) * dt;
  cr_log_info("%s, dt = 1/240: deceleration over 0.25 s %.4f (mu g = %.4f), below 1%% of v0 at t = %.4f s, %.2e m/s at the end (v0 / mu g = %.4f)\n",
              what, a, mu * g, t_stop, vx[N - 1], v0 / (mu * g));
  cr_assert(fabs(a - mu * g) < 0.05 * mu * g, "%s: deceleration %g, mu g = %g", what, a, mu * g);
  cr_assert(stop > 0 && fabs(t_stop - v0 / (mu * g)) < 0.1 * v0 / (mu * g), "%s: stopped at t = %g", what, t_stop);
  for (int n = stop; n < N; n++) cr_assert(fabs(vx[n]) < 0.01 * v0, "%s: step %d vx %g", what, n, vx[n]);

  dt = 1.0 / 24;
  slide(mode, mu, N24, dt, vx, &cx, &ke, &dv0);
  cr_assert_eq(cx, 0, "%s: friction moved a vertex", what);
  cr_assert(ke <= 1e-12, "%s: friction added kinetic energy (%g J)", what, ke);
  prev = v0;
  for (int n = 0; n < N24; n++) {
    cr_log_info("%s dt = 1/24 step %d: vx %.5f (Coulomb %.5f)\n", what, n, vx[n], fmax(0, v0 - mu * g * (n + 1) * dt));
    cr_assert(vx[n] <= prev + 1e-9 && vx[n] >= 0, "%s: speed increased at step %d (%g -> %g)", what, n, prev, vx[n]);
    prev = vx[n];
  }
  a = (v0 - vx[0]) / dt;
  cr_assert(fabs(a - mu * g) < 0.05 * mu * g, "%s, dt = 1/24: first-step deceleration %g, mu g = %g", what, a, mu * g);
}

Test(obstacles, friction_constraint_decelerates_as_coulomb) { check_slide(BS_COLLIDE_CONSTRAINT, "constraint"); }

Test(obstacles, friction_penalty_decelerates_as_coulomb) { check_slide(BS_COLLIDE_PENALTY, "penalty"); }

Test(obstacles, zero_friction_changes_nothing) {
  enum { N = 4 };
  double vx[N], ke, dv0;
  int cx;
  bs_collide_mode modes[2] = {BS_COLLIDE_CONSTRAINT, BS_COLLIDE_PENALTY};
  for (int m = 0; m < 2; m++) {
    slide(modes[m], 0.0, N, 1.0 / 24, vx, &cx, &ke, &dv0);
    cr_assert_eq(cx, 0);
    cr_assert_eq(dv0, 0, "%s: mu = 0 changed a velocity by %g", bs_collide_mode_name(modes[m]), dv0);
    cr_assert(fabs(vx[N - 1] - 2.0) < 1e-3, "%s: vx %g", bs_collide_mode_name(modes[m]), vx[N - 1]);
  }
}

/* Two constraint obstacles meeting at a corner (ground and a wall, applied in
 * the order added): a body thrown into the corner converges and stays out of
 * both; a single-vertex check that the composed projection lands on both. */
Test(obstacles, corner_of_two_constraints) {
  sim s;
  double lo[3] = {-0.1, 0.05, -0.1}, hi[3] = {0.1, 0.25, 0.1}, grav[3] = {0, -9.8, 0}, nw[3] = {1, 0, 0};
  sim_create(&s, lo, hi, 2, 1e5, grav);
  bs_levelset *wall;
  bs_error err;
  cr_assert_eq(bs_levelset_create_halfspace(nw, -0.15, &wall, &err), 0, "%s", err.msg); /* x >= -0.15 */
  add(&s, ground(0), BS_COLLIDE_CONSTRAINT, 0, 0.3);
  add(&s, wall, BS_COLLIDE_CONSTRAINT, 0, 0.3);
  sim_finish(&s, 1e-5, 1);
  for (int32_t p = 0; p < s.nv; p++) {
    s.v[3 * p] = -3;
    s.v[3 * p + 1] = -2;
  }
  const double dt = 1.0 / 24;
  int failures = 0;
  double min_y = INFINITY, min_x = INFINITY;
  for (int n = 0; n < 24; n++) {
    bs_step_stats st;
    cr_assert_eq(bs_integrator_step(s.I, n * dt, dt, s.x, s.v, &st, &err), 0, "%s", err.msg);
    failures += st.failed;
    for (int32_t p = 0; p < s.nv; p++) {
      min_y = fmin(min_y, s.x[3 * p + 1]);
      min_x = fmin(min_x, s.x[3 * p] + 0.15);
    }
  }
  cr_log_info("corner: %d failures, min phi ground %.2e, wall %.2e\n", failures, min_y, min_x);
  cr_assert_eq(failures, 0);
  cr_assert(min_y >= -1e-10 && min_x >= -1e-10, "penetration: ground %g, wall %g", min_y, min_x);
  /* a point inside both lands on the corner line */
  double *x = s.x;
  s.step.time = 0;
  x[0] = -0.3;
  x[1] = -0.2;
  x[2] = 0.05;
  bs_obstacles_project(x, s.obs);
  cr_assert(fabs(x[0] + 0.15) < 1e-14 && fabs(x[1]) < 1e-14 && x[2] == 0.05, "(%g %g %g)", x[0], x[1], x[2]);
  sim_destroy(&s);
}

/* An active pair on a box face is projected back while the trial point stays
 * over that face (the curved path), and released once it has slid past the
 * edge (projecting would pull it back onto the edge, where it would stay:
 * the failing steps of figure 13 before this rule). The gradient of a
 * released pair is left unprojected (P is the identity there). */
Test(obstacles, active_pair_slides_off_a_box_edge) {
  sim s;
  double lo[3] = {2, 2, 2}, hi[3] = {2.1, 2.1, 2.1}; /* a small block far from the box */
  sim_create(&s, lo, hi, 1, 1e5, NULL);
  bs_levelset *box;
  bs_error err;
  const double c[3] = {0, 0, 0}, h[3] = {0.5, 0.5, 0.5};
  cr_assert_eq(bs_levelset_create_box(c, h, &box, &err), 0, "%s", err.msg);
  add(&s, box, BS_COLLIDE_CONSTRAINT, 0, 0);
  sim_finish(&s, 1e-6, 0);
  s.step.time = 0;
  const size_t n3 = 3 * (size_t)s.nv;
  double *x = malloc(sizeof(double) * n3), *g = calloc(n3, sizeof(double));
  memcpy(x, s.x, sizeof(double) * n3);
  /* vertex 0 on the +x face, 1 cm below the top edge, pressed into the box */
  x[0] = 0.5;
  x[1] = 0.49;
  x[2] = 0.1;
  g[0] = 1.0;
  g[1] = -2.0;
  bs_obstacles_register_active(x, g, s.obs);
  cr_assert_eq(bs_obstacles_active_count(s.obs), 1);
  /* still over the face, a little outside: back onto the face */
  x[0] = 0.51;
  x[1] = 0.2;
  bs_obstacles_project(x, s.obs);
  cr_assert(fabs(x[0] - 0.5) < 1e-15 && x[1] == 0.2 && x[2] == 0.1, "(%.17g %.17g %.17g)", x[0], x[1], x[2]);
  double gp[3] = {1.0, -2.0, 0.5};
  memcpy(g, gp, sizeof gp);
  bs_obstacles_project_gradient(x, g, s.obs);
  cr_assert(g[0] == 0.0 && g[1] == -2.0 && g[2] == 0.5, "projected gradient (%g %g %g)", g[0], g[1], g[2]);
  /* slid up past the top edge, just outside: released, left where it is */
  x[0] = 0.501;
  x[1] = 0.6;
  bs_obstacles_project(x, s.obs);
  cr_assert(x[0] == 0.501 && x[1] == 0.6 && x[2] == 0.1, "released vertex moved to (%g %g %g)", x[0], x[1], x[2]);
  memcpy(g, gp, sizeof gp);
  bs_obstacles_project_gradient(x, g, s.obs);
  cr_assert(g[0] == 1.0 && g[1] == -2.0 && g[2] == 0.5, "released gradient changed to (%g %g %g)", g[0], g[1], g[2]);
  /* inside the box a pair is always projected (violated) */
  x[0] = 0.45;
  x[1] = 0.3;
  bs_obstacles_project(x, s.obs);
  cr_assert(fabs(x[0] - 0.5) < 1e-15, "violated pair not projected: x = %g", x[0]);
  free(x);
  free(g);
  sim_destroy(&s);
}

/* ---- a fem split over processes (bs_obstacles_set_owned) ---------------------- */

static bs_levelset *ball(double R) {
  bs_levelset *ls;
  bs_error err;
  const double cen[3] = {0, -R, 0};
  cr_assert_eq(bs_levelset_create_sphere(cen, R, &ls, &err), 0, "%s", err.msg);
  return ls;
}

/* Two "processes" that own the even and the odd vertices: the same labels
 * and projected gradient as the unsplit obstacles; the Hessian projection of
 * H' on one plus that of a zero matrix on the other is the unsplit projected
 * Hessian bit for bit (the curvature block once); active pairs, penetration
 * and the penalty split over the two. set_owned after an add is refused. */
/* The two parts of the split test: part r owns the vertices p with p % 2 ==
 * r, each with the sphere (constraint) and the ground (penalty); set_owned
 * after an add refused. */
static void make_parts(sim *s, bs_obstacles *part[2]) {
  bs_error err;
  uint8_t *own = malloc((size_t)s->nv);
  double blo[3], bhi[3];
  bs_bbox(s->nv, s->mesh->x, blo, bhi);
  for (int r = 0; r < 2; r++) {
    for (int32_t p = 0; p < s->nv; p++) own[p] = (p % 2) == r;
    cr_assert_eq(bs_obstacles_create(s->fem, &s->step, s->mask, &part[r], &err), 0, "%s", err.msg);
    cr_assert_eq(bs_obstacles_set_owned(part[r], own, &err), 0, "%s", err.msg);
    bs_obstacles_set_bounds(part[r], blo, bhi); /* the fem's own box: the same tolerance */
    cr_assert_eq(bs_obstacles_add(part[r], ball(0.5), BS_COLLIDE_CONSTRAINT, 0, 0, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_obstacles_add(part[r], ground(-0.01), BS_COLLIDE_PENALTY, 1e2, 0, &err), 0, "%s", err.msg);
  }
  cr_assert_eq(bs_obstacles_set_owned(part[0], own, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "before the first obstacle"), "%s", err.msg);
  free(own);
}

Test(obstacles, owned_vertices_split_the_sums) {
  sim s;
  double lo[3] = {-0.2, 0.0, -0.2}, hi[3] = {0.2, 0.3, 0.2}, grav[3] = {0, -40, 0};
  sim_create(&s, lo, hi, 2, 2e3, grav);
  bs_error err;
  bs_obstacles *part[2] = {NULL, NULL};
  make_parts(&s, part);
  add(&s, ball(0.5), BS_COLLIDE_CONSTRAINT, 0, 0);
  add(&s, ground(-0.01), BS_COLLIDE_PENALTY, 1e2, 0);
  sim_finish(&s, 1e-6, 1);
  const size_t n3 = 3 * (size_t)s.nv;
  s.step.dt = 1.0 / 24, s.step.time = 0.5, s.step.load = 1;
  s.step.x_n = s.step.x_hat = s.mesh->x;
  /* a feasible x with the bottom layer pressed onto the sphere, a few
     vertices below the penalty ground */
  unsigned seed = 7;
  for (size_t i = 0; i < n3; i++) s.x[i] = s.mesh->x[i] + 0.004 * (urand(&seed) - 0.5);
  for (int32_t p = 0; p < s.nv; p++)
    if (s.mesh->x[3 * p + 1] == 0) s.x[3 * p + 1] -= 0.05;
  double *g = malloc(sizeof(double) * n3), *gs = malloc(sizeof(double) * n3), *gp = malloc(sizeof(double) * n3);
  double *x1 = malloc(sizeof(double) * n3);
  memcpy(x1, s.x, sizeof(double) * n3);
  bs_obstacles_project(s.x, s.obs);
  sim_gradient(&s, s.x, g);
  bs_obstacles_register_active(s.x, g, s.obs);
  memcpy(gs, g, sizeof(double) * n3);
  bs_obstacles_project_gradient(s.x, gs, s.obs);
  bs_bsr *H, *Hp[2];
  cr_assert_eq(bs_fem_matrix(s.fem, &H, &err), 0, "%s", err.msg);
  for (int i = 0; i < s.n_own; i++) term_hessian(s.own[i], s.x, H);
  cr_assert_eq(bs_fem_matrix(s.fem, &Hp[0], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_matrix(s.fem, &Hp[1], &err), 0, "%s", err.msg);
  memcpy(Hp[0]->val, H->val, sizeof(double) * 9 * (size_t)H->nnzb);
  bs_bsr_zero(Hp[1]);
  bs_obstacles_project_hessian(s.x, g, H, s.obs);
  int32_t na = bs_obstacles_active_count(s.obs), na_sum = 0, pen = 0, pen_sum = 0;
  double depth = 0, depth_r;
  bs_obstacles_penetration(s.obs, s.step.time, x1, 0, &pen, &depth);
  cr_assert(na >= 5 && pen >= 1, "%d active pairs, %d vertices inside: the test needs contact", na, pen);
  bs_term *const *pt;
  cr_assert_eq(bs_obstacles_terms(s.obs, &pt), 1);
  double Epen = term_value(pt[0], x1), Epart = 0;
  for (int r = 0; r < 2; r++) {
    double *xr = malloc(sizeof(double) * n3);
    memcpy(xr, x1, sizeof(double) * n3);
    bs_obstacles_project(xr, part[r]);
    cr_assert_eq(memcmp(xr, s.x, sizeof(double) * n3), 0, "process %d projects otherwise", r);
    bs_obstacles_register_active(xr, g, part[r]);
    memcpy(gp, g, sizeof(double) * n3);
    bs_obstacles_project_gradient(xr, gp, part[r]);
    cr_assert_eq(memcmp(gp, gs, sizeof(double) * n3), 0, "process %d projects the gradient otherwise", r);
    bs_obstacles_project_hessian(xr, g, Hp[r], part[r]);
    na_sum += bs_obstacles_active_count(part[r]);
    int32_t c;
    bs_obstacles_penetration(part[r], s.step.time, x1, 0, &c, &depth_r);
    cr_assert_eq(depth_r, depth);
    pen_sum += c;
    cr_assert_eq(bs_obstacles_terms(part[r], &pt), 1);
    Epart += term_value(pt[0], x1);
    free(xr);
  }
  for (int64_t k = 0; k < 9 * H->nnzb; k++)
    cr_assert_eq(Hp[0]->val[k] + Hp[1]->val[k], H->val[k], "Hessian entry %lld: %.17g + %.17g vs %.17g", (long long)k,
                 Hp[0]->val[k], Hp[1]->val[k], H->val[k]);
  cr_assert_eq(na_sum, na, "active pairs %d over the parts, %d unsplit", na_sum, na);
  cr_assert_eq(pen_sum, pen, "penetrating %d over the parts, %d unsplit", pen_sum, pen);
  cr_assert(fabs(Epart - Epen) <= 1e-12 * Epen && Epen > 0, "penalty %.17g over the parts, %.17g unsplit", Epart, Epen);
  bs_bsr_destroy(&H);
  bs_bsr_destroy(&Hp[0]);
  bs_bsr_destroy(&Hp[1]);
  for (int r = 0; r < 2; r++) bs_obstacles_destroy(&part[r]);
  free(g), free(gs), free(gp), free(x1);
  sim_destroy(&s);
}
