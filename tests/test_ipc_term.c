/* test_ipc_term.c — the barrier self-contact term (bs_ipc_term.h): gradient
 * and Hessian against finite differences on two tets close together (a
 * point-triangle and an edge-edge contact), the same bits on 1 and 2
 * threads (two boxes a fraction of dhat apart), the CCD step bound, a status
 * at an intersecting state, and bad input. */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fem.h"
#include "bs_ipc_term.h"
#include "bs_mesh.h"
#include "bs_terms.h"
#include "test_term_eval.h"

typedef struct two {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_term *t;
  double *x; /* 3n */
  int n3;
} two;

static void fem_for(two *s) {
  bs_error err = {0};
  bs_material mat;
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, &mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(s->mesh, 1, &mat, NULL, &s->fem, &err), 0, "%s", err.msg);
  s->n3 = 3 * s->mesh->n_vertices;
  s->x = malloc(sizeof(double) * (size_t)s->n3);
  memcpy(s->x, s->mesh->x, sizeof(double) * (size_t)s->n3);
}

/* Tet A with its top face z = 0 ((0,0,0), (1,0,0), (0,1,0)) and tet B above
 * it: ee = 0: B's apex at height gap over A's face interior; ee = 1: B's
 * lower edge (0.2,0.2)-(0.8,0.8) at height gap across A's edge (1,0,0)-(0,1,0).
 * Every vertex then jittered by up to 1e-3 (no symmetric ties). */
static void two_tets(two *s, int ee, double gap, double dhat) {
  memset(s, 0, sizeof *s);
  double x[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.3, -1};
  const double pt_b[12] = {0.25, 0.25, gap, -0.5, -0.5, 1, 1.5, -0.2, 1, -0.2, 1.5, 1};
  const double ee_b[12] = {0.2, 0.2, gap, 0.8, 0.8, gap, 0.5, 0.2, 1, 0.2, 0.5, 1};
  memcpy(x + 12, ee ? ee_b : pt_b, sizeof pt_b);
  for (int i = 0; i < 24; i++) x[i] += 1e-3 * sin(7.3 * i + 1.1);
  const int32_t tets[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create(8, x, 2, tets, 0, NULL, &s->mesh, &err), 0, "%s", err.msg);
  fem_for(s);
  cr_assert_eq(bs_term_ipc_create(s->fem, NULL, dhat, 1.0, &s->t, &err), 0, "%s", err.msg);
}

/* Two boxes of c^3 cells, [0,1]^3 and the same lifted by 1 + gap and
 * shifted sideways, as one mesh. */
static void two_boxes(two *s, int c, double gap, double dhat) {
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
  free(x);
  free(tets);
  bs_mesh_destroy(&A);
  bs_mesh_destroy(&B);
  fem_for(s);
  cr_assert_eq(bs_term_ipc_create(s->fem, NULL, dhat, 1.0, &s->t, &err), 0, "%s", err.msg);
}

static void two_free(two *s) {
  bs_term_destroy(&s->t);
  bs_fem_destroy(&s->fem);
  bs_mesh_destroy(&s->mesh);
  free(s->x);
}

static double max_abs(int n, const double *a) {
  double m = 0;
  for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
  return m;
}

/* grad E against central differences of E, and H v (exact Hessian) against
 * central differences of grad E along a few directions v. */
