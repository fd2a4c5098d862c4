/* Penalty self-collisions (paper 5.3): the point-primitive kernels against
 * central finite differences (O(h^2)) in the face, edge and vertex regions;
 * detection on two boxes in one mesh; the term's gradient and Hessian
 * (pattern blocks plus the missing coupling blocks) against finite
 * differences, also on hundreds of contacts, the same with any thread count;
 * the contact Hessians' projection onto the PSD cone (the convexified
 * model); two boxes falling onto each other end separated; friction lowers
 * kinetic energy, conserves momentum, never moves positions; error paths
 * name the culprit. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_selfcollide.h"
#include "bs_svd.h"
#include "bs_step.h"
#include "bs_terms.h"
#include "test_term_eval.h"

/* ---- kernels ---------------------------------------------------------- */

static double rnd(unsigned *s) {
  *s = *s * 1103515245u + 12345u;
  return ((*s >> 8) & 0xffff) / 65536.0 - 0.5;
}

/* Max errors of the gradient and Hessian of f = sqdist (energy 0) or pair
 * energy (energy 1) against central differences with step h. */
static void fd_errors(int nv, const double *y0, int energy, double h, double *eg, double *eH) {
  int m = 3 * (nv + 1);
  double y[12], g[12], H[144], gp[12], gm[12];
  memcpy(y, y0, sizeof(double) * (size_t)m);
  if (energy) bs_self_pair_energy(nv, y, 2.5, g, H);
  else bs_self_sqdist(nv, y, g, H);
  *eg = *eH = 0;
  for (int i = 0; i < m; i++) {
    double s = y[i];
    y[i] = s + h;
    double fp = energy ? bs_self_pair_energy(nv, y, 2.5, gp, NULL) : bs_self_sqdist(nv, y, gp, NULL);
    y[i] = s - h;
    double fm = energy ? bs_self_pair_energy(nv, y, 2.5, gm, NULL) : bs_self_sqdist(nv, y, gm, NULL);
    y[i] = s;
    double e = fabs((fp - fm) / (2 * h) - g[i]);
    if (e > *eg) *eg = e;
    for (int j = 0; j < m; j++) {
      double eh = fabs((gp[j] - gm[j]) / (2 * h) - H[j * m + i]);
      if (eh > *eH) *eH = eh;
    }
  }
}

/* A configuration in the region `want` (face / edge / vertex): returns nv and y. */
static int region_config(int want, unsigned seed, double *y) {
  unsigned s = seed;
  double a[3] = {0.1 * rnd(&s), 0.1 * rnd(&s), 0.1 * rnd(&s)};
  double b[3] = {1 + 0.1 * rnd(&s), 0.1 + 0.1 * rnd(&s), 0.1 * rnd(&s)};
  double c[3] = {0.2 + 0.1 * rnd(&s), 1 + 0.1 * rnd(&s), 0.1 + 0.1 * rnd(&s)};
  double p[3];
  if (want == BS_SELF_FACE) p[0] = 0.35, p[1] = 0.3, p[2] = -0.4;
  else if (want == BS_SELF_EDGE) p[0] = 0.5, p[1] = -0.6, p[2] = 0.3;
  else p[0] = -0.5, p[1] = -0.4, p[2] = 0.35;
  for (int k = 0; k < 3; k++) p[k] += 0.05 * rnd(&s);
  double w[3], wf[3];
  int feat, nv, loc[3];
  bs_self_closest_triangle(p, a, b, c, w, &feat, &nv, loc, wf);
  cr_assert_eq(feat, want, "configuration in region %d came out in %d", want, feat);
  const double *P[3] = {a, b, c};
  memcpy(y, p, sizeof p);
  for (int i = 0; i < nv; i++) memcpy(y + 3 * (1 + i), P[loc[i]], 3 * sizeof(double));
  return nv;
}

static void check_region(int want) {
  for (unsigned seed = 1; seed <= 3; seed++) {
    double y[12];
    int nv = region_config(want, seed, y);
    for (int energy = 0; energy < 2; energy++) {
      double eg[4], eH[4], h = 1e-2;
      for (int r = 0; r < 4; r++, h /= 2) fd_errors(nv, y, energy, h, &eg[r], &eH[r]);
      cr_log_info("region %d energy %d: gradient FD errors %g %g %g %g, Hessian %g %g %g %g", want, energy, eg[0], eg[1],
                  eg[2], eg[3], eH[0], eH[1], eH[2], eH[3]);
      for (int r = 0; r < 3; r++) {
        /* O(h^2): halving h divides the error by ~4 (unless already at round-off) */
        if (eg[r] > 1e-9) cr_expect(eg[r] / eg[r + 1] > 2.5 && eg[r] / eg[r + 1] < 5.5,
                                    "region %d energy %d: gradient errors %g -> %g", want, energy, eg[r], eg[r + 1]);
        if (eH[r] > 1e-9) cr_expect(eH[r] / eH[r + 1] > 2.5 && eH[r] / eH[r + 1] < 5.5,
                                    "region %d energy %d: Hessian errors %g -> %g", want, energy, eH[r], eH[r + 1]);
      }
      cr_expect(eg[3] < 1e-5 && eH[3] < 1e-4, "region %d energy %d: errors %g %g at h = 1.25e-3", want, energy, eg[3],
                eH[3]);
    }
  }
}

Test(self_kernel, fd_face_region) { check_region(BS_SELF_FACE); }
Test(self_kernel, fd_edge_region) { check_region(BS_SELF_EDGE); }
Test(self_kernel, fd_vertex_region) { check_region(BS_SELF_VERTEX); }

/* The region formula is the true distance, and its gradient is Danskin's:
 * d_p = 2 (p - c), d_{x_i} = -2 w_i (p - c), c the closest point. */
Test(self_kernel, region_formula_is_closest_distance) {
  for (int want = 0; want < 3; want++)
    for (unsigned seed = 1; seed <= 3; seed++) {
      double y[12], g[12];
      int nv = region_config(want, seed, y);
      /* rebuild the full triangle to get the weights */
      unsigned s = seed;
      double a[3] = {0.1 * rnd(&s), 0.1 * rnd(&s), 0.1 * rnd(&s)};
      double b[3] = {1 + 0.1 * rnd(&s), 0.1 + 0.1 * rnd(&s), 0.1 * rnd(&s)};
      double c[3] = {0.2 + 0.1 * rnd(&s), 1 + 0.1 * rnd(&s), 0.1 + 0.1 * rnd(&s)};
      double w[3], wf[3];
      int feat, nv2, loc[3];
      double dc = bs_self_closest_triangle(y, a, b, c, w, &feat, &nv2, loc, wf);
      double d = bs_self_sqdist(nv, y, g, NULL);
      cr_expect(fabs(d - dc) <= 1e-13, "region %d: formula %.17g, closest %.17g", want, d, dc);
      double cp[3] = {0, 0, 0};
      for (int i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) cp[k] += wf[i] * y[3 * (1 + i) + k];
      for (int k = 0; k < 3; k++) {
        cr_expect(fabs(g[k] - 2 * (y[k] - cp[k])) < 1e-12, "region %d: d_p", want);
        for (int i = 0; i < nv; i++)
          cr_expect(fabs(g[3 * (1 + i) + k] + 2 * wf[i] * (y[k] - cp[k])) < 1e-12, "region %d: d_x%d", want, i);
      }
    }
}

