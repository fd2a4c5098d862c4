/* test_barrier_friction.c — friction of the barrier self-contact
 * (bs_ipc_friction.h): the kernels (closest-point weights, f0 and its
 * derivatives); the term's energy, gradient and Hessian against central
 * differences at random configurations of two boxes (point-triangle and
 * edge-edge pairs, every |u| below eps, every one above, and mixed); the
 * normal force of a single point-triangle pair against the barrier's force
 * and the sliding force mu lambda; the same bits on 1 and 2 threads; bad
 * input. The scenes (a box on a box, sticking and sliding):
 * test_barrier_friction_scenes.c. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_ipc.h"
#include "bs_ipc_friction.h"
#include "bs_ipc_term.h"
#include "bs_mesh.h"
#include "bs_terms.h"
#include "test_term_eval.h"

/* ---- kernels ------------------------------------------------------------------ */

static double norm3(const double r[3]) { return sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]); }

static void combo(const double w[4], const double y[12], double o[3]) {
  for (int k = 0; k < 3; k++) o[k] = w[0] * y[k] + w[1] * y[3 + k] + w[2] * y[6 + k] + w[3] * y[9 + k];
}

/* sum w_i y_i has the length of the exact distance, for every closest-feature
 * type (points around a triangle and segments in random positions). */
Test(barrier_friction, closest_weights_give_the_distance) {
  srand(7);
  int types_pt[7] = {0}, types_ee[9] = {0};
  for (int it = 0; it < 4000; it++) {
    double y[12], w[4], r[3];
    for (int i = 0; i < 12; i++) y[i] = 2.0 * rand() / RAND_MAX - 1;
    const int ee = it % 2;
    if (!ee) {
      bs_ipc_pt_type ty;
      const double d2 = bs_ipc_pt_d2_full(y, y + 3, y + 6, y + 9, &ty, NULL, NULL);
      types_pt[ty]++;
      bs_ipc_pt_closest_weights(y, y + 3, y + 6, y + 9, w);
      cr_assert_eq(w[0], 1);
      cr_assert_float_eq(w[1] + w[2] + w[3], -1, 1e-12);
      for (int k = 1; k < 4; k++) cr_assert(w[k] <= 1e-12 && w[k] >= -1 - 1e-12, "w %g", w[k]);
      combo(w, y, r);
      cr_assert_float_eq(norm3(r), sqrt(d2), 1e-9, "type %d", (int)ty);
    } else {
      bs_ipc_ee_type ty;
      const double d2 = bs_ipc_ee_d2_full(y, y + 3, y + 6, y + 9, &ty, NULL, NULL);
      types_ee[ty]++;
      bs_ipc_ee_closest_weights(y, y + 3, y + 6, y + 9, w);
      cr_assert_float_eq(w[0] + w[1], 1, 1e-12);
      cr_assert_float_eq(w[2] + w[3], -1, 1e-12);
      combo(w, y, r);
      cr_assert_float_eq(norm3(r), sqrt(d2), 1e-9, "type %d", (int)ty);
    }
  }
  cr_assert_gt(types_pt[BS_IPC_P_T], 0);
  cr_assert_gt(types_pt[BS_IPC_P_E0] + types_pt[BS_IPC_P_E1] + types_pt[BS_IPC_P_E2], 0);
  cr_assert_gt(types_pt[BS_IPC_P_T0] + types_pt[BS_IPC_P_T1] + types_pt[BS_IPC_P_T2], 0);
  cr_assert_gt(types_ee[BS_IPC_EA_EB], 0);
  cr_assert_gt(types_ee[BS_IPC_EA0_EB] + types_ee[BS_IPC_EA1_EB] + types_ee[BS_IPC_EA_EB0] + types_ee[BS_IPC_EA_EB1], 0);
}

/* f1 = f0' and f1' = f1' by central differences, below and above eps. */
Test(barrier_friction, f0_derivatives_match_differences) {
  const double eps = 1e-3, h = 1e-9;
  for (int i = 1; i < 40; i++) {
    const double y = 0.05 * i * eps;
    double f0, f1, f1p, a0, a1, ap, b0, b1, bp;
    bs_ipc_friction_f(y, eps, &f0, &f1, &f1p);
    bs_ipc_friction_f(y + h, eps, &a0, &a1, &ap);
    bs_ipc_friction_f(y - h, eps, &b0, &b1, &bp);
    cr_assert_float_eq((a0 - b0) / (2 * h), f1, 1e-6, "y/eps %g", y / eps);
    cr_assert_float_eq((a1 - b1) / (2 * h) * eps, f1p * eps, 1e-5, "y/eps %g", y / eps);
    cr_assert(f1 >= 0 && f1 <= 1 && f1p >= 0, "y/eps %g: f1 %g f1' %g", y / eps, f1, f1p);
  }
  double f0, f1, f1p; /* C^1 at eps: f0(eps) = eps, f1(eps) = 1, f1'(eps) = 0 */
  bs_ipc_friction_f(eps * (1 - 1e-12), eps, &f0, &f1, &f1p);
  cr_assert_float_eq(f0, eps, 1e-14);
  cr_assert_float_eq(f1, 1, 1e-9);
  cr_assert_float_eq(f1p * eps, 0, 1e-9);
}

