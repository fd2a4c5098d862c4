/* ipc_distance.c — squared distances between surface primitives with their
 * closed-form gradients and Hessians, their closest-feature classification,
 * and the edge-edge mollifier (bs_ipc.h).
 *
 * Every type is a function of at most three difference vectors of the
 * points, y_k = x[plus_k] - x[minus_k]: PP of r = p - q; PE of r = p - e0,
 * e = e1 - e0; the plane and line-line distances of r, a, b with the same
 * formula s^2 / q, s = r . (a x b), q = |a x b|^2 (PT: r = p - t0,
 * a = t1 - t0, b = t2 - t0; EE: r = eb0 - ea0, a = ea1 - ea0, b = eb1 - eb0).
 * Derivatives are taken in y (closed form below) and mapped back to the
 * points by the chain rule through the constant 0/+1/-1 matrix C of the map:
 * g = C^T g_y, H = C^T H_y C (map_back).
 *
 * PE, with alpha = r.e / e.e and n = r - alpha e (p minus its foot):
 *   d = n.n,  d_r = 2 n,  d_e = -2 alpha n,  and with u = r - 2 alpha e:
 *   d_rr = 2 (I - e e^T / e.e),  d_re = -2 alpha I - 2 e u^T / e.e,
 *   d_ee = 2 alpha^2 I - 2 u u^T / e.e.
 * s^2/q: s is trilinear, grad s = (a x b, b x r, r x a), and its Hessian's
 * blocks are cross-product matrices [v] (v x w = [v] w):
 *   s_ra = -[b], s_rb = [a], s_ab = -[r] (and transposes);
 * q = (a.a)(b.b) - (a.b)^2: q_a = 2 ((b.b) a - (a.b) b),
 *   q_b = 2 ((a.a) b - (a.b) a), q_aa = 2 ((b.b) I - b b^T),
 *   q_bb = 2 ((a.a) I - a a^T), q_ab = 4 a b^T - 2 (a.b) I - 2 b a^T;
 * d = s^2/q:  grad d = 2 s/q grad s - s^2/q^2 grad q,
 *   Hess d = 2/q grad s grad s^T + 2 s/q Hess s
 *            - 2 s/q^2 (grad s grad q^T + grad q grad s^T)
 *            - s^2/q^2 Hess q + 2 s^2/q^3 grad q grad q^T.
 */
#include <math.h>
#include <string.h>

#include "bs_ipc.h"

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void sub3(const double a[3], const double b[3], double o[3]) {
  o[0] = a[0] - b[0], o[1] = a[1] - b[1], o[2] = a[2] - b[2];
}
static void cross3(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}

/* The reduced variables of a type: y_k = x[plus[k]] - x[minus[k]] for
 * k < nk (x[minus] left out when minus[k] < 0), over nv points. */
typedef struct dmap {
  int nv, nk;
  int plus[3], minus[3];
} dmap;

static void gather(const dmap *m, const double *const x[], double *y) {
  for (int k = 0; k < m->nk; k++) {
    const double *xp = x[m->plus[k]];
    for (int c = 0; c < 3; c++) y[3 * k + c] = m->minus[k] >= 0 ? xp[c] - x[m->minus[k]][c] : xp[c];
  }
}

/* g = C^T gy, H = C^T Hy C over the nv points (either may be NULL); H is
 * made exactly symmetric (upper triangle mirrored). */
static void map_back(const dmap *m, const double *gy, const double *Hy, double *g, double *H) {
  int C[3][4] = {{0}};
  for (int k = 0; k < m->nk; k++) {
    C[k][m->plus[k]] += 1;
    if (m->minus[k] >= 0) C[k][m->minus[k]] -= 1;
  }
  const int n = 3 * m->nv, ny = 3 * m->nk;
  if (g && gy)
    for (int i = 0; i < n; i++) {
      double s = 0;
      for (int k = 0; k < m->nk; k++) s += C[k][i / 3] * gy[3 * k + i % 3];
      g[i] = s;
    }
  if (!H || !Hy) return;
  for (int i = 0; i < n; i++)
    for (int j = i; j < n; j++) {
      double s = 0;
      for (int k = 0; k < m->nk; k++)
        for (int l = 0; l < m->nk; l++)
          if (C[k][i / 3] && C[l][j / 3]) s += C[k][i / 3] * C[l][j / 3] * Hy[(3 * k + i % 3) * ny + 3 * l + j % 3];
      H[i * n + j] = H[j * n + i] = s;
    }
}