Test(self_kernel, closest_triangle_degenerate_and_energy_shape) {
  double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0}, p[3] = {0.5, 1, 0};
  double w[3], wf[3];
  int feat, nv, loc[3];
  double d = bs_self_closest_triangle(p, a, b, c, w, &feat, &nv, loc, wf);
  cr_expect(fabs(d - 1) < 1e-15 && feat == BS_SELF_EDGE, "collinear triangle: d = %g, feature %d", d, feat);
  /* Phi = k d sqrt(d + eps) ~ k depth^3 */
  double y[6] = {0, 0, 0, 0.01, 0, 0};
  double E = bs_self_pair_energy(1, y, 3.0, NULL, NULL);
  cr_expect(fabs(E - 3.0 * 1e-6) < 1e-12, "Phi = %g for depth 0.01, k = 3", E);
  double z[6] = {0, 0, 0, 0, 0, 0}, g[6], H[36];
  cr_expect_eq(bs_self_pair_energy(1, z, 3.0, g, H), 0.0);
  for (int i = 0; i < 6; i++) cr_expect(g[i] == 0 && isfinite(H[i * 6 + i]), "finite derivatives at d = 0");
}

/* v^T A v over the m x m row-major A. */
static double quad(int m, const double *A, const double *v) {
  double s = 0;
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) s += v[i] * A[i * m + j] * v[j];
  return s;
}

/* bs_sym_psd_project on a known matrix: R diag(3, -2) R^T becomes
 * R diag(3, 0) R^T (one eigenvalue clamped); a PSD matrix is left bit for
 * bit; m out of range is refused. */
Test(self_kernel, psd_projection_known_matrix) {
  const double c = cos(0.3), s = sin(0.3);
  double H[4] = {3 * c * c - 2 * s * s, 5 * c * s, 5 * c * s, 3 * s * s - 2 * c * c};
  const double want[4] = {3 * c * c, 3 * c * s, 3 * c * s, 3 * s * s};
  cr_assert_eq(bs_sym_psd_project(2, H), 1);
  for (int i = 0; i < 4; i++) cr_expect(fabs(H[i] - want[i]) < 1e-14, "entry %d: %.17g, want %.17g", i, H[i], want[i]);
  double P[4] = {2, 1, 1, 2}, P0[4];
  memcpy(P0, P, sizeof P);
  cr_assert_eq(bs_sym_psd_project(2, P), 0);
  cr_expect(memcmp(P, P0, sizeof P) == 0, "a PSD matrix changed");
  cr_expect_eq(bs_sym_psd_project(13, P), -1);
  cr_expect_eq(bs_sym_psd_project(0, P), -1);
}

/* The contact Hessians: in the face and edge regions the exact one is
 * indefinite (tilting the primitive shortens the distance), its projection
 * is PSD and differs from it by a PSD matrix (only negative curvature is
 * removed) and is projected again to itself; in the vertex region (|p - a|^2
 * is convex) the Hessian is PSD and left bit for bit. */
/* The pair's secant model (bs_self_pair_secant) in every region: at balance
 * (g = 0) it is the Hessian; when the other terms pull outwards (g = the
 * pair's own gradient plus a pull along grad d, r* = 0) the grad d grad d^T
 * part is gone, leaving
 * k psi'(d) Hess d; with a push F along grad r the model's curvature along
 * grad r is 3 k (r + r*) |grad r|^4 + (the Hess r part), so against case 2 it
 * gains 3 k r* (grad r . grad r)^2. */
Test(self_kernel, pair_secant_model) {
  const double k = 2.5;
  for (int want = 0; want < 3; want++)
    for (unsigned seed = 1; seed <= 3; seed++) {
      double y[12], H[144], Hs[144], H0[144], gp[12], gd[12], Hd[144], g[12];
      const int nv = region_config(want, seed, y), m = 3 * (nv + 1);
      bs_self_pair_energy(nv, y, k, gp, H);
      const double d = bs_self_sqdist(nv, y, gd, Hd), r = sqrt(d), se = sqrt(d + BS_SELF_EPS);
      double scale = 0;
      for (int i = 0; i < m * m; i++) scale = fmax(scale, fabs(H[i]));
      memset(g, 0, sizeof g);
      memcpy(Hs, H, sizeof(double) * (size_t)(m * m));
      bs_self_pair_secant(nv, y, k, g, Hs);
      for (int i = 0; i < m * m; i++)
        cr_expect(fabs(Hs[i] - H[i]) <= 1e-9 * scale, "region %d seed %u: at balance entry %d %g vs %g", want, seed, i,
                  Hs[i], H[i]);
      memcpy(H0, H, sizeof(double) * (size_t)(m * m));
      for (int i = 0; i < m; i++) g[i] = gp[i] + 1e-3 * gd[i];
      bs_self_pair_secant(nv, y, k, g, H0);
      const double dpsi = se + d / (2 * se);
      for (int i = 0; i < m * m; i++)
        cr_expect(fabs(H0[i] - k * dpsi * Hd[i]) <= 1e-9 * scale, "region %d seed %u: unloaded entry %d %g vs %g", want,
                  seed, i, H0[i], k * dpsi * Hd[i]);
      /* a push F = 3 k (r / 2)^2 along grad r: r* = r / 2 */
      double dd = 0;
      for (int i = 0; i < m; i++) dd += gd[i] * gd[i];
      const double F = 3 * k * (r / 2) * (r / 2), gr2 = dd / (4 * d); /* |grad r|^2 */
      for (int i = 0; i < m; i++) g[i] = gp[i] - F * gd[i] / (2 * r);
      memcpy(Hs, H, sizeof(double) * (size_t)(m * m));
      bs_self_pair_secant(nv, y, k, g, Hs);
      double q = 0, q0 = 0; /* curvatures along grad r */
      for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) {
          q += gd[i] * Hs[i * m + j] * gd[j] / (4 * d);
          q0 += gd[i] * H0[i * m + j] * gd[j] / (4 * d);
        }
      const double want_q = q0 + 3 * k * (r / 2) * gr2 * gr2;
      cr_expect(fabs(q - want_q) <= 1e-9 * fabs(want_q), "region %d seed %u: curvature %.17g, expected %.17g", want,
                seed, q, want_q);
    }
}

Test(self_kernel, psd_projection_of_contact_hessians) {
  for (int want = 0; want < 3; want++)
    for (unsigned seed = 1; seed <= 3; seed++) {
      double y[12], H[144], Hp[144], H2[144];
      const int nv = region_config(want, seed, y), m = 3 * (nv + 1);
      bs_self_pair_energy(nv, y, 2.5, NULL, H);
      memcpy(Hp, H, sizeof(double) * (size_t)(m * m));
      const int neg = bs_sym_psd_project(m, Hp);
      double scale = 0;
      for (int i = 0; i < m * m; i++) scale = fmax(scale, fabs(H[i]));
      if (want == BS_SELF_VERTEX) {
        cr_expect_eq(neg, 0, "vertex region, seed %u: %d negative eigenvalues", seed, neg);
        cr_expect(memcmp(H, Hp, sizeof(double) * (size_t)(m * m)) == 0, "vertex region: H changed");
        continue;
      }
      cr_expect_gt(neg, 0, "region %d, seed %u: the exact contact Hessian is PSD", want, seed);
      unsigned r = 7 * seed + (unsigned)want;
      for (int t = 0; t < 200; t++) {
        double v[12], D[144];
        for (int i = 0; i < m; i++) v[i] = rnd(&r);
        for (int i = 0; i < m * m; i++) D[i] = Hp[i] - H[i];
        cr_expect(quad(m, Hp, v) >= -1e-12 * scale, "region %d: v^T Hp v = %g", want, quad(m, Hp, v));
        cr_expect(quad(m, D, v) >= -1e-12 * scale, "region %d: v^T (Hp - H) v = %g", want, quad(m, D, v));
      }
      for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) cr_expect(Hp[i * m + j] == Hp[j * m + i], "Hp not symmetric");
      memcpy(H2, Hp, sizeof H2);
      bs_sym_psd_project(m, H2);
      for (int i = 0; i < m * m; i++) cr_expect(fabs(H2[i] - Hp[i]) < 1e-12 * scale, "projection not idempotent");
    }
}