/* ---- the term on two boxes ------------------------------------------------------ */

typedef struct fx {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_step_data step;
  bs_term *bar, *fr;
  double *xn, *x;
  int n3;
  int32_t na; /* box A's vertices: the first na */
} fx;

/* Box A = [0,1]^3 and box B (its copy lifted by 1 + gap, shifted sideways)
 * of c^3 cells each, every vertex of xⁿ jittered by up to jit (seeded); the
 * barrier (dhat, kappa 1e3) and its friction (mu 0.4, eps = eps_v dt =
 * 1e-2 m) lagged at xⁿ. */
static void fx_make(fx *s, int c, double gap, double dhat, double jit, unsigned seed) {
  memset(s, 0, sizeof *s);
  bs_mesh *A = NULL, *B = NULL;
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, lo2[3] = {0.031, 0.047, 1 + gap},
               hi2[3] = {1.031, 1.047, 2 + gap};
  cr_assert_eq(bs_mesh_create_box(lo, hi, c, c, c, &A, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_mesh_create_box(lo2, hi2, c, c, c, &B, &err), 0, "%s", err.msg);
  const int32_t nv = A->n_vertices + B->n_vertices, nt = A->n_tets + B->n_tets;
  double *x = malloc(sizeof(double) * 3 * (size_t)nv);
  int32_t *tets = malloc(sizeof(int32_t) * 4 * (size_t)nt);
  memcpy(x, A->x, sizeof(double) * 3 * (size_t)A->n_vertices);
  memcpy(x + 3 * (size_t)A->n_vertices, B->x, sizeof(double) * 3 * (size_t)B->n_vertices);
  memcpy(tets, A->tets, sizeof(int32_t) * 4 * (size_t)A->n_tets);
  for (int32_t i = 0; i < 4 * B->n_tets; i++) tets[4 * (size_t)A->n_tets + i] = B->tets[i] + A->n_vertices;
  cr_assert_eq(bs_mesh_create(nv, x, nt, tets, 0, NULL, &s->mesh, &err), 0, "%s", err.msg);
  s->na = A->n_vertices;
  free(x);
  free(tets);
  bs_mesh_destroy(&A);
  bs_mesh_destroy(&B);
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(s->mesh, 1, &mat, NULL, &s->fem, &err), 0, "%s", err.msg);
  s->n3 = 3 * s->mesh->n_vertices;
  s->xn = malloc(sizeof(double) * (size_t)s->n3);
  s->x = malloc(sizeof(double) * (size_t)s->n3);
  srand(seed);
  for (int i = 0; i < s->n3; i++) s->xn[i] = s->mesh->x[i] + jit * (2.0 * rand() / RAND_MAX - 1);
  memcpy(s->x, s->xn, sizeof(double) * (size_t)s->n3);
  s->step = (bs_step_data){.dt = 0.01, .x_hat = s->xn, .x_n = s->xn, .time = 0.01, .load = 1};
  cr_assert_eq(bs_term_ipc_create(s->fem, &s->step, dhat, 1e3, &s->bar, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_ipc_friction_create(s->bar, 0.4, 1.0, &s->fr, &err), 0, "%s", err.msg);
  cr_assert_eq(s->bar->ops->begin_step(s->bar, &err), 0, "%s", err.msg);
  cr_assert_eq(s->fr->ops->begin_step(s->fr, &err), 0, "%s", err.msg);
}

static void fx_free(fx *s) {
  bs_term_destroy(&s->fr);
  bs_term_destroy(&s->bar);
  bs_fem_destroy(&s->fem);
  bs_mesh_destroy(&s->mesh);
  free(s->xn);
  free(s->x);
}

static double max_abs(int n, const double *a) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}

/* grad E against central differences of E at s->x (step h), and H v
 * against central differences of grad E along a few directions v. */