static void check_fd(two *s) {
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_set_project(s->t, 0, &err), 0);
  const int n = s->n3;
  double *g = calloc((size_t)n, sizeof(double)), *gp = calloc((size_t)n, sizeof(double)),
         *gm = calloc((size_t)n, sizeof(double)), *y = malloc(sizeof(double) * (size_t)n),
         *v = malloc(sizeof(double) * (size_t)n), *Hv = malloc(sizeof(double) * (size_t)n);
  const double E = term_gradient(s->t, s->x, g);
  cr_assert_gt(E, 0, "no contact: E = %g", E);
  const double h = 1e-7, gmax = max_abs(n, g);
  for (int i = 0; i < n; i++) {
    memcpy(y, s->x, sizeof(double) * (size_t)n);
    y[i] = s->x[i] + h;
    const double Ep = term_value(s->t, y);
    y[i] = s->x[i] - h;
    const double Em = term_value(s->t, y);
    const double fd = (Ep - Em) / (2 * h);
    cr_assert_leq(fabs(fd - g[i]), 1e-6 * gmax, "dof %d: gradient %.10g, differences %.10g", i, g[i], fd);
  }
  bs_bsr *H = NULL;
  cr_assert_eq(bs_fem_matrix(s->fem, &H, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_reserve_extra(H, s->t->hessian_extra, &err), 0, "%s", err.msg);
  term_hessian(s->t, s->x, H);
  bs_bsr_index_extra(H);
  for (int k = 0; k < 4; k++) {
    for (int i = 0; i < n; i++) v[i] = cos(1.7 * i * (k + 1) + k);
    bs_bsr_mul(H, NULL, v, Hv);
    for (int i = 0; i < n; i++) y[i] = s->x[i] + h * v[i];
    memset(gp, 0, sizeof(double) * (size_t)n);
    term_gradient(s->t, y, gp);
    for (int i = 0; i < n; i++) y[i] = s->x[i] - h * v[i];
    memset(gm, 0, sizeof(double) * (size_t)n);
    term_gradient(s->t, y, gm);
    const double hmax = max_abs(n, Hv);
    cr_assert_gt(hmax, 0);
    for (int i = 0; i < n; i++) {
      const double fd = (gp[i] - gm[i]) / (2 * h);
      cr_assert_leq(fabs(fd - Hv[i]), 1e-5 * hmax, "direction %d dof %d: H v %.10g, differences %.10g", k, i, Hv[i],
                    fd);
    }
  }
  bs_bsr_destroy(&H);
  free(g), free(gp), free(gm), free(y), free(v), free(Hv);
}

Test(ipc_term, point_triangle_derivatives_match_differences) {
  two s;
  two_tets(&s, 0, 0.03, 0.1);
  bs_ipc_stats st;
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_detect(s.t, s.x, &st, &err), 0, "%s", err.msg);
  cr_assert_geq(st.pairs_pt, 1);
  cr_assert_eq(st.intersecting, 0);
  cr_assert_float_eq(st.min_distance, 0.03, 3e-3, "min distance %g", st.min_distance);
  check_fd(&s);
  two_free(&s);
}

Test(ipc_term, edge_edge_derivatives_match_differences) {
  two s;
  two_tets(&s, 1, 0.03, 0.1);
  bs_ipc_stats st;
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_detect(s.t, s.x, &st, &err), 0, "%s", err.msg);
  cr_assert_geq(st.pairs_ee, 1, "no edge-edge pair");
  check_fd(&s);
  two_free(&s);
}

/* The projected Hessian is what the term assembles by default: symmetric,
 * and v.H v >= 0 along any v. */