/* ---- meshes ----------------------------------------------------------- */

/* Two boxes as one mesh; *nA receives the vertex count of the first. */
static bs_mesh *two_boxes(const double *loA, const double *hiA, int nA_cells, const double *loB, const double *hiB,
                          int nB_cells, int32_t *nA) {
  bs_error err;
  bs_mesh *A, *B, *m;
  cr_assert_eq(bs_mesh_create_box(loA, hiA, nA_cells, nA_cells, nA_cells, &A, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_mesh_create_box(loB, hiB, nB_cells, nB_cells, nB_cells, &B, &err), 0, "%s", err.msg);
  int32_t nv = A->n_vertices + B->n_vertices, nt = A->n_tets + B->n_tets;
  double *x = malloc(sizeof(double) * 3 * (size_t)nv);
  int32_t *tets = malloc(sizeof(int32_t) * 4 * (size_t)nt);
  memcpy(x, A->x, sizeof(double) * 3 * (size_t)A->n_vertices);
  memcpy(x + 3 * A->n_vertices, B->x, sizeof(double) * 3 * (size_t)B->n_vertices);
  memcpy(tets, A->tets, sizeof(int32_t) * 4 * (size_t)A->n_tets);
  for (int32_t i = 0; i < 4 * B->n_tets; i++) tets[4 * A->n_tets + i] = B->tets[i] + A->n_vertices;
  cr_assert_eq(bs_mesh_create(nv, x, nt, tets, 0, NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_vertices, nv);
  *nA = A->n_vertices;
  bs_mesh_destroy(&A);
  bs_mesh_destroy(&B);
  free(x);
  free(tets);
  return m;
}

typedef struct world {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_material mat;
  bs_term *self;
  int32_t nA;
  double *x;
  size_t n3;
} world;

/* A = [0,1]^3 (3^3 cells), B = [1.5,2.5] x [0,1]^2 (2^3 cells). */
static void world_create(world *w, double k) {
  bs_error err;
  memset(w, 0, sizeof *w);
  double loA[3] = {0, 0, 0}, hiA[3] = {1, 1, 1}, loB[3] = {1.5, 0, 0}, hiB[3] = {2.5, 1, 1};
  w->mesh = two_boxes(loA, hiA, 3, loB, hiB, 2, &w->nA);
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, &w->mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(w->mesh, 1, &w->mat, NULL, &w->fem, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_self_create(w->fem, NULL, k, &w->self, &err), 0, "%s", err.msg);
  w->n3 = 3 * (size_t)w->mesh->n_vertices;
  w->x = malloc(sizeof(double) * w->n3);
  memcpy(w->x, w->mesh->x, sizeof(double) * w->n3);
}

static void world_destroy(world *w) {
  bs_term_destroy(&w->self);
  cr_assert_null(w->self);
  bs_fem_destroy(&w->fem);
  bs_mesh_destroy(&w->mesh);
  free(w->x);
}

/* A's vertex at rest position (1, 1/3, 1/3) (cells of 1/3), moved off the
 * mesh lines in y and z so that it never lies on a tet face. */
static int32_t a_vertex_off_the_lines(world *w) {
  int32_t q = -1;
  for (int32_t v = 0; v < w->nA; v++) {
    const double *X = w->mesh->x + 3 * v;
    if (fabs(X[0] - 1) < 1e-12 && fabs(X[1] - 1.0 / 3) < 1e-12 && fabs(X[2] - 1.0 / 3) < 1e-12) q = v;
  }
  cr_assert(q >= 0);
  w->x[3 * q + 1] += 0.011;
  w->x[3 * q + 2] += 0.023;
  return q;
}

/* The B vertex at rest position (1.5, 0.5, 0.5) (centre of B's xmin face). */
static int32_t b_face_centre(const world *w) {
  for (int32_t v = w->nA; v < w->mesh->n_vertices; v++) {
    const double *p = w->mesh->x + 3 * v;
    if (fabs(p[0] - 1.5) < 1e-12 && fabs(p[1] - 0.5) < 1e-12 && fabs(p[2] - 0.5) < 1e-12) return v;
  }
  cr_assert_fail("no vertex at (1.5, 0.5, 0.5)");
  return -1;
}

/* ---- detection -------------------------------------------------------- */

Test(self_detect, nothing_overlaps_energy_zero) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  int32_t count = -1;
  double depth = -1;
  /* every vertex lies on its own (closed) tets: those are excluded */
  cr_assert_eq(bs_term_self_detect(w.self, w.x, &count, &depth, &err), 0, "%s", err.msg);
  cr_expect_eq(count, 0, "%d vertices flagged at rest", count);
  cr_expect_eq(depth, 0.0);
  cr_expect_eq(term_value(w.self, w.x), 0.0);
  /* small random motion that inverts nothing: still no collision */
  unsigned s = 7;
  for (size_t i = 0; i < w.n3; i++) w.x[i] += 0.02 * rnd(&s);
  cr_assert_eq(bs_term_self_detect(w.self, w.x, &count, &depth, &err), 0, "%s", err.msg);
  cr_expect_eq(count, 0, "%d vertices flagged after a small perturbation", count);
  double *g = calloc(w.n3, sizeof(double));
  cr_expect_eq(term_gradient(w.self, w.x, g), 0.0);
  for (size_t i = 0; i < w.n3; i++) cr_expect_eq(g[i], 0.0);
  free(g);
  world_destroy(&w);
}

Test(self_detect, pushed_vertex_is_found) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  int32_t p = b_face_centre(&w);
  w.x[3 * p] = 0.9; /* 0.1 deep into A through its face x = 1 */
  w.x[3 * p + 1] = 0.4;
  w.x[3 * p + 2] = 0.52;
  int32_t count = -1;
  double depth = -1;
  cr_assert_eq(bs_term_self_detect(w.self, w.x, &count, &depth, &err), 0, "%s", err.msg);
  cr_expect_eq(count, 1, "%d vertices flagged, expected the pushed one", count);
  cr_expect(fabs(depth - 0.1) < 1e-12, "depth %.17g, expected 0.1", depth);
  double E = term_value(w.self, w.x);
  cr_expect(fabs(E - 1e6 * 0.01 * sqrt(0.01 + BS_SELF_EPS)) < 1e-9, "E = %.17g", E);
  /* the force on the pushed vertex points out of A (+x), reactions on A's face */
  double *g = calloc(w.n3, sizeof(double));
  term_gradient(w.self, w.x, g);
  cr_expect(g[3 * p] < 0 && fabs(g[3 * p + 1]) < 1e-9 * fabs(g[3 * p]), "grad at p (%g, %g, %g)", g[3 * p],
            g[3 * p + 1], g[3 * p + 2]);
  double sum[3] = {0, 0, 0};
  for (size_t i = 0; i < w.n3; i++) sum[i % 3] += g[i];
  for (int k = 0; k < 3; k++) cr_expect(fabs(sum[k]) < 1e-9 * fabs(g[3 * p]), "net force component %d: %g", k, sum[k]);
  for (int32_t v = w.nA; v < w.mesh->n_vertices; v++)
    if (v != p)
      for (int k = 0; k < 3; k++) cr_expect_eq(g[3 * v + k], 0.0, "B vertex %d is not involved", v);
  free(g);
  bs_self_stats st;
  cr_assert_eq(bs_term_self_stats(w.self, &st, &err), 0, "%s", err.msg);
  cr_expect_eq(st.colliding, 1);
  cr_expect(st.evaluations >= 3 && st.rebuilds == 1, "evaluations %lld rebuilds %lld", (long long)st.evaluations,
            (long long)st.rebuilds);
  /* detect, value and gradient at the same positions: one search, two reuses */
  cr_expect(st.reused >= 2, "reused %lld of %lld", (long long)st.reused, (long long)st.evaluations);
  bs_term_self_reset_stats(w.self);
  cr_assert_eq(bs_term_self_stats(w.self, &st, &err), 0, "%s", err.msg);
  cr_expect_eq(st.evaluations, 0);
  world_destroy(&w);
}