static void check_fd(fx *s, double h, const char *what) {
  const int n = s->n3;
  const bs_term *t = s->fr;
  double *g = calloc((size_t)n, sizeof(double)), *gp = calloc((size_t)n, sizeof(double)),
         *gm = calloc((size_t)n, sizeof(double)), *y = malloc(sizeof(double) * (size_t)n),
         *v = malloc(sizeof(double) * (size_t)n), *Hv = malloc(sizeof(double) * (size_t)n);
  const double E = term_gradient(t, s->x, g), gtol = 1e-6 * fmax(max_abs(n, g), 1.0);
  cr_assert_float_eq(E, term_value(t, s->x), 0.0);
  for (int i = 0; i < n; i++) {
    memcpy(y, s->x, sizeof(double) * (size_t)n);
    y[i] = s->x[i] + h;
    const double Ep = term_value(t, y);
    y[i] = s->x[i] - h;
    const double fd = (Ep - term_value(t, y)) / (2 * h);
    cr_assert_leq(fabs(fd - g[i]), gtol, "%s: dof %d: gradient %.10g, differences %.10g", what, i, g[i], fd);
  }
  bs_bsr *H = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_fem_matrix(s->fem, &H, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_reserve_extra(H, t->hessian_extra, &err), 0, "%s", err.msg);
  term_hessian(t, s->x, H);
  bs_bsr_index_extra(H);
  bs_ipc_friction_stats st;
  cr_assert_eq(bs_term_ipc_friction_stats(t, &st, &err), 0);
  cr_assert_eq(st.missing_blocks, 0);
  for (int k = 0; k < 4; k++) {
    for (int i = 0; i < n; i++) v[i] = cos(1.7 * i * (k + 1) + k);
    bs_bsr_mul(H, NULL, v, Hv);
    double vHv = 0;
    for (int i = 0; i < n; i++) vHv += v[i] * Hv[i];
    cr_assert_geq(vHv, -1e-12 * max_abs(n, Hv) * n, "v.H v = %g", vHv);
    for (int i = 0; i < n; i++) y[i] = s->x[i] + h * v[i];
    memset(gp, 0, sizeof(double) * (size_t)n);
    term_gradient(t, y, gp);
    for (int i = 0; i < n; i++) y[i] = s->x[i] - h * v[i];
    memset(gm, 0, sizeof(double) * (size_t)n);
    term_gradient(t, y, gm);
    const double hmax = max_abs(n, Hv);
    cr_assert_gt(hmax, 0);
    for (int i = 0; i < n; i++) {
      const double fd = (gp[i] - gm[i]) / (2 * h);
      cr_assert_leq(fabs(fd - Hv[i]), 1e-5 * hmax, "%s: direction %d dof %d: H v %.10g, differences %.10g", what, k,
                    i, Hv[i], fd);
    }
  }
  bs_bsr_destroy(&H);
  free(g), free(gp), free(gm), free(y), free(v), free(Hv);
}

/* x = xⁿ with box B moved by shift (0.6, 0.8, 0) s and every vertex
 * jittered by up to j (per coordinate). Every pair's relative displacement
 * then has a length within |s| +- 2 sqrt3 j, and its tangential part at
 * least 0.8 s - 2 sqrt3 j (the y shift is tangential to every normal of
 * this configuration, which lies in the x-z plane up to the jitter of xⁿ). */
static void move(fx *s, double sh, double j, unsigned seed) {
  srand(seed);
  for (int i = 0; i < s->n3; i++) {
    const int v = i / 3, k = i % 3;
    const double b = v >= s->na ? (k == 0 ? 0.6 * sh : k == 1 ? 0.8 * sh : 0) : 0;
    s->x[i] = s->xn[i] + b + j * (2.0 * rand() / RAND_MAX - 1);
  }
}

/* Random configurations (3 seeds): all |u| < eps (E between mu N eps/3 and
 * mu N f0(0.5 eps)), all |u| > eps (E >= mu N 2 eps), and mixed around eps. */