/* PP in r: d = r.r. */
static double pp_red(const double r[3], double gy[3], double Hy[9]) {
  if (gy)
    for (int c = 0; c < 3; c++) gy[c] = 2 * r[c];
  if (Hy)
    for (int i = 0; i < 9; i++) Hy[i] = i % 4 == 0 ? 2 : 0;
  return dot3(r, r);
}

/* PE in (r, e), e != 0 (header comment). */
static double pe_red(const double r[3], const double e[3], double gy[6], double Hy[36]) {
  const double ee = dot3(e, e), al = dot3(r, e) / ee;
  double n[3], u[3];
  for (int c = 0; c < 3; c++) n[c] = r[c] - al * e[c], u[c] = r[c] - 2 * al * e[c];
  if (gy)
    for (int c = 0; c < 3; c++) gy[c] = 2 * n[c], gy[3 + c] = -2 * al * n[c];
  if (Hy)
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        const double id = i == j;
        Hy[i * 6 + j] = 2 * (id - e[i] * e[j] / ee);
        Hy[i * 6 + 3 + j] = -2 * al * id - 2 * e[i] * u[j] / ee;
        Hy[(3 + j) * 6 + i] = Hy[i * 6 + 3 + j];
        Hy[(3 + i) * 6 + 3 + j] = 2 * al * al * id - 2 * u[i] * u[j] / ee;
      }
  return dot3(n, n);
}

/* q = |a x b|^2 = (a.a)(b.b) - (a.b)^2: its gradient dq[6] and Hessian
 * Hq[36] in (a, b) (either may be NULL). */
static void q_derivs(const double a[3], const double b[3], double dq[6], double Hq[36]) {
  const double aa = dot3(a, a), bb = dot3(b, b), ab = dot3(a, b);
  if (dq)
    for (int c = 0; c < 3; c++) dq[c] = 2 * (bb * a[c] - ab * b[c]), dq[3 + c] = 2 * (aa * b[c] - ab * a[c]);
  if (!Hq) return;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      const double id = i == j;
      Hq[i * 6 + j] = 2 * (bb * id - b[i] * b[j]);
      Hq[(3 + i) * 6 + 3 + j] = 2 * (aa * id - a[i] * a[j]);
      Hq[i * 6 + 3 + j] = 4 * a[i] * b[j] - 2 * ab * id - 2 * b[i] * a[j];
      Hq[(3 + j) * 6 + i] = Hq[i * 6 + 3 + j];
    }
}

/* Adds sign [v] (the cross-product matrix of v) to block (bi, bj) of the
 * 9 x 9 matrix H and its transpose to block (bj, bi). */
static void add_skew(double H[81], int bi, int bj, double sign, const double v[3]) {
  const double K[9] = {0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0};
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      H[(3 * bi + i) * 9 + 3 * bj + j] += sign * K[i * 3 + j];
      H[(3 * bj + j) * 9 + 3 * bi + i] += sign * K[i * 3 + j];
    }
}

/* s^2 / q in (r, a, b), a x b != 0 (header comment). */
static double plane_red(const double r[3], const double a[3], const double b[3], double gy[9], double Hy[81]) {
  double N[3];
  cross3(a, b, N);
  const double s = dot3(r, N), q = dot3(N, N), d = s * s / q;
  if (!gy && !Hy) return d;
  double ds[9], dq[9] = {0}, dqab[6], Hqab[36];
  memcpy(ds, N, sizeof N);
  cross3(b, r, ds + 3);
  cross3(r, a, ds + 6);
  q_derivs(a, b, dqab, Hy ? Hqab : NULL);
  memcpy(dq + 3, dqab, sizeof dqab);
  if (gy)
    for (int i = 0; i < 9; i++) gy[i] = 2 * s / q * ds[i] - s * s / (q * q) * dq[i];
  if (!Hy) return d;
  double Hs[81] = {0};
  add_skew(Hs, 0, 1, -1, b); /* s_ra = -[b] */
  add_skew(Hs, 0, 2, 1, a);  /* s_rb = [a]  */
  add_skew(Hs, 1, 2, -1, r); /* s_ab = -[r] */
  const double c1 = 2 / q, c2 = 2 * s / q, c3 = 2 * s / (q * q), c4 = s * s / (q * q), c5 = 2 * s * s / (q * q * q);
  for (int i = 0; i < 9; i++)
    for (int j = 0; j < 9; j++) {
      const double hq = i >= 3 && j >= 3 ? Hqab[(i - 3) * 6 + j - 3] : 0;
      Hy[i * 9 + j] = c1 * ds[i] * ds[j] + c2 * Hs[i * 9 + j] - c3 * (ds[i] * dq[j] + dq[i] * ds[j]) - c4 * hq +
                      c5 * dq[i] * dq[j];
    }
  return d;
}