/* begin_step rebuilds the hierarchies only when their cost grew
 * (BS_SELF_REBUILD_GROWTH): not after a rigid translation, after a stretch;
 * the contacts do not depend on the hierarchy: a term rebuilt at the
 * stretched shape and one still built at rest give the same value and
 * gradient, bit for bit. */
Test(self_detect, rebuilt_only_when_the_cost_grew_and_contacts_do_not_depend_on_it) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  bs_step_data step;
  memset(&step, 0, sizeof step);
  bs_term *t = NULL;
  cr_assert_eq(bs_term_self_create(w.fem, &step, 1e6, &t, &err), 0, "%s", err.msg);
  step.x_n = w.x;
  bs_self_stats st;
  cr_assert_eq(t->ops->begin_step(t, &err), 0, "%s", err.msg);
  for (size_t i = 0; i < w.n3; i++) w.x[i] += i % 3 == 0 ? 3.0 : i % 3 == 1 ? 1.0 : -2.0;
  cr_assert_eq(t->ops->begin_step(t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_self_stats(t, &st, &err), 0, "%s", err.msg);
  cr_expect_eq(st.rebuilds, 1, "rebuilt %lld times at rest and translated", (long long)st.rebuilds);
  for (size_t i = 0; i < w.n3; i++) /* back to rest, y and z stretched 3 times */
    w.x[i] = i % 3 == 0 ? w.mesh->x[i] : 3 * w.mesh->x[i];
  cr_assert_eq(t->ops->begin_step(t, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_self_stats(t, &st, &err), 0, "%s", err.msg);
  cr_expect_eq(st.rebuilds, 2, "rebuilt %lld times after the stretch", (long long)st.rebuilds);
  int32_t p = b_face_centre(&w); /* now at (1.5, 1.5, 1.5): pushed 0.1 into A */
  w.x[3 * p] = 0.9;
  w.x[3 * p + 1] += 0.013;
  double *g1 = calloc(w.n3, sizeof(double)), *g2 = calloc(w.n3, sizeof(double));
  const double E1 = term_gradient(t, w.x, g1), E2 = term_gradient(w.self, w.x, g2);
  cr_expect(E1 > 0, "E = %g: the pushed vertex collides", E1);
  cr_expect_eq(E1, E2, "E %.17g rebuilt, %.17g built at rest", E1, E2);
  cr_expect_eq(memcmp(g1, g2, w.n3 * sizeof(double)), 0, "the gradients differ");
  free(g1);
  free(g2);
  bs_term_destroy(&t);
  world_destroy(&w);
}

/* A surface vertex of A pushed into A through its own tets (inverting them)
 * is not flagged while it stays within the tets of its edge neighbours: with
 * the paper's rule (every tet that does not have the vertex) it would be, at
 * a depth of about one edge from every admissible triangle, a jump of E that
 * stalls line searches. Pushed past two layers of tets (through a tangle of
 * its own body) it is flagged. */
Test(self_detect, own_neighbourhood_excluded) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  const int32_t q = a_vertex_off_the_lines(&w);
  int32_t count = -1;
  for (int i = 0; i <= 100; i++) {
    w.x[3 * q] = 1 - 0.6 * i / 100.0; /* down to x = 0.4: inside the second layer */
    cr_assert_eq(bs_term_self_detect(w.self, w.x, &count, NULL, &err), 0, "%s", err.msg);
    cr_expect_eq(count, 0, "a vertex inside its neighbours' tets (x = %g) was flagged", w.x[3 * q]);
    cr_expect_eq(term_value(w.self, w.x), 0.0);
  }
  /* pushed past two layers of tets (through its own body): flagged */
  w.x[3 * q] = 0.2;
  cr_assert_eq(bs_term_self_detect(w.self, w.x, &count, NULL, &err), 0, "%s", err.msg);
  cr_expect_eq(count, 1, "a vertex pushed through its own body: %d flagged", count);
  world_destroy(&w);
}

/* A vertex pushed through its own body leaves its excluded neighbourhood
 * through an interface face, its distance to which is then a primitive: Phi
 * starts from 0 there (continuous), where the distance to the body's surface
 * alone would make it jump by k (1/3 m)^3 ~ 4e4 J. Further in, the distance
 * grows smoothly and the vertex is pushed back. */
Test(self_detect, leaving_the_neighbourhood_is_continuous) {
  const double k = 1e6;
  world w;
  world_create(&w, k);
  bs_error err;
  const int32_t q = a_vertex_off_the_lines(&w);
  const int steps = 1000;
  const double x0 = 0.45, x1 = 0.05, h = (x0 - x1) / steps;
  double E_prev = 0, jump = 0, E_end = 0;
  int first = -1;
  for (int i = 0; i <= steps; i++) {
    w.x[3 * q] = x0 - h * i;
    int32_t count = -1;
    cr_assert_eq(bs_term_self_detect(w.self, w.x, &count, NULL, &err), 0, "%s", err.msg);
    const double E = term_value(w.self, w.x);
    cr_assert(isfinite(E) && E >= 0);
    if (count > 0 && first < 0) {
      first = i;
      cr_expect_leq(E, k * h * h * h, "the first flagged position (x = %g) has Phi = %g", w.x[3 * q], E);
    }
    if (i > 0) jump = fmax(jump, fabs(E - E_prev));
    E_prev = E_end = E;
  }
  cr_assert(first > 0, "never flagged");
  /* Phi ~ k depth^3 with depth growing at most by h per step: |dPhi| <= 3 k depth^2 h */
  cr_expect_leq(jump, 3 * k * 0.5 * 0.5 * h, "largest change of Phi between neighbouring positions %g", jump);
  cr_expect_gt(E_end, 0.0);
  /* there (x = 0.05, an interface face its primitive) the gradient is the
     value's central difference, on q and on the face's vertices */
  double *g = calloc(w.n3, sizeof(double));
  term_gradient(w.self, w.x, g);
  double gmax = 0, emax = 0;
  int moved = 0;
  for (size_t i = 0; i < w.n3; i++) {
    if (g[i] == 0.0) continue;
    moved += (int)(i / 3 != (size_t)q);
    const double s0 = w.x[i], hh = 1e-6;
    w.x[i] = s0 + hh;
    const double Ep = term_value(w.self, w.x);
    w.x[i] = s0 - hh;
    const double Em = term_value(w.self, w.x);
    w.x[i] = s0;
    gmax = fmax(gmax, fabs(g[i]));
    emax = fmax(emax, fabs((Ep - Em) / (2 * hh) - g[i]));
  }
  cr_expect(moved >= 3, "the primitive's vertices get no force");
  cr_expect(gmax > 0 && emax <= 1e-6 * gmax, "gradient vs central differences: error %g of %g", emax, gmax);
  free(g);
  world_destroy(&w);
}

/* ---- term derivatives ------------------------------------------------- */