Test(barrier_friction, derivatives_match_differences_below_and_above_eps) {
  const double eps = 1e-2;
  for (unsigned seed = 1; seed <= 3; seed++) {
    fx s;
    fx_make(&s, 2, 0.02, 0.05, 2e-3, seed);
    bs_ipc_friction_stats st;
    bs_error err = {0};
    cr_assert_eq(bs_term_ipc_friction_stats(s.fr, &st, &err), 0, "%s", err.msg);
    cr_assert_gt(st.pairs_pt, 0);
    cr_assert_gt(st.pairs_ee, 0);
    cr_assert_float_eq(st.eps, eps, 1e-15);
    const double muN = st.mu * st.normal_force;
    fprintf(stderr, "seed %u: %lld point-triangle, %lld edge-edge pairs, normal force %.4g N\n", seed,
            (long long)st.pairs_pt, (long long)st.pairs_ee, st.normal_force);
    /* below eps: |u| <= 0.3 eps + 2 sqrt3 0.05 eps < 0.5 eps */
    move(&s, 0.3 * eps, 0.05 * eps, seed + 10);
    double f0, f1, f1p;
    bs_ipc_friction_f(0.5 * eps, eps, &f0, &f1, &f1p);
    const double Elo = term_value(s.fr, s.x);
    cr_assert(Elo >= muN * eps / 3 * (1 - 1e-12) && Elo <= muN * f0, "E %g, mu N %g", Elo, muN);
    check_fd(&s, 1e-7, "below eps");
    /* above eps: |u| >= 0.8 * 5 eps - 2 sqrt3 0.3 eps > 2 eps */
    move(&s, 5 * eps, 0.3 * eps, seed + 20);
    const double Ehi = term_value(s.fr, s.x);
    cr_assert_geq(Ehi, muN * 2 * eps, "E %g, mu N %g", Ehi, muN);
    check_fd(&s, 1e-7, "above eps");
    /* mixed: |u| around eps */
    move(&s, eps, 0.4 * eps, seed + 30);
    check_fd(&s, 1e-7, "mixed");
    /* at xⁿ (u = 0 everywhere): E = mu N eps / 3, no force */
    memcpy(s.x, s.xn, sizeof(double) * (size_t)s.n3);
    double *g = calloc((size_t)s.n3, sizeof(double));
    cr_assert_float_eq(term_gradient(s.fr, s.x, g), muN * eps / 3, 1e-12 * muN * eps);
    cr_assert_eq(max_abs(s.n3, g), 0);
    free(g);
    check_fd(&s, 1e-9, "at x^n"); /* the Hessian is continuous but not differentiable at u = 0: a short step */
    fx_free(&s);
  }
}

/* One point-triangle pair: tet B's apex at height gap over tet A's top face
 * z = 0 (a 1 m apart elsewhere). Its lambda is the barrier's force on the
 * apex; sliding the apex 3 eps along x costs the force mu lambda against
 * x, taken from the triangle's vertices by the barycentric weights (the
 * forces sum to 0). */