Test(ipc_term, projected_hessian_is_psd) {
  two s;
  two_tets(&s, 1, 0.02, 0.1);
  bs_error err = {0};
  bs_bsr *H = NULL;
  cr_assert_eq(bs_fem_matrix(s.fem, &H, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_bsr_reserve_extra(H, s.t->hessian_extra, &err), 0, "%s", err.msg);
  term_hessian(s.t, s.x, H);
  bs_bsr_index_extra(H);
  double v[24], Hv[24];
  for (int k = 0; k < 50; k++) {
    for (int i = 0; i < 24; i++) v[i] = sin(3.1 * i * (k + 1) + 0.7 * k);
    bs_bsr_mul(H, NULL, v, Hv);
    double q = 0, vv = 0;
    for (int i = 0; i < 24; i++) q += v[i] * Hv[i], vv += v[i] * v[i];
    cr_assert_geq(q, -1e-10 * vv * max_abs(24, Hv), "v.H v = %g", q);
  }
  bs_bsr_destroy(&H);
  two_free(&s);
}

/* E, grad E and H with 1 and with 2 threads: the same bits. */
Test(ipc_term, same_bits_on_1_and_2_threads) {
  double E[2];
  double *g[2];
  double *Hval[2];
  int64_t nnz = 0, nextra[2];
  double *extra[2];
  int64_t pairs = 0;
  for (int r = 0; r < 2; r++) {
    omp_set_num_threads(r + 1);
    two s;
    two_boxes(&s, 6, 0.02, 0.05);
    bs_error err = {0};
    bs_ipc_stats st;
    cr_assert_eq(bs_term_ipc_detect(s.t, s.x, &st, &err), 0, "%s", err.msg);
    cr_assert_gt(st.pairs_pt + st.pairs_ee, 64, "pairs %lld", (long long)(st.pairs_pt + st.pairs_ee));
    cr_assert_eq(st.intersecting, 0);
    if (r == 0) pairs = st.pairs_pt + st.pairs_ee;
    else cr_assert_eq(st.pairs_pt + st.pairs_ee, pairs);
    g[r] = calloc((size_t)s.n3, sizeof(double));
    E[r] = term_gradient(s.t, s.x, g[r]);
    bs_bsr *H = NULL;
    cr_assert_eq(bs_fem_matrix(s.fem, &H, &err), 0, "%s", err.msg);
    cr_assert_eq(bs_bsr_reserve_extra(H, s.t->hessian_extra, &err), 0, "%s", err.msg);
    term_hessian(s.t, s.x, H);
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
    two_free(&s);
  }
  cr_assert_eq(memcmp(Hval[0], Hval[1], sizeof(double) * 9 * (size_t)nnz), 0);
  cr_assert_eq(nextra[0], nextra[1]);
  cr_assert_eq(memcmp(extra[0], extra[1], sizeof(double) * 9 * (size_t)nextra[0]), 0);
  for (int r = 0; r < 2; r++) free(g[r]), free(Hval[r]), free(extra[r]);
  omp_set_num_threads(2);
}

/* The CCD bound: a motion of B's apex 2 gaps down is cut before contact
 * (at most half of it), and the state there is evaluable with a positive
 * distance; a motion away is free (1); a motion through the whole of A
 * (tunnelling) is cut too. */
Test(ipc_term, max_step_stops_before_contact) {
  two s;
  two_tets(&s, 0, 0.03, 0.01);
  bs_error err = {0};
  double d[24] = {0}, a = -1, y[24];
  const int apex = 4; /* B's apex: the 5th vertex (the mesh keeps the order) */
  cr_assert_lt(fabs(s.x[3 * apex + 2] - 0.03), 2e-3);
  const double gap = s.x[3 * apex + 2];
  for (int r = 0; r < 3; r++) {
    const double dz[3] = {-2 * gap, 0.5, -3.0};
    memset(d, 0, sizeof d);
    d[3 * apex + 2] = dz[r];
    cr_assert_eq(bs_term_ipc_max_step(s.t, s.x, d, &a, &err), 0, "%s", err.msg);
    if (r == 1) {
      cr_assert_eq(a, 1.0);
      continue;
    }
    cr_assert_lt(a, r == 0 ? 0.5 : 0.011, "motion %d: alpha %g", r, a);
    cr_assert_gt(a, r == 0 ? 0.3 : 0.004, "motion %d: alpha %g (too conservative)", r, a);
    for (int i = 0; i < 24; i++) y[i] = s.x[i] + a * d[i];
    bs_ipc_stats st;
    cr_assert_eq(bs_term_ipc_detect(s.t, y, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.intersecting, 0);
    cr_assert_gt(st.min_distance, 0);
  }
  bs_ipc_stats st;
  cr_assert_eq(bs_term_ipc_stats(s.t, &st, &err), 0);
  cr_assert_eq(st.ccd_calls, 3);
  cr_assert_eq(st.ccd_limited, 2);
  two_free(&s);
}

/* The pairs of t at y into a fresh copy (pairs and count). */
static bs_ipc_pair *pairs_at(bs_term *t, const double *y, int64_t *n) {
  const bs_ipc_pair *p = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_pairs(t, y, &p, n, &err), 0, "%s", err.msg);
  bs_ipc_pair *c = malloc(sizeof *c * (size_t)(*n + 1));
  if (*n) memcpy(c, p, sizeof *c * (size_t)*n); /* p may be NULL when there are none */
  return c;
}

/* Detection along a motion after max_step runs on max_step's candidates
 * (no tree query: detections_swept counts it) and finds what a term that
 * never saw the motion finds by its trees: the same pairs in the same
 * order, the same smallest distance; a point off the motion is detected by
 * the trees again, with the same answer too. Box B sinks from 3 cm above box
 * A to 8 mm (dhat 2 cm: only the candidates of the swept boxes grown by dhat
 * hold the pairs at the end), and slides and twists a little, so that the
 * pairs change along the motion. */
Test(ipc_term, detection_on_max_step_candidates_is_the_trees_detection) {
  two s, fresh;
  two_boxes(&s, 5, 0.03, 0.02);
  two_boxes(&fresh, 5, 0.03, 0.02);
  bs_error err = {0};
  const int32_t nA = s.mesh->n_vertices / 2;
  double *d = calloc((size_t)s.n3, sizeof(double)), *y = malloc(sizeof(double) * (size_t)s.n3);
  for (int32_t v = nA; v < s.mesh->n_vertices; v++) {
    const double *p = s.x + 3 * (size_t)v;
    d[3 * v] = 0.01 + 0.01 * (p[1] - 0.5);
    d[3 * v + 1] = -0.01 * (p[0] - 0.5);
    d[3 * v + 2] = -0.022;
  }
  double alpha = -1;
  cr_assert_eq(bs_term_ipc_max_step(s.t, s.x, d, &alpha, &err), 0, "%s", err.msg);
  cr_assert_eq(alpha, 1.0, "alpha %g: the motion ends 8 mm apart", alpha);
  const double as[6] = {0, 0.25, 0.5, 0.75, 1, 0.5};
  int64_t max_pairs = 0;
  for (int k = 0; k < 6; k++) {
    for (int i = 0; i < s.n3; i++) y[i] = s.x[i] + as[k] * d[i];
    if (k == 5) y[3 * nA] -= 1e-2; /* off the motion (B's vertices move along +x, by 0.55 cm at most) */
    bs_ipc_stats a, b, a1;
    cr_assert_eq(bs_term_ipc_stats(s.t, &a, &err), 0);
    cr_assert_eq(bs_term_ipc_detect(s.t, y, &a1, &err), 0, "%s", err.msg);
    cr_assert_eq(a1.detections_swept - a.detections_swept, k < 5 ? 1 : 0, "point %d", k);
    cr_assert_eq(bs_term_ipc_detect(fresh.t, y, &b, &err), 0, "%s", err.msg);
    cr_assert_eq(b.detections_swept, 0);
    int64_t na, nb;
    bs_ipc_pair *pa = pairs_at(s.t, y, &na), *pb = pairs_at(fresh.t, y, &nb);
    cr_assert_eq(na, nb, "point %d: %lld pairs, the trees find %lld", k, (long long)na, (long long)nb);
    cr_assert_eq(memcmp(pa, pb, sizeof *pa * (size_t)na), 0, "point %d: other pairs or order", k);
    cr_assert_eq(memcmp(&a1.min_distance, &b.min_distance, sizeof(double)), 0, "point %d: %.17g vs %.17g", k,
                 a1.min_distance, b.min_distance);
    cr_assert_eq(a1.intersecting, b.intersecting);
    if (na > max_pairs) max_pairs = na;
    free(pa), free(pb);
  }
  cr_assert_gt(max_pairs, 20, "pairs %lld: the motion should bring the boxes within dhat", (long long)max_pairs);
  free(d), free(y);
  two_free(&s);
  two_free(&fresh);
}

/* B's apex pushed into A: no distance is 0, but B's edges cross A's top
 * face: value, gradient and hessian say "not evaluable" (no NaN). */
Test(ipc_term, intersecting_state_is_not_evaluable) {
  two s;
  two_tets(&s, 0, 0.03, 0.1);
  s.x[3 * 4 + 2] = -0.2;
  double E = 1234, *g = calloc((size_t)s.n3, sizeof(double));
  cr_assert_eq(s.t->ops->value(s.t, s.x, &E), BS_TERM_NOT_EVALUABLE);
  cr_assert_eq(s.t->ops->gradient(s.t, s.x, &E, g), BS_TERM_NOT_EVALUABLE);
  bs_ipc_stats st;
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_detect(s.t, s.x, &st, &err), 0, "%s", err.msg);
  cr_assert_gt(st.intersecting, 0);
  double k = 0;
  cr_assert_eq(bs_term_ipc_kappa_init(s.t, s.x, g, 1, 10, &k, &err), BS_ENUMERIC);
  cr_assert(strstr(err.msg, "crossing"), "%s", err.msg);
  free(g);
  two_free(&s);
}