static void dense_from_bsr(const bs_bsr *H, double *D, size_t n3) {
  memset(D, 0, sizeof(double) * n3 * n3);
  for (int32_t i = 0; i < H->n; i++)
    for (int32_t s = H->row_ptr[i]; s < H->row_ptr[i + 1]; s++)
      for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) D[(3 * (size_t)i + a) * n3 + 3 * (size_t)H->col[s] + b] = H->val[9 * (size_t)s + 3 * a + b];
}

/* Largest central-difference errors of the term's gradient g and dense
 * Hessian D at w->x, at steps 1e-3, 5e-4, 2.5e-4 (errg, errH); gp, gm: n3
 * scratch. */
static void term_fd_errors(world *w, const double *g, const double *D, double *gp, double *gm, double errg[3],
                      double errH[3]) {
  const size_t n3 = w->n3;
  double h = 1e-3;
  for (int r = 0; r < 3; r++, h /= 2) {
    errg[r] = errH[r] = 0;
    for (size_t i = 0; i < n3; i++) {
      double s0 = w->x[i];
      w->x[i] = s0 + h;
      memset(gp, 0, sizeof(double) * n3);
      double Ep = term_gradient(w->self, w->x, gp);
      w->x[i] = s0 - h;
      memset(gm, 0, sizeof(double) * n3);
      double Em = term_gradient(w->self, w->x, gm);
      w->x[i] = s0;
      errg[r] = fmax(errg[r], fabs((Ep - Em) / (2 * h) - g[i]));
      for (size_t j = 0; j < n3; j++) errH[r] = fmax(errH[r], fabs((gp[j] - gm[j]) / (2 * h) - D[j * n3 + i]));
    }
  }
}

/* The two boxes (stiffness 1e6) with B's face-centre vertex pushed into A
 * through A's x = 1 face (the face region, and edge/vertex cases from B's
 * corners), and a matrix of the fem's pattern into *H. */
static void face_contact_world(world *w, bs_bsr **H) {
  bs_error err;
  world_create(w, 1e6);
  int32_t p = b_face_centre(w);
  w->x[3 * p] = 0.93, w->x[3 * p + 1] = 0.41, w->x[3 * p + 2] = 0.57;
  cr_assert_eq(bs_fem_matrix(w->fem, H, &err), 0, "%s", err.msg);
}

Test(self_term, gradient_and_hessian_match_fd) {
  world w;
  bs_bsr *H;
  face_contact_world(&w, &H);
  bs_error err;
  size_t n3 = w.n3;
  double *g = calloc(n3, sizeof(double)), *gp = calloc(n3, sizeof(double)), *gm = calloc(n3, sizeof(double));
  double *D = malloc(sizeof(double) * n3 * n3);
  term_gradient(w.self, w.x, g);
  term_hessian(w.self, w.x, H);
  cr_assert_eq(bs_bsr_check(H, 1e-12, &err), 0, "%s", err.msg);
  dense_from_bsr(H, D, n3);
  int64_t cnt = 0;
  cr_assert_eq(bs_term_self_missing_blocks(w.self, w.x, 0, NULL, NULL, &cnt, &err), 0, "%s", err.msg);
  cr_expect(cnt >= 2 && cnt % 2 == 0, "%lld missing blocks (p does not share a tet with A)", (long long)cnt);
  int32_t *pairs = malloc(sizeof(int32_t) * 2 * (size_t)cnt);
  double *blocks = malloc(sizeof(double) * 9 * (size_t)cnt);
  int64_t cnt2 = 0;
  cr_assert_eq(bs_term_self_missing_blocks(w.self, w.x, cnt, pairs, blocks, &cnt2, &err), 0, "%s", err.msg);
  cr_expect_eq(cnt2, cnt);
  bs_self_stats st;
  bs_term_self_stats(w.self, &st, &err);
  cr_expect_eq(st.missing_blocks, cnt);
  for (int64_t s = 0; s < cnt; s++) {
    cr_expect(bs_bsr_slot(w.fem->pattern, pairs[2 * s], pairs[2 * s + 1]) < 0, "listed block is in the pattern");
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++)
        D[(3 * (size_t)pairs[2 * s] + a) * n3 + 3 * (size_t)pairs[2 * s + 1] + b] += blocks[9 * s + 3 * a + b];
  }
  /* missing pairs are among the coupling pairs within the depth */
  int32_t *cp = NULL;
  int64_t ncp = 0;
  cr_assert_eq(bs_self_coupling_pairs(w.fem, w.x, 0.08, &cp, &ncp, &err), 0, "%s", err.msg);
  for (int64_t s = 0; s < cnt; s++) {
    int32_t i = pairs[2 * s] < pairs[2 * s + 1] ? pairs[2 * s] : pairs[2 * s + 1];
    int32_t j = pairs[2 * s] ^ pairs[2 * s + 1] ^ i;
    int found = 0;
    for (int64_t r = 0; r < ncp; r++) found |= cp[2 * r] == i && cp[2 * r + 1] == j;
    cr_expect(found, "missing block (%d, %d) not among the coupling pairs", i, j);
  }
  free(cp);
  double errg[3], errH[3];
  term_fd_errors(&w, g, D, gp, gm, errg, errH);
  double gscale = 0;
  for (size_t i = 0; i < n3; i++) gscale = fmax(gscale, fabs(g[i]));
  cr_expect(gscale > 0);
  for (int r = 0; r < 2; r++) {
    cr_expect(errg[r + 1] < 0.3 * errg[r] || errg[r + 1] < 1e-9 * gscale, "gradient FD errors %g -> %g", errg[r],
              errg[r + 1]);
    cr_expect(errH[r + 1] < 0.3 * errH[r] || errH[r + 1] < 1e-9 * gscale, "Hessian FD errors %g -> %g", errH[r],
              errH[r + 1]);
  }
  cr_expect(errg[2] < 1e-5 * gscale && errH[2] < 1e-4 * gscale, "errors %g %g (scale %g)", errg[2], errH[2], gscale);
  free(pairs);
  free(blocks);
  bs_bsr_destroy(&H);
  free(g);
  free(gp);
  free(gm);
  free(D);
  world_destroy(&w);
}

/* The term's convexified Hessian (bs_terms.h hessian_convexified) at a
 * face contact: it differs from the exact one by a PSD matrix, is itself PSD
 * (a sum of projected contact Hessians), and leaves E and grad E alone. */
Test(self_term, convexified_hessian_is_psd) {
  world w;
  bs_bsr *H, *Hc;
  face_contact_world(&w, &H);
  bs_error err;
  const size_t n3 = w.n3;
  cr_assert_not_null(w.self->ops->hessian_convexified);
  cr_assert_eq(bs_fem_matrix(w.fem, &Hc, &err), 0, "%s", err.msg);
  const double E0 = term_value(w.self, w.x);
  term_hessian(w.self, w.x, H);
  cr_assert_eq(w.self->ops->hessian_convexified(w.self, w.x, Hc), BS_TERM_OK);
  cr_expect_eq(term_value(w.self, w.x), E0);
  cr_assert_eq(bs_bsr_check(Hc, 1e-12, &err), 0, "%s", err.msg);
  double *D = malloc(sizeof(double) * n3 * n3), *Dc = malloc(sizeof(double) * n3 * n3);
  double *v = malloc(sizeof(double) * n3);
  dense_from_bsr(H, D, n3);
  dense_from_bsr(Hc, Dc, n3);
  double scale = 0, diff = 0;
  for (size_t i = 0; i < n3 * n3; i++) scale = fmax(scale, fabs(D[i])), diff = fmax(diff, fabs(Dc[i] - D[i]));
  cr_expect(scale > 0 && diff > 1e-6 * scale, "no negative curvature removed (|Hc - H| = %g, |H| = %g)", diff, scale);
  unsigned r = 11;
  for (int t = 0; t < 100; t++) {
    for (size_t i = 0; i < n3; i++) v[i] = rnd(&r);
    double qc = 0, qd = 0;
    for (size_t i = 0; i < n3; i++)
      for (size_t j = 0; j < n3; j++) qc += v[i] * Dc[i * n3 + j] * v[j], qd += v[i] * (Dc[i * n3 + j] - D[i * n3 + j]) * v[j];
    cr_expect(qc >= -1e-10 * scale && qd >= -1e-10 * scale, "v^T Hc v = %g, v^T (Hc - H) v = %g", qc, qd);
  }
  free(D);
  free(Dc);
  free(v);
  bs_bsr_destroy(&H);
  bs_bsr_destroy(&Hc);
  world_destroy(&w);
}