enum { K_PP, K_PE, K_PLANE };

/* The kind's d^2 of the points x through map m, derivatives mapped back;
 * a degenerate PE (e = 0) falls back to PP of y0, a degenerate plane
 * (a x b = 0) to PE of (y0, y1) (bs_ipc.h). */
static double eval(int kind, dmap m, const double *const x[], double *g, double *H) {
  double y[9], gy[9], Hy[81], d, N[3];
  gather(&m, x, y);
  if (kind == K_PLANE) {
    cross3(y + 3, y + 6, N);
    if (dot3(N, N) == 0) kind = K_PE, m.nk = 2;
  }
  if (kind == K_PE && dot3(y + 3, y + 3) == 0) kind = K_PP, m.nk = 1;
  double *gp = g ? gy : NULL, *Hp = H ? Hy : NULL;
  if (kind == K_PP)
    d = pp_red(y, gp, Hp);
  else if (kind == K_PE)
    d = pe_red(y, y + 3, gp, Hp);
  else
    d = plane_red(y, y + 3, y + 6, gp, Hp);
  map_back(&m, gp, Hp, g, H);
  return d;
}

static dmap mk(int nv, int nk, int p0, int m0, int p1, int m1, int p2, int m2) {
  dmap m = {nv, nk, {p0, p1, p2}, {m0, m1, m2}};
  return m;
}

double bs_ipc_pp_d2(const double p[3], const double q[3], double g[6], double H[36]) {
  const double *x[2] = {p, q};
  return eval(K_PP, mk(2, 1, 0, 1, 0, 0, 0, 0), x, g, H);
}

double bs_ipc_pe_d2(const double p[3], const double e0[3], const double e1[3], double g[9], double H[81]) {
  const double *x[3] = {p, e0, e1};
  return eval(K_PE, mk(3, 2, 0, 1, 2, 1, 0, 0), x, g, H);
}

double bs_ipc_pt_plane_d2(const double p[3], const double t0[3], const double t1[3], const double t2[3],
                          double g[12], double H[144]) {
  const double *x[4] = {p, t0, t1, t2};
  return eval(K_PLANE, mk(4, 3, 0, 1, 2, 1, 3, 1), x, g, H);
}

double bs_ipc_ee_line_d2(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                         double g[12], double H[144]) {
  const double *x[4] = {ea0, ea1, eb0, eb1};
  return eval(K_PLANE, mk(4, 3, 2, 0, 1, 0, 3, 2), x, g, H);
}

/* Squared distance from p to the segment (e0, e1) and its clamped parameter
 * (0 for e0 == e1). */
static double seg_d2(const double p[3], const double e0[3], const double e1[3], double *alpha) {
  double r[3], e[3], n[3];
  sub3(p, e0, r);
  sub3(e1, e0, e);
  const double ee = dot3(e, e);
  double al = ee > 0 ? dot3(r, e) / ee : 0;
  al = al < 0 ? 0 : al > 1 ? 1 : al;
  for (int c = 0; c < 3; c++) n[c] = r[c] - al * e[c];
  *alpha = al;
  return dot3(n, n);
}