/* A box of 3^3 cells rotated by 30 degrees about z and 20 about x: no
 * surface primitive touches or crosses another (flat faces whose rounded
 * orientations are noise were seen to cross: 26 pairs with 30 degrees about
 * z alone), and a pierced face is still seen. */
Test(ipc_term, rotated_box_has_no_crossing_and_a_piercing_is_seen) {
  two s;
  memset(&s, 0, sizeof s);
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.3, 0.3};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 3, 3, 3, &s.mesh, &err), 0, "%s", err.msg);
  const double pi = 3.14159265358979323846, cz = cos(pi / 6), sz = sin(pi / 6), cx = cos(pi / 9), sx = sin(pi / 9);
  for (int32_t i = 0; i < s.mesh->n_vertices; i++) {
    double *p = s.mesh->x + 3 * (size_t)i, a = cz * p[0] - sz * p[1], b = sz * p[0] + cz * p[1];
    p[0] = a, p[1] = cx * b - sx * p[2], p[2] = sx * b + cx * p[2];
  }
  fem_for(&s);
  cr_assert_eq(bs_term_ipc_create(s.fem, NULL, 0.1, 1.0, &s.t, &err), 0, "%s", err.msg);
  bs_ipc_stats st;
  cr_assert_eq(bs_term_ipc_detect(s.t, s.x, &st, &err), 0, "%s", err.msg);
  cr_expect_eq(st.intersecting, 0);
  cr_expect_gt(st.pairs_pt + st.pairs_ee, 0, "neighbours within dhat on the faces");
  /* vertex 0 (a corner) pushed through the box past the opposite corner:
   * its edges now cross the far faces */
  const double *far = s.x + 3 * (size_t)(s.mesh->n_vertices - 1);
  for (int k = 0; k < 3; k++) s.x[k] = far[k] + 0.3 * (far[k] - s.x[k]);
  cr_assert_eq(bs_term_ipc_detect(s.t, s.x, &st, &err), 0, "%s", err.msg);
  cr_expect_gt(st.intersecting, 0);
  two_free(&s);
}