/* Many contacts (more than one batch of the parallel contact Hessians): two
 * 12^3-cell boxes overlapping by 0.8 of a cell, offset off each other's mesh
 * planes. The Hessian, exact and convexified, is the same bit for bit with 1
 * and 3 threads, symmetric, and holds every contact's blocks (the extras are
 * the missing blocks); the exact one times random directions matches central
 * differences of the gradient to O(h^2). With the paper's primitives (every
 * boundary triangle without p, bs_selfcollide.h) vertices near the other
 * box's edges were measured to their own neighbours' triangles, equidistant
 * from two of them: the differences jumped (3.9e3 max |H v| at h = 1e-5). */
typedef struct overlap {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_term *self;
  int32_t contacts;
} overlap;

static void overlap_create(overlap *o, int threads) {
  bs_error err;
  double loA[3] = {0, 0, 0}, hiA[3] = {1, 1, 1};
  double loB[3] = {0.9337, 0.0311, 0.0523}, hiB[3] = {1.9337, 1.0311, 1.0523};
  int32_t nA;
  o->mesh = two_boxes(loA, hiA, 12, loB, hiB, 12, &nA);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(o->mesh, 1, &mat, NULL, &o->fem, &err), 0, "%s", err.msg);
  const int nt = omp_get_max_threads();
  omp_set_num_threads(threads); /* the term's thread count is the one at its creation */
  cr_assert_eq(bs_term_self_create(o->fem, NULL, 1e6, &o->self, &err), 0, "%s", err.msg);
  omp_set_num_threads(nt);
  double depth;
  cr_assert_eq(bs_term_self_detect(o->self, o->mesh->x, &o->contacts, &depth, &err), 0, "%s", err.msg);
}

static void overlap_destroy(overlap *o) {
  bs_term_destroy(&o->self);
  bs_fem_destroy(&o->fem);
  bs_mesh_destroy(&o->mesh);
}

static bs_bsr *overlap_hessian(const overlap *o, int convex) {
  bs_error err;
  bs_bsr *H;
  cr_assert_eq(bs_fem_matrix(o->fem, &H, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_reserve_extra(H, o->self->hessian_extra, &err), 0, "%s", err.msg);
  cr_assert_eq((convex ? o->self->ops->hessian_convexified : o->self->ops->hessian)(o->self, o->mesh->x, H),
               BS_TERM_OK);
  int64_t missing = -1;
  cr_assert_eq(bs_term_self_missing_blocks(o->self, o->mesh->x, 0, NULL, NULL, &missing, &err), 0, "%s", err.msg);
  cr_expect_eq(H->n_extra, missing, "%lld extras, %lld missing blocks", (long long)H->n_extra, (long long)missing);
  cr_assert_eq(bs_bsr_check(H, 1e-12, &err), 0, "%s", err.msg);
  return H;
}

/* max |H v - (g(x + h v) - g(x - h v)) / 2h| over |H v| for 3 random v. */
static double overlap_fd_error(const overlap *o, const bs_bsr *H, double h) {
  const size_t n3 = 3 * (size_t)o->mesh->n_vertices;
  double *x = malloc(n3 * sizeof *x), *v = malloc(n3 * sizeof *v), *Hv = malloc(n3 * sizeof *Hv);
  double *gp = malloc(n3 * sizeof *gp), *gm = malloc(n3 * sizeof *gm), worst = 0;
  unsigned r = 5;
  for (int t = 0; t < 3; t++) {
    for (size_t i = 0; i < n3; i++) v[i] = rnd(&r);
    bs_bsr_mul(H, NULL, v, Hv);
    for (size_t i = 0; i < n3; i++) x[i] = o->mesh->x[i] + h * v[i];
    memset(gp, 0, n3 * sizeof *gp);
    term_gradient(o->self, x, gp);
    for (size_t i = 0; i < n3; i++) x[i] = o->mesh->x[i] - h * v[i];
    memset(gm, 0, n3 * sizeof *gm);
    term_gradient(o->self, x, gm);
    double e = 0, s = 0;
    for (size_t i = 0; i < n3; i++) e = fmax(e, fabs(Hv[i] - (gp[i] - gm[i]) / (2 * h))), s = fmax(s, fabs(Hv[i]));
    cr_assert(s > 0);
    worst = fmax(worst, e / s);
  }
  free(x);
  free(v);
  free(Hv);
  free(gp);
  free(gm);
  return worst;
}

Test(self_term, many_contacts_same_hessian_with_any_thread_count) {
  overlap o1, o3;
  overlap_create(&o1, 1);
  overlap_create(&o3, 3);
  cr_assert(o1.contacts > 256 && o1.contacts == o3.contacts, "%d and %d contacts (more than a batch of 256 wanted)",
            o1.contacts, o3.contacts);
  for (int convex = 0; convex < 2; convex++) {
    bs_bsr *H1 = overlap_hessian(&o1, convex), *H3 = overlap_hessian(&o3, convex);
    cr_assert(H1->n_extra > 0 && H1->n_extra == H3->n_extra);
    cr_assert_eq(memcmp(H1->val, H3->val, 9 * (size_t)H1->nnzb * sizeof(double)), 0, "convex %d: values differ",
                 convex);
    cr_assert_eq(memcmp(H1->extra_val, H3->extra_val, 9 * (size_t)H1->n_extra * sizeof(double)), 0,
                 "convex %d: extras differ", convex);
    if (!convex) {
      const double e1 = overlap_fd_error(&o3, H3, 1e-5), e2 = overlap_fd_error(&o3, H3, 1e-6);
      cr_expect(e2 < 1e-5 && e2 < 0.1 * e1 + 1e-9, "FD errors %g (h 1e-5), %g (h 1e-6)", e1, e2);
    }
    bs_bsr_destroy(&H1);
    bs_bsr_destroy(&H3);
  }
  overlap_destroy(&o1);
  overlap_destroy(&o3);
}

Test(self_term, coupling_pairs_by_margin) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  int32_t *pairs = NULL;
  int64_t n = -1;
  /* the boxes are 0.5 apart: margin 0.45 couples within each box only (vertices
   * an edge or more apart), 0.55 joins A and B */
  cr_assert_eq(bs_self_coupling_pairs(w.fem, NULL, 0.0, &pairs, &n, &err), 0, "%s", err.msg);
  cr_expect_eq(n, 0, "margin 0: %lld pairs", (long long)n);
  cr_expect_null(pairs);
  int64_t cross = 0;
  cr_assert_eq(bs_self_coupling_pairs(w.fem, NULL, 0.45, &pairs, &n, &err), 0, "%s", err.msg);
  for (int64_t s = 0; s < n; s++) cross += pairs[2 * s] < w.nA && pairs[2 * s + 1] >= w.nA;
  cr_expect_eq(cross, 0, "margin 0.45 joined A and B");
  free(pairs);
  cr_assert_eq(bs_self_coupling_pairs(w.fem, NULL, 0.55, &pairs, &n, &err), 0, "%s", err.msg);
  for (int64_t s = 0; s < n; s++) {
    cr_expect(bs_bsr_slot(w.fem->pattern, pairs[2 * s], pairs[2 * s + 1]) < 0, "pair in the pattern");
    cross += pairs[2 * s] < w.nA && pairs[2 * s + 1] >= w.nA;
    if (s) cr_expect(pairs[2 * s - 2] < pairs[2 * s] || (pairs[2 * s - 2] == pairs[2 * s] && pairs[2 * s - 1] < pairs[2 * s + 1]));
  }
  cr_expect(cross > 0, "margin 0.55 must couple the facing sides of A and B");
  free(pairs);
  world_destroy(&w);
}