bs_ipc_pt_type bs_ipc_pt_classify(const double p[3], const double t0[3], const double t1[3], const double t2[3]) {
  double a[3], b[3], r[3], N[3], w[3];
  sub3(t1, t0, a);
  sub3(t2, t0, b);
  sub3(p, t0, r);
  cross3(a, b, N);
  const double q = dot3(N, N);
  if (q > 1e-20 * dot3(a, a) * dot3(b, b)) {
    cross3(r, b, w);
    const double u = dot3(w, N); /* barycentric coordinates of the foot, times q */
    cross3(a, r, w);
    const double v = dot3(w, N);
    if (u >= 0 && v >= 0 && u + v <= q) return BS_IPC_P_T;
  }
  const double *T[3] = {t0, t1, t2};
  double best = INFINITY;
  bs_ipc_pt_type type = BS_IPC_P_T0;
  for (int k = 0; k < 3; k++) {
    double al, d = seg_d2(p, T[k], T[(k + 1) % 3], &al);
    if (d < best) {
      best = d;
      type = al <= 0 ? (bs_ipc_pt_type)(BS_IPC_P_T0 + k)
             : al >= 1 ? (bs_ipc_pt_type)(BS_IPC_P_T0 + (k + 1) % 3)
                       : (bs_ipc_pt_type)(BS_IPC_P_E0 + k);
    }
  }
  return type;
}

/* The nearest endpoint-segment pair of two segments (the boundary of their
 * parameter square): table of types per pair and clamped end. */
static bs_ipc_ee_type ee_boundary_type(const double ea0[3], const double ea1[3], const double eb0[3],
                                       const double eb1[3]) {
  static const bs_ipc_ee_type tab[4][3] = {
      {BS_IPC_EA0_EB0, BS_IPC_EA0_EB1, BS_IPC_EA0_EB}, /* ea0 against b */
      {BS_IPC_EA1_EB0, BS_IPC_EA1_EB1, BS_IPC_EA1_EB}, /* ea1 against b */
      {BS_IPC_EA0_EB0, BS_IPC_EA1_EB0, BS_IPC_EA_EB0}, /* eb0 against a */
      {BS_IPC_EA0_EB1, BS_IPC_EA1_EB1, BS_IPC_EA_EB1}, /* eb1 against a */
  };
  const double *pt[4] = {ea0, ea1, eb0, eb1};
  const double *s0[4] = {eb0, eb0, ea0, ea0}, *s1[4] = {eb1, eb1, ea1, ea1};
  double best = INFINITY;
  bs_ipc_ee_type type = BS_IPC_EA0_EB0;
  for (int k = 0; k < 4; k++) {
    double al, d = seg_d2(pt[k], s0[k], s1[k], &al);
    if (d < best) best = d, type = tab[k][al <= 0 ? 0 : al >= 1 ? 1 : 2];
  }
  return type;
}

bs_ipc_ee_type bs_ipc_ee_classify(const double ea0[3], const double ea1[3], const double eb0[3],
                                  const double eb1[3]) {
  double a[3], b[3], r[3], N[3], w[3];
  sub3(ea1, ea0, a);
  sub3(eb1, eb0, b);
  sub3(eb0, ea0, r);
  cross3(a, b, N);
  const double q = dot3(N, N);
  if (q > BS_IPC_PARALLEL_SIN2 * dot3(a, a) * dot3(b, b)) {
    cross3(r, b, w);
    const double sa = dot3(w, N); /* the lines' closest parameters, times q */
    cross3(r, a, w);
    const double sb = dot3(w, N);
    if (sa >= 0 && sa <= q && sb >= 0 && sb <= q) return BS_IPC_EA_EB;
  }
  return ee_boundary_type(ea0, ea1, eb0, eb1);
}

double bs_ipc_pt_d2_typed(bs_ipc_pt_type type, const double p[3], const double t0[3], const double t1[3],
                          const double t2[3], double g[12], double H[144]) {
  const double *x[4] = {p, t0, t1, t2};
  if (type <= BS_IPC_P_T2) return eval(K_PP, mk(4, 1, 0, 1 + (int)type, 0, 0, 0, 0), x, g, H);
  if (type <= BS_IPC_P_E2) {
    const int k = (int)type - BS_IPC_P_E0, i0 = 1 + k, i1 = 1 + (k + 1) % 3;
    return eval(K_PE, mk(4, 2, 0, i0, i1, i0, 0, 0), x, g, H);
  }
  return eval(K_PLANE, mk(4, 3, 0, 1, 2, 1, 3, 1), x, g, H);
}