Test(ipc_term, bad_input_is_refused_by_name) {
  two s;
  two_tets(&s, 0, 0.03, 0.1);
  bs_term *t = NULL;
  bs_error err = {0};
  const double bad[3] = {0, -1e-3, NAN};
  for (int i = 0; i < 3; i++) {
    cr_assert_eq(bs_term_ipc_create(s.fem, NULL, bad[i], 1, &t, &err), BS_EINPUT);
    cr_assert(strstr(err.msg, "dhat"), "%s", err.msg);
    cr_assert_null(t);
  }
  cr_assert_eq(bs_term_ipc_create(s.fem, NULL, 0.1, -1, &t, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "kappa"), "%s", err.msg);
  cr_assert_eq(bs_term_ipc_set_kappa(s.t, INFINITY, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "kappa"), "%s", err.msg);
  bs_ipc_stats st;
  cr_assert_eq(bs_term_ipc_stats(NULL, &st, &err), BS_EINPUT);
  two_free(&s);
}

/* IPC's initial kappa: with a contact at the start, the one that balances
 * the barrier's gradient against a given other gradient (here: pushing B's
 * apex down with a unit force), inside [kappa_min, kappa_max]. */
Test(ipc_term, kappa_init_balances_the_gradients) {
  two s;
  two_tets(&s, 0, 0.03, 0.1);
  double *ge = calloc((size_t)s.n3, sizeof(double)), k = 0;
  ge[3 * 4 + 2] = 1.0; /* dE/dz of the apex: gravity-like */
  bs_error err = {0};
  cr_assert_eq(bs_term_ipc_kappa_init(s.t, s.x, ge, 1e-6, 1e6, &k, &err), 0, "%s", err.msg);
  cr_assert_gt(k, 1e-6);
  cr_assert_lt(k, 1e6);
  /* with that kappa the apex's z-force balances: E_z + kappa b_z ~ 0 along the barrier's gradient */
  double *g = calloc((size_t)s.n3, sizeof(double));
  term_gradient(s.t, s.x, g);
  double gb2 = 0, dot = 0;
  for (int i = 0; i < s.n3; i++) gb2 += g[i] * g[i], dot += (g[i] + ge[i]) * g[i];
  cr_assert_lt(fabs(dot), 1e-9 * gb2 + 1e-12, "residual along the barrier gradient %g", dot);
  free(ge), free(g);
  two_free(&s);
}