/* ---- friction --------------------------------------------------------- */

static double kinetic(const bs_fem *fem, const double *v) {
  double K = 0;
  for (int32_t i = 0; i < fem->n_vertices; i++)
    K += 0.5 * fem->mass[i] * (v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
  return K;
}

Test(self_friction, lowers_kinetic_energy_keeps_positions) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  int32_t p = b_face_centre(&w);
  w.x[3 * p] = 0.9, w.x[3 * p + 1] = 0.4, w.x[3 * p + 2] = 0.52;
  size_t n3 = w.n3;
  double *v = malloc(sizeof(double) * n3), *v0 = malloc(sizeof(double) * n3), *x0 = malloc(sizeof(double) * n3);
  memcpy(x0, w.x, sizeof(double) * n3);
  for (unsigned seed = 1; seed <= 5; seed++) {
    unsigned s = seed;
    for (size_t i = 0; i < n3; i++) v0[i] = 2 * rnd(&s);
    double mus[4] = {0, 0.01, 0.3, 1e3};
    for (int m = 0; m < 4; m++) {
      memcpy(v, v0, sizeof(double) * n3);
      int32_t nc = -1;
      cr_assert_eq(bs_self_friction(w.self, w.x, mus[m], 1.0 / 24, NULL, v, &nc, &err), 0, "%s", err.msg);
      cr_expect_eq(memcmp(x0, w.x, sizeof(double) * n3), 0, "positions changed");
      double K0 = kinetic(w.fem, v0), K1 = kinetic(w.fem, v);
      cr_expect(K1 <= K0 * (1 + 1e-14), "mu %g: kinetic energy %.17g -> %.17g", mus[m], K0, K1);
      if (mus[m] == 0) {
        cr_expect_eq(memcmp(v, v0, sizeof(double) * n3), 0, "mu = 0 changed velocities");
        cr_expect_eq(nc, 0);
        continue;
      }
      cr_expect_eq(nc, 1);
      cr_expect(K1 < K0, "mu %g: friction removed nothing", mus[m]);
      double P0[3] = {0, 0, 0}, P1[3] = {0, 0, 0};
      for (int32_t i = 0; i < w.mesh->n_vertices; i++)
        for (int k = 0; k < 3; k++) P0[k] += w.fem->mass[i] * v0[3 * i + k], P1[k] += w.fem->mass[i] * v[3 * i + k];
      for (int k = 0; k < 3; k++) cr_expect(fabs(P1[k] - P0[k]) < 1e-10, "momentum %d: %g -> %g", k, P0[k], P1[k]);
      /* the normal (x) component of every velocity is unchanged: impulses are tangential */
      for (size_t i = 0; i < n3; i += 3) cr_expect_eq(v[i], v0[i], "normal velocity changed");
    }
  }
  /* a fixed vertex (mask 0) keeps its velocity */
  uint8_t *mask = malloc((size_t)w.mesh->n_vertices);
  memset(mask, 1, (size_t)w.mesh->n_vertices);
  mask[p] = 0;
  for (size_t i = 0; i < n3; i++) v[i] = v0[i];
  cr_assert_eq(bs_self_friction(w.self, w.x, 0.5, 1.0 / 24, mask, v, NULL, &err), 0, "%s", err.msg);
  for (int k = 0; k < 3; k++) cr_expect_eq(v[3 * p + k], v0[3 * p + k]);
  free(mask);
  free(v);
  free(v0);
  free(x0);
  world_destroy(&w);
}

/* With mu large the contact's relative tangential velocity vanishes. */
Test(self_friction, sticks_with_large_mu) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  int32_t p = b_face_centre(&w);
  w.x[3 * p] = 0.9, w.x[3 * p + 1] = 0.4, w.x[3 * p + 2] = 0.52;
  double *v = calloc(w.n3, sizeof(double));
  for (int32_t i = 0; i < w.nA; i++) v[3 * i + 1] = 1.0; /* A slides along +y, B at rest */
  cr_assert_eq(bs_self_friction(w.self, w.x, 1e6, 1.0 / 24, NULL, v, NULL, &err), 0, "%s", err.msg);
  /* vbar (A's closest point minus p) tangential part is now zero: A's face
   * vertices moved uniformly in y, so their weighted velocity is one value */
  double vA = -1;
  for (int32_t i = 0; i < w.nA; i++)
    if (v[3 * i + 1] != 1.0) vA = v[3 * i + 1];
  cr_expect(vA < 1.0 && vA > 0, "A's contact vertices slowed: %g", vA);
  cr_expect(v[3 * p + 1] > 0, "p dragged along: %g", v[3 * p + 1]);
  free(v);
  world_destroy(&w);
}

/* ---- errors ----------------------------------------------------------- */

Test(self_errors, culprits_named) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  bs_term *t = NULL;
  cr_expect_eq(bs_term_self_create(w.fem, NULL, -1, &t, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "k = -1") != NULL, "%s", err.msg);
  cr_expect_eq(bs_term_self_create(w.fem, NULL, NAN, &t, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "stiffness") != NULL, "%s", err.msg);
  cr_expect_null(t);
  bs_term *grav = NULL;
  double gv[3] = {0, -9.8, 0};
  cr_assert_eq(bs_term_gravity_create(w.fem, NULL, gv, &grav, &err), 0, "%s", err.msg);
  bs_self_stats st;
  cr_expect_eq(bs_term_self_stats(grav, &st, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "\"gravity\"") != NULL, "%s", err.msg);
  cr_expect_eq(bs_term_is_self(grav), 0);
  cr_expect_eq(bs_term_is_self(w.self), 1);
  double *v = calloc(w.n3, sizeof(double));
  cr_expect_eq(bs_self_friction(w.self, w.x, -0.1, 0.1, NULL, v, NULL, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "mu = -0.1") != NULL, "%s", err.msg);
  cr_expect_eq(bs_self_friction(w.self, w.x, 0.1, 0, NULL, v, NULL, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "dt = 0") != NULL, "%s", err.msg);
  w.x[3 * 5 + 1] = NAN;
  cr_expect_eq(bs_term_self_detect(w.self, w.x, NULL, NULL, &err), BS_ENUMERIC);
  cr_expect(strstr(err.msg, "vertex 5") != NULL, "%s", err.msg);
  double E;
  cr_expect_eq(w.self->ops->value(w.self, w.x, &E), BS_TERM_NOT_EVALUABLE, "a non-finite x must not be evaluable");
  int32_t *pairs;
  int64_t n;
  cr_expect_eq(bs_self_coupling_pairs(w.fem, NULL, -1, &pairs, &n, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "margin = -1") != NULL, "%s", err.msg);
  bs_term_destroy(&grav);
  bs_term_destroy(&grav); /* NULL is fine */
  free(v);
  world_destroy(&w);
}

/* A non-finite x is outside the term's domain: value, gradient and hessian
 * say so by their status (never by a NaN) and leave their outputs alone. */