Test(barrier_friction, single_pair_normal_force_and_sliding_force) {
  const double x[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.3, -1, 0.25, 0.25, 0.03, -0.5, -0.5, 1, 1.5, -0.2, 1, -0.2, 1.5, 1};
  const int32_t tets[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  bs_error err = {0};
  bs_mesh *m = NULL;
  bs_fem *fem = NULL;
  bs_material mat;
  cr_assert_eq(bs_mesh_create(8, x, 2, tets, 0, NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(m, 1, &mat, NULL, &fem, &err), 0, "%s", err.msg);
  bs_step_data step = {.dt = 0.01, .x_hat = x, .x_n = x, .time = 0.01, .load = 1};
  bs_term *bar = NULL, *fr = NULL;
  cr_assert_eq(bs_term_ipc_create(fem, &step, 0.1, 1e3, &bar, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_ipc_friction_create(bar, 0.5, 2e-3, &fr, &err), 0, "%s", err.msg);
  cr_assert_eq(bar->ops->begin_step(bar, &err), 0, "%s", err.msg);
  cr_assert_eq(fr->ops->begin_step(fr, &err), 0, "%s", err.msg);
  bs_ipc_friction_stats st;
  cr_assert_eq(bs_term_ipc_friction_stats(fr, &st, &err), 0);
  cr_assert_eq(st.pairs_pt, 1);
  cr_assert_eq(st.pairs_ee, 0);
  double g[24] = {0};
  term_gradient(bar, x, g);
  const double lambda = norm3(g + 12);
  cr_assert_gt(lambda, 0);
  cr_assert_float_eq(st.normal_force, lambda, 1e-12 * lambda, "lambda %.17g, barrier force %.17g", st.normal_force,
                     lambda);
  const double eps = st.eps;
  cr_assert_float_eq(eps, 2e-5, 1e-18);
  double y[24];
  memcpy(y, x, sizeof y);
  y[12] += 3 * eps;
  memset(g, 0, sizeof g);
  const double E = term_gradient(fr, y, g);
  cr_assert_float_eq(E, 0.5 * lambda * 3 * eps, 1e-12 * E);
  const double want = 0.5 * lambda; /* mu lambda along +x at the apex */
  cr_assert_float_eq(g[12], want, 1e-12 * want);
  cr_assert_float_eq(g[13], 0, 1e-12 * want);
  cr_assert_float_eq(g[14], 0, 1e-12 * want);
  /* the triangle's vertices take -(1 - b1 - b2), -b1, -b2 of it: b = (0.25, 0.25) */
  cr_assert_float_eq(g[0], -0.5 * want, 1e-12 * want);
  cr_assert_float_eq(g[3], -0.25 * want, 1e-12 * want);
  cr_assert_float_eq(g[6], -0.25 * want, 1e-12 * want);
  for (int k = 0; k < 3; k++) {
    double s = 0;
    for (int v = 0; v < 8; v++) s += g[3 * v + k];
    cr_assert_float_eq(s, 0, 1e-12 * want);
  }
  bs_term_destroy(&fr);
  bs_term_destroy(&bar);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&m);
}

/* E, grad E and H (pattern and extra blocks) with 1 and with 2 threads: the
 * same bits (two boxes of 6^3 cells: over 64 pairs, so the loops split). */
Test(barrier_friction, same_bits_on_1_and_2_threads) {
  double E[2], *g[2], *Hval[2], *extra[2];
  int64_t nnz = 0, nextra[2];
  for (int r = 0; r < 2; r++) {
    omp_set_num_threads(r + 1);
    fx s;
    fx_make(&s, 6, 0.01, 0.03, 1e-3, 5);
    bs_ipc_friction_stats st;
    bs_error err = {0};
    cr_assert_eq(bs_term_ipc_friction_stats(s.fr, &st, &err), 0);
    cr_assert_gt(st.pairs_pt + st.pairs_ee, 64, "pairs %lld", (long long)(st.pairs_pt + st.pairs_ee));
    move(&s, 1e-2, 5e-3, 6);
    g[r] = calloc((size_t)s.n3, sizeof(double));
    E[r] = term_gradient(s.fr, s.x, g[r]);
    bs_bsr *H = NULL;
    cr_assert_eq(bs_fem_matrix(s.fem, &H, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_bsr_reserve_extra(H, s.fr->hessian_extra, &err), 0, "%s", err.msg);
    term_hessian(s.fr, s.x, H);
    nnz = H->nnzb;
    Hval[r] = malloc(sizeof(double) * 9 * (size_t)nnz);
    memcpy(Hval[r], H->val, sizeof(double) * 9 * (size_t)nnz);
    nextra[r] = H->n_extra;
    extra[r] = malloc(sizeof(double) * 9 * (size_t)(H->n_extra + 1));
    memcpy(extra[r], H->extra_val, sizeof(double) * 9 * (size_t)H->n_extra);
    bs_bsr_destroy(&H);
    if (r == 1) {
      cr_assert_eq(memcmp(&E[0], &E[1], sizeof(double)), 0, "E %.17g vs %.17g", E[0], E[1]);
      cr_assert_eq(memcmp(g[0], g[1], sizeof(double) * (size_t)s.n3), 0);
    }
    fx_free(&s);
  }
  cr_assert_eq(memcmp(Hval[0], Hval[1], sizeof(double) * 9 * (size_t)nnz), 0);
  cr_assert_eq(nextra[0], nextra[1]);
  cr_assert_gt(nextra[0], 0);
  cr_assert_eq(memcmp(extra[0], extra[1], sizeof(double) * 9 * (size_t)nextra[0]), 0);
  for (int r = 0; r < 2; r++) free(g[r]), free(Hval[r]), free(extra[r]);
  omp_set_num_threads(2);
}

Test(barrier_friction, bad_input_is_refused_by_name) {
  fx s;
  fx_make(&s, 1, 0.02, 0.05, 0, 1);
  bs_term *t = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_friction_create(s.bar, 0, 1e-3, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "mu"), "%s", err.msg);
  cr_assert_eq(bs_term_ipc_friction_create(s.bar, NAN, 1e-3, &t, &err), BS_EINPUT);
  cr_assert_eq(bs_term_ipc_friction_create(s.bar, 0.3, 0, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "eps_v"), "%s", err.msg);
  cr_assert_eq(bs_term_ipc_friction_create(s.fr, 0.3, 1e-3, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "barrier"), "%s", err.msg);
  cr_assert_null(t);
  bs_ipc_friction_stats st;
  cr_assert_eq(bs_term_ipc_friction_stats(s.bar, &st, &err), BS_EINPUT);
  cr_assert(bs_term_is_ipc_friction(s.fr) && !bs_term_is_ipc_friction(s.bar));
  fx_free(&s);
}