double bs_ipc_ee_d2_typed(bs_ipc_ee_type type, const double ea0[3], const double ea1[3], const double eb0[3],
                          const double eb1[3], double g[12], double H[144]) {
  const double *x[4] = {ea0, ea1, eb0, eb1};
  switch (type) {
    case BS_IPC_EA0_EB0: return eval(K_PP, mk(4, 1, 0, 2, 0, 0, 0, 0), x, g, H);
    case BS_IPC_EA0_EB1: return eval(K_PP, mk(4, 1, 0, 3, 0, 0, 0, 0), x, g, H);
    case BS_IPC_EA1_EB0: return eval(K_PP, mk(4, 1, 1, 2, 0, 0, 0, 0), x, g, H);
    case BS_IPC_EA1_EB1: return eval(K_PP, mk(4, 1, 1, 3, 0, 0, 0, 0), x, g, H);
    case BS_IPC_EA0_EB: return eval(K_PE, mk(4, 2, 0, 2, 3, 2, 0, 0), x, g, H);
    case BS_IPC_EA1_EB: return eval(K_PE, mk(4, 2, 1, 2, 3, 2, 0, 0), x, g, H);
    case BS_IPC_EA_EB0: return eval(K_PE, mk(4, 2, 2, 0, 1, 0, 0, 0), x, g, H);
    case BS_IPC_EA_EB1: return eval(K_PE, mk(4, 2, 3, 0, 1, 0, 0, 0), x, g, H);
    default: return eval(K_PLANE, mk(4, 3, 2, 0, 1, 0, 3, 2), x, g, H);
  }
}

double bs_ipc_pt_d2_full(const double p[3], const double t0[3], const double t1[3], const double t2[3],
                         bs_ipc_pt_type *type, double g[12], double H[144]) {
  const bs_ipc_pt_type ty = bs_ipc_pt_classify(p, t0, t1, t2);
  if (type) *type = ty;
  return bs_ipc_pt_d2_typed(ty, p, t0, t1, t2, g, H);
}

double bs_ipc_ee_d2_full(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                         bs_ipc_ee_type *type, double g[12], double H[144]) {
  const bs_ipc_ee_type ty = bs_ipc_ee_classify(ea0, ea1, eb0, eb1);
  if (type) *type = ty;
  return bs_ipc_ee_d2_typed(ty, ea0, ea1, eb0, eb1, g, H);
}

double bs_ipc_mollifier_eps(const double ea0_rest[3], const double ea1_rest[3], const double eb0_rest[3],
                            const double eb1_rest[3]) {
  double a[3], b[3];
  sub3(ea1_rest, ea0_rest, a);
  sub3(eb1_rest, eb0_rest, b);
  return 1e-3 * dot3(a, a) * dot3(b, b);
}

double bs_ipc_mollifier(const double ea0[3], const double ea1[3], const double eb0[3], const double eb1[3],
                        double eps_x, double g[12], double H[144]) {
  const double *x[4] = {ea0, ea1, eb0, eb1};
  const dmap m = mk(4, 2, 1, 0, 3, 2, 0, 0); /* a = ea1 - ea0, b = eb1 - eb0 */
  double y[6], N[3], dq[6], Hq[36], gy[6], Hy[36];
  gather(&m, x, y);
  cross3(y, y + 3, N);
  const double c = dot3(N, N);
  if (!(eps_x > 0) || c >= eps_x) {
    if (g) memset(g, 0, 12 * sizeof(double));
    if (H) memset(H, 0, 144 * sizeof(double));
    return 1;
  }
  const double xi = c / eps_x, m0 = (2 - xi) * xi, m1 = (2 - 2 * xi) / eps_x, m2 = -2 / (eps_x * eps_x);
  q_derivs(y, y + 3, dq, H ? Hq : NULL);
  for (int i = 0; i < 6; i++) gy[i] = m1 * dq[i];
  if (H)
    for (int i = 0; i < 6; i++)
      for (int j = 0; j < 6; j++) Hy[i * 6 + j] = m2 * dq[i] * dq[j] + m1 * Hq[i * 6 + j];
  map_back(&m, gy, Hy, g, H);
  return m0;
}