Test(self_errors, non_finite_x_is_not_evaluable) {
  world w;
  world_create(&w, 1e6);
  bs_error err;
  double E = 12.5, *g = calloc(w.n3, sizeof(double));
  bs_bsr *H = NULL;
  cr_assert_eq(bs_fem_matrix(w.fem, &H, &err), 0, "%s", err.msg);
  bs_bsr_zero(H);
  for (int pass = 0; pass < 2; pass++) { /* NaN, then +Inf */
    w.x[3 * 5 + 1] = pass ? INFINITY : NAN;
    cr_expect_eq(w.self->ops->value(w.self, w.x, &E), BS_TERM_NOT_EVALUABLE);
    cr_expect_eq(w.self->ops->gradient(w.self, w.x, &E, g), BS_TERM_NOT_EVALUABLE);
    cr_expect_eq(w.self->ops->hessian(w.self, w.x, H), BS_TERM_NOT_EVALUABLE);
  }
  cr_expect_eq(E, 12.5, "E was written: %g", E);
  for (size_t i = 0; i < w.n3; i++) cr_expect_eq(g[i], 0.0, "g[%zu] was written: %g", i, g[i]);
  for (int64_t i = 0; i < 9 * H->nnzb; i++) cr_expect_eq(H->val[i], 0.0, "H was written (value %lld)", (long long)i);
  /* back at a finite x: evaluable again, E = 0 at rest */
  memcpy(w.x, w.mesh->x, sizeof(double) * w.n3);
  cr_expect_eq(w.self->ops->value(w.self, w.x, &E), BS_TERM_OK);
  cr_expect_eq(E, 0.0);
  cr_expect_str_eq(bs_term_status_name(BS_TERM_NOT_EVALUABLE), "not_evaluable");
  cr_expect_str_eq(bs_term_status_name(BS_TERM_OK), "ok");
  bs_bsr_destroy(&H);
  free(g);
  world_destroy(&w);
}

/* ---- dynamics: two boxes of one mesh fall onto each other -------------- */

typedef struct fric_ctx {
  bs_term *self;
  const uint8_t *mask;
  double mu;
} fric_ctx;

static int post_friction(const double *x_n, double *x, const double *g, double *v, double dt, void *ctx,
                         bs_error *err) {
  (void)x_n, (void)g;
  fric_ctx *c = ctx;
  return bs_self_friction(c->self, x, c->mu, dt, c->mask, v, NULL, err);
}

/* A = [0,1] x [0,0.5] x [0,1] with its bottom fixed; B above it, offset so
 * no vertices coincide, falling at 2 m/s. Returns B's lowest y after the run
 * and the largest penetration depth seen at the end. */
static void drop(int with_self, double *minyB, double *depth_end, int *failed, int *newton) {
  bs_error err;
  double loA[3] = {0, 0, 0}, hiA[3] = {1, 0.5, 1}, loB[3] = {0.23, 0.6, 0.17}, hiB[3] = {0.83, 1.0, 0.77};
  int32_t nA;
  bs_mesh *mesh = two_boxes(loA, hiA, 2, loB, hiB, 2, &nA);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_FIXED_COROTATED, 2e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  bs_fem *fem;
  cr_assert_eq(bs_fem_create(mesh, 1, &mat, NULL, &fem, &err), 0, "%s", err.msg);
  bs_step_data step;
  memset(&step, 0, sizeof step);
  bs_term *terms[4];
  int nt = 0;
  double g[3] = {0, -9.8, 0};
  cr_assert_eq(bs_term_inertia_create(fem, &step, &terms[nt++], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_gravity_create(fem, &step, g, &terms[nt++], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_elastic_create(fem, 0, &terms[nt++], &err), 0, "%s", err.msg);
  if (with_self) cr_assert_eq(bs_term_self_create(fem, &step, 1e8, &terms[nt++], &err), 0, "%s", err.msg);
  size_t nv = (size_t)mesh->n_vertices, n3 = 3 * nv;
  uint8_t *mask = malloc(nv);
  for (size_t i = 0; i < nv; i++) mask[i] = !((int32_t)i < nA && mesh->x[3 * i + 1] == 0);
  bs_integrator_opts o;
  bs_integrator_opts_default(&o);
  o.min.tol = 1e-4;
  bs_integrator *I;
  cr_assert_eq(bs_integrator_create(fem, &step, nt, terms, mask, NULL, NULL, &o, &I, &err), 0, "%s", err.msg);
  fric_ctx fc = {with_self ? terms[3] : NULL, mask, 0.2};
  if (with_self) {
    bs_step_hooks hk;
    memset(&hk, 0, sizeof hk);
    hk.post_solve = post_friction;
    hk.ctx = &fc;
    bs_integrator_set_hooks(I, &hk);
  }
  double *x = malloc(sizeof(double) * n3), *v = calloc(n3, sizeof(double));
  memcpy(x, mesh->x, sizeof(double) * n3);
  for (size_t i = (size_t)nA; i < nv; i++) v[3 * i + 1] = -2.0;
  double dt = 1.0 / 96;
  *failed = 0;
  *newton = 0;
  for (int s = 0; s < 36; s++) {
    bs_step_stats st;
    cr_assert_eq(bs_integrator_step(I, s * dt, dt, x, v, &st, &err), 0, "%s", err.msg);
    *failed += st.failed;
    *newton += st.min.iterations;
    if (getenv("BS_SELF_DEBUG"))
      cr_log_info("step %d: self %d iterations %d ls %d reason %s |g| %g", s, with_self, st.min.iterations,
                  st.min.ls_evaluations, st.min.reason_text ? st.min.reason_text : "", st.min.grad_norm);
  }
  *minyB = INFINITY;
  for (size_t i = (size_t)nA; i < nv; i++) *minyB = fmin(*minyB, x[3 * i + 1]);
  *depth_end = 0;
  if (with_self) {
    int32_t c;
    cr_assert_eq(bs_term_self_detect(terms[3], x, &c, depth_end, &err), 0, "%s", err.msg);
    bs_self_stats ss;
    bs_term_self_stats(terms[3], &ss, &err);
    cr_log_info("drop: %lld evaluations, %lld rebuilds; seconds rebuild %.3g refit %.3g detect %.3g closest %.3g",
                (long long)ss.evaluations, (long long)ss.rebuilds, ss.t_rebuild, ss.t_refit, ss.t_detect,
                ss.t_closest);
  }
  bs_integrator_destroy(&I);
  for (int i = 0; i < nt; i++) bs_term_destroy(&terms[i]);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&mesh);
  free(mask);
  free(x);
  free(v);
}

Test(self_dynamics, falling_boxes_end_separated, .timeout = 300) {
  double miny, depth;
  int failed, newton;
  drop(0, &miny, &depth, &failed, &newton);
  cr_expect(miny < 0.4, "control without self-collision: B should sink into A (min y %g)", miny);
  drop(1, &miny, &depth, &failed, &newton);
  cr_expect_eq(failed, 0, "%d steps failed", failed);
  /* The coupling blocks (vertex, primitive) are outside the fem pattern; with
   * them in the Newton system (bs_bsr extra list) a step takes ~14 Newton
   * iterations, without them ~60 (linear convergence while in contact). */
  cr_expect(newton < 25 * 36, "%d Newton iterations over 36 steps: is the self-collision Hessian complete?", newton);
  /* A (soft, fixed at its bottom) is pressed down a little under B: judge
   * the separation by the penetration depth, and B's height against the control */
  cr_expect(miny > 0.45, "B's lowest vertex at y = %g, A's top at rest at 0.5", miny);
  cr_expect(depth < 0.01, "penetration depth %g at the end", depth);
}
