/* selfcollide.c — penalty self-collisions and self-contact friction (paper
 * section 5.3; the formulas and the contract are in bs_selfcollide.h).
 *
 * Derivatives of the squared distance d in each region, written in local
 * variables z that are differences of the inputs y = (p, a, b, c):
 *   vertex: z = u = p - a.                   d_u = 2u, d_uu = 2I.
 *   edge:   z = (u, e), e = b - a, s = u.e, q = e.e, d = u.u - s^2/q:
 *     d_u  = 2u - 2 s e/q,            d_e = -2 s u/q + 2 s^2 e/q^2,
 *     d_uu = 2I - 2 e e^T/q,
 *     d_ue = -2 (e u^T + s I)/q + 4 s e e^T/q^2,
 *     d_ee = -2 u u^T/q + 4 s (u e^T + e u^T)/q^2 + 2 s^2 I/q^2 - 8 s^2 e e^T/q^3.
 *   face:   z = (u, e1, e2), e1 = b - a, e2 = c - a, n = e1 x e2, r = u.n,
 *     N = n.n, d = f(u, n) = r^2/N with
 *     f_u = 2 r n/N,   f_n = 2 r u/N - 2 r^2 n/N^2,
 *     f_uu = 2 n n^T/N,
 *     f_un = 2 (n u^T + r I)/N - 4 r n n^T/N^2,
 *     f_nn = 2 u u^T/N - 4 r (u n^T + n u^T)/N^2 - 2 r^2 I/N^2 + 8 r^2 n n^T/N^3;
 *     dn/de1 = -[e2]x, dn/de2 = [e1]x, and d^2 n_k/de1_i de2_j = eps_kij,
 *     so the (e1, e2) block gains sum_k f_n,k eps_kij = -[f_n]x.
 * Then y-derivatives by the linear map z = A y: g_y = A^T g_z,
 * H_y = A^T H_z A.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "bs_selfcollide.h"
#include "bs_bvh.h"
#include "bs_svd.h"
#include "bs_shim.h"
#include "bs_vec3.h"

/* PAR_MIN: surface vertices below which detection runs on one thread (a
 * parallel region costs more). */
enum { PAR_MIN = 2048 };
/* Contacts whose Hessians are computed (and PSD-projected) in one parallel
 * pass before they are added, in order, into H; HESS_PAR_MIN: fewer run
 * serially (a projection costs tens of microseconds). */
enum { HESS_BATCH = 256, HESS_PAR_MIN = 8 };

/* ---- small vector helpers -------------------------------------------- */
/* [a]x, the matrix of b -> a x b. */
static void skew(const double *a, double *M) {
  M[0] = 0, M[1] = -a[2], M[2] = a[1];
  M[3] = a[2], M[4] = 0, M[5] = -a[0];
  M[6] = -a[1], M[7] = a[0], M[8] = 0;
}
static void mul33(const double *A, const double *B, double *C) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}
/* C = A^T B */
static void mul33tn(const double *A, const double *B, double *C) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) C[3 * i + j] = A[i] * B[j] + A[3 + i] * B[3 + j] + A[6 + i] * B[6 + j];
}

/* ---- closest point on a triangle (Ericson, Real-Time Collision Detection 5.1.5) */
static double seg_closest(const double *p, const double *a, const double *b, double *t) {
  double e[3], u[3];
  bs_sub3(b, a, e);
  bs_sub3(p, a, u);
  double q = bs_dot3(e, e), s = q > 0 ? bs_dot3(u, e) / q : 0;
  if (s < 0) s = 0;
  if (s > 1) s = 1;
  *t = s;
  double r[3] = {u[0] - s * e[0], u[1] - s * e[1], u[2] - s * e[2]};
  return bs_dot3(r, r);
}

static void set_feature(const double w[3], int *feature, int *nv, int loc[3], double wf[3]) {
  int n = 0;
  for (int i = 0; i < 3; i++)
    if (w[i] != 0) loc[n] = i, wf[n] = w[i], n++;
  if (n == 0) loc[0] = 0, wf[0] = 1, n = 1; /* cannot happen: weights sum to 1 */
  *nv = n;
  *feature = n == 3 ? BS_SELF_FACE : n == 2 ? BS_SELF_EDGE : BS_SELF_VERTEX;
}

double bs_self_closest_triangle(const double p[3], const double a[3], const double b[3], const double c[3],
                                double w[3], int *feature, int *nv, int loc[3], double wf[3]) {
  double ab[3], ac[3], ap[3], bp[3], cp[3], n[3];
  bs_sub3(b, a, ab);
  bs_sub3(c, a, ac);
  bs_cross3(ab, ac, n);
  double nn = bs_dot3(n, n), scale = bs_dot3(ab, ab) * bs_dot3(ac, ac);
  w[0] = w[1] = w[2] = 0;
  if (!(nn > 1e-24 * scale) || !(scale > 0)) {
    /* degenerate: the closest of the three edges */
    const double *P[3] = {a, b, c};
    double best = INFINITY;
    for (int e = 0; e < 3; e++) {
      double t, dd = seg_closest(p, P[e], P[(e + 1) % 3], &t);
      if (dd < best) {
        best = dd;
        w[0] = w[1] = w[2] = 0;
        w[e] = 1 - t;
        w[(e + 1) % 3] += t;
      }
    }
    set_feature(w, feature, nv, loc, wf);
    return best;
  }
  bs_sub3(p, a, ap);
  double d1 = bs_dot3(ab, ap), d2 = bs_dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    w[0] = 1;
    goto done;
  }
  bs_sub3(p, b, bp);
  double d3 = bs_dot3(ab, bp), d4 = bs_dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    w[1] = 1;
    goto done;
  }
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    double v = d1 / (d1 - d3);
    w[0] = 1 - v, w[1] = v;
    goto done;
  }
  bs_sub3(p, c, cp);
  double d5 = bs_dot3(ab, cp), d6 = bs_dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    w[2] = 1;
    goto done;
  }
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    double t = d2 / (d2 - d6);
    w[0] = 1 - t, w[2] = t;
    goto done;
  }
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w[1] = 1 - t, w[2] = t;
    goto done;
  }
  {
    double den = 1 / (va + vb + vc), v = vb * den, t = vc * den;
    w[0] = 1 - v - t, w[1] = v, w[2] = t;
  }
done:
  set_feature(w, feature, nv, loc, wf);
  double q[3];
  for (int k = 0; k < 3; k++) q[k] = p[k] - (w[0] * a[k] + w[1] * b[k] + w[2] * c[k]);
  return bs_dot3(q, q);
}

/* ---- squared distance in a region, with derivatives ------------------- */

/* Adds coef * M (3x3) to block (bi, bj) of an m-block row-major matrix. */
static void add_block(double *H, int m, int bi, int bj, double coef, const double *M) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) H[(3 * bi + i) * 3 * m + 3 * bj + j] += coef * M[3 * i + j];
}

/* Maps z-derivatives (nz blocks) to y-derivatives (ny blocks) through A (nz x
 * ny coefficients, each times I). */
static void map_derivs(int nz, int ny, const double *A, const double *gz, const double *Hz, double *g, double *H) {
  if (g) {
    memset(g, 0, sizeof(double) * 3 * (size_t)ny);
    for (int zi = 0; zi < nz; zi++)
      for (int yi = 0; yi < ny; yi++)
        if (A[zi * ny + yi] != 0)
          for (int k = 0; k < 3; k++) g[3 * yi + k] += A[zi * ny + yi] * gz[3 * zi + k];
  }
  if (H) {
    memset(H, 0, sizeof(double) * 9 * (size_t)ny * (size_t)ny);
    for (int zk = 0; zk < nz; zk++)
      for (int zl = 0; zl < nz; zl++) {
        double B[9];
        for (int i = 0; i < 3; i++)
          for (int j = 0; j < 3; j++) B[3 * i + j] = Hz[(3 * zk + i) * 3 * nz + 3 * zl + j];
        for (int yi = 0; yi < ny; yi++) {
          double ai = A[zk * ny + yi];
          if (ai == 0) continue;
          for (int yj = 0; yj < ny; yj++) {
            double aj = A[zl * ny + yj];
            if (aj != 0) add_block(H, ny, yi, yj, ai * aj, B);
          }
        }
      }
  }
}

/* Point p to the line through a and b (y = p, a, b). */
static double sqdist_edge(const double *y, const double *u, double *g, double *H) {
  const double *a = y + 3;
  static const double A[2 * 3] = {1, -1, 0, /* u = p - a */
                                  0, -1, 1 /* e = b - a */};
  double e[3];
  bs_sub3(y + 6, a, e);
  double s = bs_dot3(u, e), q = bs_dot3(e, e);
  double d = bs_dot3(u, u) - s * s / q;
  if (!g && !H) return d;
  double gz[6], Hz[36];
  for (int k = 0; k < 3; k++) {
    gz[k] = 2 * u[k] - 2 * s * e[k] / q;
    gz[3 + k] = -2 * s * u[k] / q + 2 * s * s * e[k] / (q * q);
  }
  double Buu[9], Bue[9], Bee[9], Beu[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double I = i == j;
      Buu[3 * i + j] = 2 * I - 2 * e[i] * e[j] / q;
      Bue[3 * i + j] = -2 * (e[i] * u[j] + s * I) / q + 4 * s * e[i] * e[j] / (q * q);
      Bee[3 * i + j] = -2 * u[i] * u[j] / q + 4 * s * (u[i] * e[j] + e[i] * u[j]) / (q * q) + 2 * s * s * I / (q * q) -
                       8 * s * s * e[i] * e[j] / (q * q * q);
    }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) Beu[3 * i + j] = Bue[3 * j + i];
  memset(Hz, 0, sizeof Hz);
  add_block(Hz, 2, 0, 0, 1, Buu);
  add_block(Hz, 2, 0, 1, 1, Bue);
  add_block(Hz, 2, 1, 0, 1, Beu);
  add_block(Hz, 2, 1, 1, 1, Bee);
  map_derivs(2, 3, A, gz, Hz, g, H);
  return d;
}

/* Point p to the plane through a, b and c (y = p, a, b, c). */
static double sqdist_face(const double *y, const double *u, double *g, double *H) {
  const double *a = y + 3;
  static const double A[3 * 4] = {1, -1, 0, 0, /* u  = p - a */
                                  0, -1, 1, 0, /* e1 = b - a */
                                  0, -1, 0, 1 /* e2 = c - a */};
  double e1[3], e2[3], n[3];
  bs_sub3(y + 6, a, e1);
  bs_sub3(y + 9, a, e2);
  bs_cross3(e1, e2, n);
  double r = bs_dot3(u, n), N = bs_dot3(n, n);
  double d = r * r / N;
  if (!g && !H) return d;
  double fu[3], fn[3], Fuu[9], Fun[9], Fnn[9];
  for (int k = 0; k < 3; k++) {
    fu[k] = 2 * r * n[k] / N;
    fn[k] = 2 * r * u[k] / N - 2 * r * r * n[k] / (N * N);
  }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      double I = i == j;
      Fuu[3 * i + j] = 2 * n[i] * n[j] / N;
      Fun[3 * i + j] = 2 * (n[i] * u[j] + r * I) / N - 4 * r * n[i] * n[j] / (N * N);
      Fnn[3 * i + j] = 2 * u[i] * u[j] / N - 4 * r * (u[i] * n[j] + n[i] * u[j]) / (N * N) - 2 * r * r * I / (N * N) +
                       8 * r * r * n[i] * n[j] / (N * N * N);
    }
  double J1[9], J2[9], S1[9], S2[9], Sf[9];
  skew(e2, S2);
  skew(e1, S1);
  for (int i = 0; i < 9; i++) J1[i] = -S2[i]; /* dn/de1 */
  memcpy(J2, S1, sizeof J2);                   /* dn/de2 */
  skew(fn, Sf);
  double gz[9], Hz[81];
  for (int k = 0; k < 3; k++) {
    gz[k] = fu[k];
    gz[3 + k] = J1[k] * fn[0] + J1[3 + k] * fn[1] + J1[6 + k] * fn[2];
    gz[6 + k] = J2[k] * fn[0] + J2[3 + k] * fn[1] + J2[6 + k] * fn[2];
  }
  double B[9], T[9];
  memset(Hz, 0, sizeof Hz);
  add_block(Hz, 3, 0, 0, 1, Fuu);
  mul33(Fun, J1, B); /* u, e1 */
  add_block(Hz, 3, 0, 1, 1, B);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) T[3 * i + j] = B[3 * j + i];
  add_block(Hz, 3, 1, 0, 1, T);
  mul33(Fun, J2, B); /* u, e2 */
  add_block(Hz, 3, 0, 2, 1, B);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) T[3 * i + j] = B[3 * j + i];
  add_block(Hz, 3, 2, 0, 1, T);
  double C[9];
  mul33(Fnn, J1, C);
  mul33tn(J1, C, B); /* e1, e1 */
  add_block(Hz, 3, 1, 1, 1, B);
  mul33(Fnn, J2, C);
  mul33tn(J2, C, B); /* e2, e2 */
  add_block(Hz, 3, 2, 2, 1, B);
  mul33(Fnn, J2, C);
  mul33tn(J1, C, B); /* e1, e2 */
  for (int i = 0; i < 9; i++) B[i] -= Sf[i];
  add_block(Hz, 3, 1, 2, 1, B);
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) T[3 * i + j] = B[3 * j + i];
  add_block(Hz, 3, 2, 1, 1, T);
  map_derivs(3, 4, A, gz, Hz, g, H);
  return d;
}

double bs_self_sqdist(int nv, const double *y, double *g, double *H) {
  const double *p = y, *a = y + 3;
  double u[3];
  bs_sub3(p, a, u);
  if (nv == 1) {
    static const double A[2] = {1, -1};
    double gz[3], Hz[9] = {2, 0, 0, 0, 2, 0, 0, 0, 2};
    for (int k = 0; k < 3; k++) gz[k] = 2 * u[k];
    map_derivs(1, 2, A, gz, Hz, g, H);
    return bs_dot3(u, u);
  }
  return nv == 2 ? sqdist_edge(y, u, g, H) : sqdist_face(y, u, g, H);
}

double bs_self_pair_energy(int nv, const double *y, double k, double *g, double *H) {
  int m = 3 * (nv + 1);
  double gd[12], Hd[144];
  double d = bs_self_sqdist(nv, y, (g || H) ? gd : NULL, H ? Hd : NULL);
  if (d < 0) d = 0; /* round-off in the edge and face formulas */
  double se = sqrt(d + BS_SELF_EPS);
  double psi = d * se, dpsi = se + d / (2 * se), ddpsi = 1 / se - d / (4 * se * se * se);
  if (g)
    for (int i = 0; i < m; i++) g[i] = k * dpsi * gd[i];
  if (H)
    for (int i = 0; i < m; i++)
      for (int j = 0; j < m; j++) H[i * m + j] = k * (ddpsi * gd[i] * gd[j] + dpsi * Hd[i * m + j]);
  return k * psi;
}

void bs_self_pair_secant(int nv, const double *y, double k, const double *g, double *H) {
  const int m = 3 * (nv + 1);
  double gd[12];
  const double d = bs_self_sqdist(nv, y, gd, NULL);
  if (!(d > BS_SELF_SECANT_MIN_D)) return;
  const double r = sqrt(d), se = sqrt(d + BS_SELF_EPS);
  const double s = k * (se + d / (2 * se)) * 2 * r; /* dPhi/dr */
  double gg = 0, dd = 0;
  for (int i = 0; i < m; i++) gg += g[i] * gd[i], dd += gd[i] * gd[i];
  if (!(dd > 0)) return;
  const double F = s - gg * 2 * r / dd; /* the other terms' push along grad r */
  const double rs = F > 0 ? sqrt(F / (3 * k)) : 0;
  const double c = 3 * k * (rs - r) / (4 * d); /* (3 k (r + r*) - 6 k r) grad r grad r^T */
  if (!isfinite(c)) return;
  for (int i = 0; i < m; i++)
    for (int j = 0; j < m; j++) H[i * m + j] += c * gd[i] * gd[j];
}

/* ---- the term --------------------------------------------------------- */

typedef struct contact {
  int nv;           /* primitive vertices (0: not colliding)       */
  int32_t v[4];     /* p, then the primitive's vertices            */
  double w[4];      /* -1, then the closest point's weights         */
  double d;         /* squared distance                            */
} contact;

typedef struct self_data {
  const bs_fem *fem;
  const bs_mesh *mesh;
  double k;
  int secant;           /* hessian_g gives the secant model (else the Hessian) */
  int32_t n_surf;
  int32_t *surf;        /* boundary vertices                                */
  /* hierarchies: built at creation, rebuilt at a step's start when their
     cost grew (bvh_update), refit at each detection */
  bs_bvh tet_bvh;       /* the tets                                         */
  bs_bvh tri_bvh;       /* the boundary triangles                           */
  double tet_cost, tri_cost; /* their bs_bvh_cost at the last rebuild      */
  bs_shim_tree *rest;   /* the boundary at rest                             */
  double h_min;         /* smallest search radius: half the mean boundary edge */
  int nthreads;
  int32_t *cand;        /* nthreads * n_faces                              */
  int32_t *mark;        /* nthreads * n_vertices: find_tet's neighbour marks */
  /* per surface vertex */
  int32_t *coll_tet;    /* tet it is in, -1 none                             */
  int32_t *hint;        /* last primitive triangle, -1 none                 */
  int64_t *if_ptr;      /* n_surf + 1: CSR of the interface faces below     */
  int32_t *if_face;     /* 3 if_ptr[n_surf]: vertices of each interface face */
  contact *con;
  int32_t *active;      /* n_surf: the contacts of a Hessian, in order     */
  double *hl;           /* HESS_BATCH * 144: their local Hessians          */
  int failed;           /* a shim call failed (non-finite input)            */
  /* the last detection: positions and result, reused when detect is called
     again at the same positions (value then gradient then Hessian at one
     iterate, friction at the solution) */
  double *x_last;       /* 3 n_vertices                                     */
  int have_last;
  int32_t last_count, last_colliding;
  double last_depth;
  bs_self_stats stats;
} self_data;

static void self_free(void *p) {
  self_data *d = p;
  if (!d) return;
  free(d->surf);
  bs_bvh_free(&d->tet_bvh);
  bs_bvh_free(&d->tri_bvh);
  bs_shim_tree_destroy(&d->rest);
  free(d->cand);
  free(d->mark);
  free(d->coll_tet);
  free(d->hint);
  free(d->if_ptr);
  free(d->if_face);
  free(d->con);
  free(d->active);
  free(d->hl);
  free(d->x_last);
  free(d);
}

/* Both hierarchies' topology from the positions x, and their costs there. */
static void bvh_rebuild(self_data *d, const double *x) {
  double t0 = bs_seconds();
  bs_bvh_build(&d->tet_bvh, x, d->nthreads);
  bs_bvh_build(&d->tri_bvh, x, d->nthreads);
  bs_bvh_refit(&d->tet_bvh, x, d->nthreads);
  bs_bvh_refit(&d->tri_bvh, x, d->nthreads);
  d->tet_cost = bs_bvh_cost(&d->tet_bvh);
  d->tri_cost = bs_bvh_cost(&d->tri_bvh);
  d->stats.rebuilds++;
  d->stats.t_rebuild += bs_seconds() - t0;
}

/* At a step's start: both hierarchies refit to x, rebuilt when either's cost
 * grew past BS_SELF_REBUILD_GROWTH times its cost at the last rebuild (or is
 * not finite). */
static void bvh_update(self_data *d, const double *x) {
  double t0 = bs_seconds();
  bs_bvh_refit(&d->tet_bvh, x, d->nthreads);
  bs_bvh_refit(&d->tri_bvh, x, d->nthreads);
  const double ct = bs_bvh_cost(&d->tet_bvh), cf = bs_bvh_cost(&d->tri_bvh);
  d->stats.t_refit += bs_seconds() - t0;
  if (!(ct <= BS_SELF_REBUILD_GROWTH * d->tet_cost) || !(cf <= BS_SELF_REBUILD_GROWTH * d->tri_cost))
    bvh_rebuild(d, x);
}

/* det[b - a, c - a, d - a] in double, with a bound on its rounding error
 * (far above the true one, about 1e-15 of the product of the lengths). */
static double orient_bound(const double *a, const double *b, const double *c, const double *d, double *bound) {
  double u[3], v[3], w[3], n[3];
  bs_sub3(b, a, u);
  bs_sub3(c, a, v);
  bs_sub3(d, a, w);
  bs_cross3(u, v, n);
  double lu = fabs(u[0]) + fabs(u[1]) + fabs(u[2]), lv = fabs(v[0]) + fabs(v[1]) + fabs(v[2]);
  double lw = fabs(w[0]) + fabs(w[1]) + fabs(w[2]);
  *bound = 1e-12 * lu * lv * lw;
  return bs_dot3(n, w);
}

/* A floating-point filter in front of the exact test: 1 when p is certainly
 * outside the closed tet (a, b, c, d) of either orientation (outside its box,
 * or on the far side of a face by more than the rounding bound), 0 when
 * unsure (the exact test then decides). */
static int surely_outside(const double *p, const double *a, const double *b, const double *c, const double *d) {
  for (int k = 0; k < 3; k++) {
    double lo = fmin(fmin(a[k], b[k]), fmin(c[k], d[k])), hi = fmax(fmax(a[k], b[k]), fmax(c[k], d[k]));
    if (p[k] < lo || p[k] > hi) return 1;
  }
  double eb, e;
  double o = orient_bound(a, b, c, d, &eb);
  if (!(fabs(o) > eb)) return 0;
  const double *V[4] = {a, b, c, d};
  for (int i = 0; i < 4; i++) {
    const double *W[4] = {V[0], V[1], V[2], V[3]};
    W[i] = p;
    double oi = orient_bound(W[0], W[1], W[2], W[3], &e);
    if (fabs(oi) > e && (oi > 0) != (o > 0)) return 1;
  }
  return 0;
}

/* Whether one of the n vertices v is pv or an edge neighbour of pv (the
 * row of pv in the fem's pattern P, which holds pv and every vertex sharing a
 * tet with it). A tet (n = 4) with such a vertex is in pv's excluded
 * neighbourhood, and so is the tet of a boundary triangle (n = 3) with one,
 * which is then not on the boundary of the region where pv collides. See the
 * header. */
static int near_vertex(const bs_bsr *P, int32_t pv, const int32_t *v, int n) {
  for (int a = 0; a < n; a++)
    if (bs_bsr_slot(P, pv, v[a]) >= 0) return 1;
  return 0;
}

/* The first tet (in traversal order) outside the neighbourhood of vertex pv
 * (near_vertex) whose closed set contains x_pv; -1 if none; -2 on a shim
 * error. The neighbour test reads mark (the thread's, n_vertices): set here
 * to pv at the vertices of pv's pattern row, and never pv elsewhere (only a
 * row's vertices get its vertex), so mark[v] == pv is near_vertex's test
 * without its binary searches. */
static int32_t find_tet(const self_data *d, const double *x, int32_t pv, int32_t *mark) {
  const double *p = x + 3 * (size_t)pv;
  const bs_bsr *P = d->fem->pattern;
  for (int32_t s = P->row_ptr[pv]; s < P->row_ptr[pv + 1]; s++) mark[P->col[s]] = pv;
  const bs_bvh *b = &d->tet_bvh;
  int32_t stack[BS_BVH_STACK];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const bs_bvh_node *nd = &b->nodes[stack[--top]];
    if (p[0] < nd->lo[0] || p[0] > nd->hi[0] || p[1] < nd->lo[1] || p[1] > nd->hi[1] || p[2] < nd->lo[2] ||
        p[2] > nd->hi[2])
      continue;
    if (nd->left >= 0) {
      stack[top++] = nd->left;
      stack[top++] = nd->right;
      continue;
    }
    for (int32_t j = nd->first; j < nd->first + nd->count; j++) {
      const int32_t *tv = b->leaf_elems + 4 * (size_t)j; /* tet order[j]'s vertices */
      if (mark[tv[0]] == pv || mark[tv[1]] == pv || mark[tv[2]] == pv || mark[tv[3]] == pv) continue;
      if (surely_outside(p, x + 3 * (size_t)tv[0], x + 3 * (size_t)tv[1], x + 3 * (size_t)tv[2],
                         x + 3 * (size_t)tv[3]))
        continue;
      int r = bs_shim_point_in_tet(p, x + 3 * (size_t)tv[0], x + 3 * (size_t)tv[1], x + 3 * (size_t)tv[2],
                                   x + 3 * (size_t)tv[3]);
      if (r < -1) return -2;
      if (r >= 0) return b->order[j];
    }
  }
  return -1;
}

static double tri_dist2(const double *x, const int32_t *f, const double *p) {
  double w[3], wf[3];
  int feat, nv, loc[3];
  return bs_self_closest_triangle(p, x + 3 * (size_t)f[0], x + 3 * (size_t)f[1], x + 3 * (size_t)f[2], w, &feat, &nv,
                                  loc, wf);
}

/* Rest-shape estimate of the triangle that surface vertex pv (inside tet t)
 * collides with: the triangle closest in the rest shape to the rest-shape
 * image of x_pv (its barycentric coordinates in t). -1 when unavailable. */
static int32_t rest_estimate(const self_data *d, const double *x, int32_t pv, int32_t t) {
  const bs_mesh *m = d->mesh;
  const int32_t *tv = m->tets + 4 * t;
  double Ds[9], r[3];
  for (int c = 0; c < 3; c++)
    for (int k = 0; k < 3; k++) Ds[3 * k + c] = x[3 * tv[c + 1] + k] - x[3 * tv[0] + k];
  bs_sub3(x + 3 * (size_t)pv, x + 3 * (size_t)tv[0], r);
  double det = Ds[0] * (Ds[4] * Ds[8] - Ds[5] * Ds[7]) - Ds[1] * (Ds[3] * Ds[8] - Ds[5] * Ds[6]) +
               Ds[2] * (Ds[3] * Ds[7] - Ds[4] * Ds[6]);
  if (!(fabs(det) > 0) || !isfinite(det)) return -1;
  /* lambda = Ds^-1 r by Cramer's rule */
  double lam[3];
  for (int c = 0; c < 3; c++) {
    double M[9];
    memcpy(M, Ds, sizeof M);
    for (int k = 0; k < 3; k++) M[3 * k + c] = r[k];
    lam[c] = (M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
              M[2] * (M[3] * M[7] - M[4] * M[6])) / det;
  }
  double X[3];
  for (int k = 0; k < 3; k++) {
    X[k] = m->x[3 * tv[0] + k];
    for (int c = 0; c < 3; c++) X[k] += lam[c] * (m->x[3 * tv[c + 1] + k] - m->x[3 * tv[0] + k]);
  }
  if (!isfinite(X[0]) || !isfinite(X[1]) || !isfinite(X[2])) return -1;
  int32_t tri = -1;
  if (bs_shim_tree_closest(d->rest, X, NULL, &tri, NULL, NULL) != 0) return -1;
  return tri;
}

/* c := the contact of vertex pv with the closest feature of triangle f. */
static void set_contact(contact *c, const double *x, int32_t pv, const int32_t *f) {
  double w[3], wf[3];
  int feat, nv, loc[3];
  c->d = bs_self_closest_triangle(x + 3 * (size_t)pv, x + 3 * (size_t)f[0], x + 3 * (size_t)f[1],
                                  x + 3 * (size_t)f[2], w, &feat, &nv, loc, wf);
  c->nv = nv;
  c->v[0] = pv;
  c->w[0] = -1;
  for (int a = 0; a < nv; a++) c->v[1 + a] = f[loc[a]], c->w[1 + a] = wf[a];
}

/* The closest admissible primitive of surface vertex i (index into surf):
 * over the boundary triangles with neither p nor an edge neighbour of p as a
 * vertex and p's interface faces (a full scan of its short list). Returns 0,
 * or -1 on a shim error. c->nv = 0 when none exists. */
static int closest_primitive(self_data *d, const double *x, int32_t i, double diag, int32_t *buf) {
  const bs_mesh *m = d->mesh;
  const bs_bsr *P = d->fem->pattern;
  int32_t pv = d->surf[i];
  const double *p = x + 3 * (size_t)pv;
  contact *c = &d->con[i];
  c->nv = 0;
  double ib = INFINITY;
  const int32_t *iface = NULL;
  for (int64_t j = d->if_ptr[i]; j < d->if_ptr[i + 1]; j++) {
    const int32_t *f = d->if_face + 3 * j;
    const double dd = tri_dist2(x, f, p);
    if (dd < ib) ib = dd, iface = f;
  }
  double r = -1;
  int32_t h = d->hint[i];
  if (h >= 0 && !near_vertex(P, pv, m->faces + 3 * h, 3)) r = sqrt(tri_dist2(x, m->faces + 3 * h, p));
  if (r < 0) {
    int32_t e = rest_estimate(d, x, pv, d->coll_tet[i]);
    if (e >= 0 && !near_vertex(P, pv, m->faces + 3 * e, 3)) r = sqrt(tri_dist2(x, m->faces + 3 * e, p));
  }
  if (r < 0) r = d->h_min;
  if (iface && sqrt(ib) < r) r = sqrt(ib);
  for (;;) {
    double lo[3] = {p[0] - r, p[1] - r, p[2] - r}, hi[3] = {p[0] + r, p[1] + r, p[2] + r};
    const int64_t cnt = bs_bvh_within(&d->tri_bvh, lo, hi, buf, m->n_faces);
    double best = INFINITY;
    int32_t bt = -1;
    for (int64_t j = 0; j < cnt; j++) {
      int32_t f = buf[j];
      if (near_vertex(P, pv, m->faces + 3 * f, 3)) continue;
      double dd = tri_dist2(x, m->faces + 3 * f, p);
      if (dd < best || (dd == best && f < bt)) best = dd, bt = f;
    }
    /* every boundary triangle within r is among the candidates, so best is
       their minimum when it is <= r^2; the interface scan is exact */
    const int surf_ok = bt >= 0 && best <= r * r, if_ok = iface && ib <= r * r;
    if (surf_ok && (!if_ok || best <= ib)) {
      set_contact(c, x, pv, m->faces + 3 * bt);
      d->hint[i] = bt;
      return 0;
    }
    if (if_ok) {
      set_contact(c, x, pv, iface);
      return 0;
    }
    if (r > 2 * diag) return 0; /* every triangle was seen: none admissible */
    r = r < d->h_min ? d->h_min : 2 * r;
  }
}

/* The calling thread's number in its team (0 without OpenMP): the index of
 * its per-thread buffers (cand, mark). */
static int thread_num(void) {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/* 1 when the n vertices' coordinates are all finite. */
static int all_finite(const double *x, int32_t n) {
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(| : bad) if (n >= 4 * PAR_MIN)
  for (int64_t i = 0; i < 3 * (int64_t)n; i++) bad |= !isfinite(x[i]);
  return !bad;
}

/* Detection and primitives at x; fills d->con. Returns the number of
 * colliding vertices, or -1 on a non-finite x or a shim error. */
static int32_t detect_at(self_data *d, const double *x) {
  if (!all_finite(x, d->mesh->n_vertices)) return -1; /* a NaN would pass the boxes' min and max */
  double t0 = bs_seconds();
  bs_bvh_refit(&d->tet_bvh, x, d->nthreads);
  d->stats.t_refit += bs_seconds() - t0;
  const bs_bvh_node *root = &d->tet_bvh.nodes[0];
  t0 = bs_seconds();
  int failed = 0;
  int32_t n = d->n_surf;
#pragma omp parallel num_threads(d->nthreads) reduction(| : failed) if (n >= PAR_MIN)
  {
    int32_t *mark = d->mark + (size_t)thread_num() * (size_t)d->mesh->n_vertices;
#pragma omp for schedule(dynamic, 64)
    for (int32_t i = 0; i < n; i++) {
      int32_t t = find_tet(d, x, d->surf[i], mark);
      if (t == -2) failed = 1, t = -1;
      d->coll_tet[i] = t;
      d->con[i].nv = 0;
    }
  }
  int32_t count = 0;
  for (int32_t i = 0; i < n; i++) count += d->coll_tet[i] >= 0;
  double t1 = bs_seconds();
  d->stats.t_detect += t1 - t0;
  if (failed) return -1;
  if (count == 0) {
    d->stats.colliding = 0;
    d->stats.max_depth = 0;
    return 0;
  }
  bs_bvh_refit(&d->tri_bvh, x, d->nthreads);
  double diag = 0;
  for (int k = 0; k < 3; k++) diag += (root->hi[k] - root->lo[k]) * (root->hi[k] - root->lo[k]);
  diag = sqrt(diag);
#pragma omp parallel num_threads(d->nthreads) reduction(| : failed) if (count >= PAR_MIN / 8)
  {
    int32_t *buf = d->cand + (size_t)thread_num() * (size_t)d->mesh->n_faces;
#pragma omp for schedule(dynamic, 16)
    for (int32_t i = 0; i < n; i++)
      if (d->coll_tet[i] >= 0 && closest_primitive(d, x, i, diag, buf) != 0) failed = 1;
  }
  d->stats.t_closest += bs_seconds() - t1;
  if (failed) return -1;
  count = 0;
  double depth = 0;
  for (int32_t i = 0; i < n; i++)
    if (d->con[i].nv > 0) {
      count++;
      double dd = sqrt(d->con[i].d);
      depth = dd > depth ? dd : depth;
    }
  d->stats.colliding = count;
  d->stats.max_depth = depth;
  return count;
}

/* detect_at, or its last result when x is bitwise the x of the last call
 * (a memcmp of 3 n doubles against a point-in-tet search per surface vertex). */
static int32_t detect(self_data *d, const double *x) {
  const size_t bytes = 3 * sizeof(double) * (size_t)d->mesh->n_vertices;
  d->stats.evaluations++;
  if (d->have_last && memcmp(x, d->x_last, bytes) == 0) {
    d->stats.reused++;
    d->stats.colliding = d->last_colliding;
    d->stats.max_depth = d->last_depth;
    return d->last_count;
  }
  const int32_t cnt = detect_at(d, x);
  d->have_last = cnt >= 0;
  if (cnt >= 0) {
    memcpy(d->x_last, x, bytes);
    d->last_count = cnt;
    d->last_colliding = d->stats.colliding;
    d->last_depth = d->stats.max_depth;
  }
  return cnt;
}

static void gather(const double *x, const contact *c, double *y) {
  for (int a = 0; a <= c->nv; a++)
    for (int k = 0; k < 3; k++) y[3 * a + k] = x[3 * (size_t)c->v[a] + k];
}

/* Not evaluable where detection cannot run (a non-finite x, or a failed
 * geometric query): then neither *Eout nor g is touched. */
static int self_eval(const bs_term *t, const double *x, double *Eout, double *g) {
  self_data *d = t->data;
  int32_t cnt = detect(d, x);
  if (cnt < 0) return BS_TERM_NOT_EVALUABLE;
  double E = 0;
  for (int32_t i = 0; i < d->n_surf && cnt > 0; i++) {
    const contact *c = &d->con[i];
    if (c->nv == 0) continue;
    double y[12], gl[12];
    gather(x, c, y);
    E += bs_self_pair_energy(c->nv, y, d->k, g ? gl : NULL, NULL);
    if (g)
      for (int a = 0; a <= c->nv; a++)
        for (int k = 0; k < 3; k++) g[3 * (size_t)c->v[a] + k] += gl[3 * a + k];
  }
  *Eout = E;
  return BS_TERM_OK;
}

static int self_value(const bs_term *t, const double *x, double *E) { return self_eval(t, x, E, NULL); }
static int self_gradient(const bs_term *t, const double *x, double *E, double *g) { return self_eval(t, x, E, g); }

/* Adds the Hessian at x (after detect) into H, or, with H NULL, visits the
 * blocks off the fem pattern. Returns the blocks that found no place (H: no
 * slot and no room left in its extra list; NULL: off the pattern). */
typedef void (*missing_fn)(int32_t i, int32_t j, const double *B, void *ctx);

/* The local Hessians of the contacts active[0..n) into hl (144 each, row
 * stride 3 (nv + 1)), with the secant model when g (the objective's
 * gradient) is given, projected onto the PSD cone when convex; in parallel,
 * each the same whatever the thread count. */
static void local_hessians(const self_data *d, const double *x, const double *g, int convex, const int32_t *active,
                           int n, double *hl) {
#pragma omp parallel for schedule(dynamic, 4) num_threads(d->nthreads) if (n >= HESS_PAR_MIN)
  for (int i = 0; i < n; i++) {
    const contact *c = &d->con[active[i]];
    double y[12], gl[12], *Hl = hl + 144 * (size_t)i;
    gather(x, c, y);
    bs_self_pair_energy(c->nv, y, d->k, NULL, Hl);
    if (g) {
      gather(g, c, gl);
      bs_self_pair_secant(c->nv, y, d->k, gl, Hl);
    }
    if (convex) bs_sym_psd_project(3 * (c->nv + 1), Hl);
  }
}

/* Adds contact c's local Hessian Hl into H, or with H NULL visits its blocks
 * off the fem pattern P; returns the blocks that found no place. */
static int64_t place(const contact *c, const double *Hl, const bs_bsr *P, bs_bsr *H, missing_fn fn, void *ctx) {
  const int m = 3 * (c->nv + 1);
  int64_t missing = 0;
  for (int a = 0; a <= c->nv; a++)
    for (int b = 0; b <= c->nv; b++) {
      double B[9];
      for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++) B[3 * r + q] = Hl[(3 * a + r) * m + 3 * b + q];
      if (H) { /* its slot, else H's extra list */
        missing += bs_bsr_add_block(H, c->v[a], c->v[b], B) == BS_BSR_DROPPED;
      } else if (a != b && bs_bsr_slot(P, c->v[a], c->v[b]) < 0) {
        missing++;
        if (fn) fn(c->v[a], c->v[b], B, ctx);
      }
    }
  return missing;
}

static int64_t assemble(self_data *d, const double *x, const double *g, int convex, bs_bsr *H, missing_fn fn,
                        void *ctx) {
  int32_t n = 0;
  for (int32_t i = 0; i < d->n_surf; i++)
    if (d->con[i].nv > 0) d->active[n++] = i;
  int64_t missing = 0;
  for (int32_t b0 = 0; b0 < n; b0 += HESS_BATCH) {
    const int nb = n - b0 < HESS_BATCH ? (int)(n - b0) : HESS_BATCH;
    local_hessians(d, x, g, convex, d->active + b0, nb, d->hl);
    for (int i = 0; i < nb; i++)
      missing += place(&d->con[d->active[b0 + i]], d->hl + 144 * (size_t)i, d->fem->pattern, H, fn, ctx);
  }
  return missing;
}

/* Not evaluable as self_eval (H untouched). convex: each contact's Hessian
 * projected onto the PSD cone (the term's hessian_convexified); g: the
 * secant model (the term's hessian_g). */
static int hessian_at(const bs_term *t, const double *x, const double *g, int convex, bs_bsr *H) {
  self_data *d = t->data;
  int32_t cnt = detect(d, x);
  if (cnt < 0) return BS_TERM_NOT_EVALUABLE;
  d->stats.missing_blocks = cnt ? assemble(d, x, g, convex, H, NULL, NULL) : 0;
  return BS_TERM_OK;
}

static int self_hessian(const bs_term *t, const double *x, bs_bsr *H) { return hessian_at(t, x, NULL, 0, H); }
static int self_hessian_convexified(const bs_term *t, const double *x, bs_bsr *H) {
  return hessian_at(t, x, NULL, 1, H);
}
static int self_hessian_g(const bs_term *t, const double *x, const double *g, bs_bsr *H) {
  return hessian_at(t, x, ((const self_data *)t->data)->secant ? g : NULL, 0, H);
}

static int self_begin_step(bs_term *t, bs_error *err) {
  (void)err;
  self_data *d = t->data;
  if (t->step && t->step->x_n) {
    const double *x = t->step->x_n;
    for (int32_t v = 0; v < d->mesh->n_vertices; v++)
      for (int k = 0; k < 3; k++)
        if (!isfinite(x[3 * (size_t)v + k]))
          return bs_error_set(err, BS_ENUMERIC, "self-collision: position of vertex %d is not finite", (int)v);
    bvh_update(d, x); /* the last detection stays valid: the same positions give the same contacts */
  }
  return 0;
}

static const bs_term_ops self_ops = {self_value, self_gradient, self_hessian, self_begin_step, self_free,
                                     self_hessian_convexified, self_hessian_g, NULL, NULL, NULL};

/* ---- interface faces ---------------------------------------------------
 * The excluded region of surface vertex p is the union of the tets that hold
 * p or an edge neighbour of p (near_vertex). Its interface faces are its
 * faces shared with a tet outside it: where p, moving through its own body,
 * enters an admissible tet other than through the surface. They are primitives
 * of p besides the boundary triangles (see the header), which makes the
 * distance, and Phi, zero wherever p enters the admissible tets. They depend
 * on the mesh only: listed once, at creation. */

typedef struct tri_key {
  int32_t v[3]; /* ascending */
} tri_key;

static int cmp_tri_key(const void *a, const void *b) {
  const int32_t *p = ((const tri_key *)a)->v, *q = ((const tri_key *)b)->v;
  for (int k = 0; k < 3; k++)
    if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
  return 0;
}

static tri_key make_key(int32_t a, int32_t b, int32_t c) {
  tri_key k;
  if (a > b) { int32_t t = a; a = b; b = t; }
  if (b > c) { int32_t t = b; b = c; c = t; }
  if (a > b) { int32_t t = a; a = b; b = t; }
  k.v[0] = a, k.v[1] = b, k.v[2] = c;
  return k;
}

/* Scratch of one thread (grown on demand). */
typedef struct if_scratch {
  int32_t *tets;
  size_t cap_tets;
  tri_key *keys;
  size_t cap_keys;
} if_scratch;

/* p grown to hold need elements of size bytes (cap updated); NULL when out of
 * memory (p is then still valid and owned by the caller). */
static void *grow(void *p, size_t *cap, size_t need, size_t size) {
  if (p && need <= *cap) return p;
  size_t c = *cap ? *cap : 256;
  while (c < need) c *= 2;
  void *q = realloc(p, c * size);
  if (q) *cap = c;
  return q;
}

/* The interface faces of vertex pv into sc->keys (count returned; -1: out of
 * memory). bkeys: the boundary faces, sorted. */
static int64_t interface_of(const self_data *d, int32_t pv, const tri_key *bkeys, if_scratch *sc) {
  const bs_mesh *m = d->mesh;
  const bs_bsr *P = d->fem->pattern;
  size_t nt = 0;
  for (int32_t s = P->row_ptr[pv]; s < P->row_ptr[pv + 1]; s++) {
    const int32_t q = P->col[s];
    const size_t deg = (size_t)(m->v2t_ptr[q + 1] - m->v2t_ptr[q]);
    int32_t *t = grow(sc->tets, &sc->cap_tets, nt + deg, sizeof(int32_t));
    if (!t) return -1;
    sc->tets = t;
    memcpy(sc->tets + nt, m->v2t + m->v2t_ptr[q], deg * sizeof(int32_t));
    nt += deg;
  }
  qsort(sc->tets, nt, sizeof(int32_t), bs_cmp_i32);
  size_t u = 0;
  for (size_t j = 0; j < nt; j++)
    if (u == 0 || sc->tets[j] != sc->tets[u - 1]) sc->tets[u++] = sc->tets[j];
  tri_key *kk = grow(sc->keys, &sc->cap_keys, 4 * u, sizeof(tri_key));
  if (!kk) return -1;
  sc->keys = kk;
  size_t nk = 0;
  for (size_t j = 0; j < u; j++) {
    const int32_t *tv = m->tets + 4 * (size_t)sc->tets[j];
    sc->keys[nk++] = make_key(tv[1], tv[2], tv[3]);
    sc->keys[nk++] = make_key(tv[0], tv[2], tv[3]);
    sc->keys[nk++] = make_key(tv[0], tv[1], tv[3]);
    sc->keys[nk++] = make_key(tv[0], tv[1], tv[2]);
  }
  qsort(sc->keys, nk, sizeof(tri_key), cmp_tri_key);
  /* a face met once bounds the region: the boundary's are already primitives */
  int64_t n = 0;
  for (size_t j = 0; j < nk;) {
    size_t e = j + 1;
    while (e < nk && cmp_tri_key(&sc->keys[e], &sc->keys[j]) == 0) e++;
    if (e == j + 1 && !bsearch(&sc->keys[j], bkeys, (size_t)m->n_faces, sizeof(tri_key), cmp_tri_key))
      sc->keys[n++] = sc->keys[j];
    j = e;
  }
  return n;
}

static int build_interfaces(self_data *d, bs_error *err) {
  const bs_mesh *m = d->mesh;
  const int32_t ns = d->n_surf;
  tri_key *bkeys = malloc(sizeof(tri_key) * ((size_t)m->n_faces + 1));
  int32_t **lists = calloc((size_t)ns + 1, sizeof(int32_t *));
  d->if_ptr = calloc((size_t)ns + 1, sizeof(int64_t));
  if (!bkeys || !lists || !d->if_ptr) {
    free(bkeys);
    free(lists);
    return bs_error_set(err, BS_ENOMEM, "out of memory listing the self-collision interface faces");
  }
  for (int32_t f = 0; f < m->n_faces; f++)
    bkeys[f] = make_key(m->faces[3 * f], m->faces[3 * f + 1], m->faces[3 * f + 2]);
  qsort(bkeys, (size_t)m->n_faces, sizeof(tri_key), cmp_tri_key);
  int failed = 0;
#pragma omp parallel num_threads(d->nthreads) reduction(| : failed) if (ns >= PAR_MIN)
  {
    if_scratch sc = {0};
#pragma omp for schedule(dynamic, 64)
    for (int32_t i = 0; i < ns; i++) {
      if (failed) continue;
      const int64_t n = interface_of(d, d->surf[i], bkeys, &sc);
      lists[i] = n >= 0 ? malloc(sizeof(int32_t) * 3 * (size_t)(n > 0 ? n : 1)) : NULL;
      if (!lists[i]) {
        failed = 1;
        continue;
      }
      for (int64_t j = 0; j < n; j++) memcpy(lists[i] + 3 * j, sc.keys[j].v, 3 * sizeof(int32_t));
      d->if_ptr[i + 1] = n;
    }
    free(sc.tets);
    free(sc.keys);
  }
  free(bkeys);
  if (!failed) {
    for (int32_t i = 0; i < ns; i++) d->if_ptr[i + 1] += d->if_ptr[i];
    d->if_face = malloc(sizeof(int32_t) * 3 * (size_t)(d->if_ptr[ns] + 1));
    if (!d->if_face) failed = 1;
  }
  for (int32_t i = 0; i < ns; i++) {
    if (!failed)
      memcpy(d->if_face + 3 * d->if_ptr[i], lists[i], sizeof(int32_t) * 3 * (size_t)(d->if_ptr[i + 1] - d->if_ptr[i]));
    free(lists[i]);
  }
  free(lists);
  if (failed) return bs_error_set(err, BS_ENOMEM, "out of memory listing the self-collision interface faces");
  return 0;
}

int bs_term_self_create(const bs_fem *fem, const bs_step_data *step, double k, bs_term **out, bs_error *err) {
  if (!fem || !out) return bs_error_set(err, BS_EINPUT, "self-collision term: fem and out must be non-NULL");
  *out = NULL;
  if (!isfinite(k) || !(k > 0))
    return bs_error_set(err, BS_EINPUT, "self-collision stiffness k = %g: must be finite and > 0 (J/m^3)", k);
  const bs_mesh *m = fem->mesh;
  if (m->n_faces < 1 || m->n_tets < 1)
    return bs_error_set(err, BS_EINPUT, "self-collision term: the mesh has %d boundary faces and %d tets",
                        (int)m->n_faces, (int)m->n_tets);
  self_data *d = bs_calloc(1, sizeof *d, "the self-collision term", err);
  if (!d) return BS_ENOMEM;
  d->fem = fem;
  d->mesh = m;
  d->k = k;
  int st = 0;
  uint8_t *is_surf = bs_calloc((size_t)m->n_vertices + 1, 1, "the self-collision surface", err);
  if (!is_surf) st = BS_ENOMEM;
  if (!st) {
    for (int32_t f = 0; f < 3 * m->n_faces; f++) is_surf[m->faces[f]] = 1;
    for (int32_t v = 0; v < m->n_vertices; v++) d->n_surf += is_surf[v];
    d->surf = bs_calloc((size_t)d->n_surf + 1, sizeof(int32_t), "the self-collision surface", err);
    d->coll_tet = bs_calloc((size_t)d->n_surf + 1, sizeof(int32_t), "the self-collision surface", err);
    d->hint = bs_calloc((size_t)d->n_surf + 1, sizeof(int32_t), "the self-collision surface", err);
    d->con = bs_calloc((size_t)d->n_surf + 1, sizeof(contact), "the self-collision contacts", err);
    d->active = bs_calloc((size_t)d->n_surf + 1, sizeof(int32_t), "the self-collision contacts", err);
    d->hl = bs_calloc(144 * (size_t)HESS_BATCH, sizeof(double), "the self-collision contact Hessians", err);
    d->nthreads = 1;
#ifdef _OPENMP
    d->nthreads = omp_get_max_threads();
#endif
    d->cand = bs_calloc((size_t)d->nthreads * (size_t)m->n_faces, sizeof(int32_t), "the candidate buffers", err);
    d->mark = bs_calloc((size_t)d->nthreads * (size_t)m->n_vertices + 1, sizeof(int32_t), "the neighbour marks", err);
    for (size_t i = 0; d->mark && i < (size_t)d->nthreads * (size_t)m->n_vertices; i++) d->mark[i] = -1;
    d->x_last = bs_calloc(3 * (size_t)m->n_vertices + 1, sizeof(double), "the self-collision positions", err);
    if (!d->surf || !d->coll_tet || !d->hint || !d->con || !d->active || !d->hl || !d->cand || !d->mark ||
        !d->x_last)
      st = BS_ENOMEM;
    if (!st) st = bs_bvh_init(&d->tet_bvh, m->tets, 4, m->n_tets, err);
    if (!st) st = bs_bvh_init(&d->tri_bvh, m->faces, 3, m->n_faces, err);
  }
  if (!st) {
    int32_t n = 0;
    for (int32_t v = 0; v < m->n_vertices; v++)
      if (is_surf[v]) d->surf[n++] = v;
    for (int32_t i = 0; i < d->n_surf; i++) d->hint[i] = -1;
    double len = 0;
    for (int32_t e = 0; e < m->n_edges; e++) {
      double u[3];
      bs_sub3(m->x + 3 * (size_t)m->edges[2 * e], m->x + 3 * (size_t)m->edges[2 * e + 1], u);
      len += sqrt(bs_dot3(u, u));
    }
    d->h_min = m->n_edges ? 0.5 * len / m->n_edges : 1e-3;
    if (!(d->h_min > 0)) d->h_min = 1e-3;
    st = bs_shim_tree_create(m->x, m->n_vertices, m->faces, m->n_faces, &d->rest, err);
  }
  free(is_surf);
  bs_term *t = NULL;
  if (!st) st = build_interfaces(d, err);
  if (!st) {
    bvh_rebuild(d, m->x);
    t = calloc(1, sizeof *t);
    if (!t) st = bs_error_set(err, BS_ENOMEM, "out of memory creating the self-collision term");
  }
  if (st) {
    self_free(d);
    return st;
  }
  t->name = "self_collision";
  t->kind = BS_TERM_SELF_COLLISION;
  t->ops = &self_ops;
  t->fem = fem;
  t->step = step;
  t->expensive = 1;
  /* A colliding vertex couples with at most 3 primitive vertices: 6 blocks. */
  t->hessian_extra = 6 * (int64_t)d->n_surf;
  t->data = d;
  *out = t;
  return 0;
}

int bs_term_is_self(const bs_term *t) { return t && t->ops == &self_ops; }

static int need_self(const bs_term *t, const char *what, bs_error *err) {
  if (!bs_term_is_self(t))
    return bs_error_set(err, BS_EINPUT, "%s: term \"%s\" is not a self-collision term", what,
                        t && t->name ? t->name : "NULL");
  return 0;
}

static int check_x(const self_data *d, const double *x, const char *what, bs_error *err) {
  if (!x) return bs_error_set(err, BS_EINPUT, "%s: positions are NULL", what);
  for (int32_t v = 0; v < d->mesh->n_vertices; v++)
    for (int k = 0; k < 3; k++)
      if (!isfinite(x[3 * (size_t)v + k]))
        return bs_error_set(err, BS_ENUMERIC, "%s: position of vertex %d (component %d) is not finite", what, (int)v,
                            k);
  return 0;
}

int bs_term_self_stats(const bs_term *t, bs_self_stats *out, bs_error *err) {
  int st = need_self(t, "self-collision stats", err);
  if (st) return st;
  *out = ((const self_data *)t->data)->stats;
  return 0;
}

int bs_term_self_set_secant(bs_term *t, int on, bs_error *err) {
  int st = need_self(t, "self-collision secant model", err);
  if (st) return st;
  ((self_data *)t->data)->secant = on != 0;
  return 0;
}

void bs_term_self_reset_stats(bs_term *t) {
  if (bs_term_is_self(t)) memset(&((self_data *)t->data)->stats, 0, sizeof(bs_self_stats));
}

int bs_term_self_detect(bs_term *t, const double *x, int32_t *count, double *max_depth, bs_error *err) {
  int st = need_self(t, "self-collision detect", err);
  if (st) return st;
  self_data *d = t->data;
  if ((st = check_x(d, x, "self-collision detect", err))) return st;
  int32_t c = detect(d, x);
  if (c < 0) return bs_error_set(err, BS_EINTERNAL, "self-collision detect: a geometric query failed");
  if (count) *count = c;
  if (max_depth) *max_depth = d->stats.max_depth;
  return 0;
}

typedef struct missing_ctx {
  int64_t n, cap;
  int32_t *pairs;
  double *blocks;
} missing_ctx;

static void collect_missing(int32_t i, int32_t j, const double *B, void *ctx) {
  missing_ctx *c = ctx;
  if (c->n < c->cap) {
    c->pairs[2 * c->n] = i;
    c->pairs[2 * c->n + 1] = j;
    memcpy(c->blocks + 9 * c->n, B, 9 * sizeof(double));
  }
  c->n++;
}

int bs_term_self_missing_blocks(bs_term *t, const double *x, int64_t cap, int32_t *pairs, double *blocks,
                                int64_t *count, bs_error *err) {
  int st = need_self(t, "self-collision missing blocks", err);
  if (st) return st;
  if (cap < 0 || (cap > 0 && (!pairs || !blocks)) || !count)
    return bs_error_set(err, BS_EINPUT, "self-collision missing blocks: cap = %lld with NULL buffers or count",
                        (long long)cap);
  self_data *d = t->data;
  if ((st = check_x(d, x, "self-collision missing blocks", err))) return st;
  if (detect(d, x) < 0) return bs_error_set(err, BS_EINTERNAL, "self-collision missing blocks: a query failed");
  missing_ctx c = {0, cap, pairs, blocks};
  d->stats.missing_blocks = assemble(d, x, NULL, 0, NULL, collect_missing, &c);
  *count = c.n;
  return 0;
}

int bs_self_friction(bs_term *t, const double *x, double mu, double dt, const uint8_t *mask, double *v,
                     int32_t *n_contacts, bs_error *err) {
  int st = need_self(t, "self-collision friction", err);
  if (st) return st;
  if (!isfinite(mu) || mu < 0)
    return bs_error_set(err, BS_EINPUT, "self-collision friction: mu = %g must be finite and >= 0", mu);
  if (!isfinite(dt) || !(dt > 0))
    return bs_error_set(err, BS_EINPUT, "self-collision friction: dt = %g must be finite and > 0", dt);
  if (!v) return bs_error_set(err, BS_EINPUT, "self-collision friction: velocities are NULL");
  self_data *d = t->data;
  if ((st = check_x(d, x, "self-collision friction", err))) return st;
  if (detect(d, x) < 0) return bs_error_set(err, BS_EINTERNAL, "self-collision friction: a query failed");
  int32_t applied = 0;
  const double *mass = d->fem->mass;
  for (int32_t i = 0; i < d->n_surf && mu > 0; i++) {
    const contact *c = &d->con[i];
    if (c->nv == 0) continue;
    double y[12], g[12];
    gather(x, c, y);
    bs_self_pair_energy(c->nv, y, d->k, g, NULL);
    double f[3] = {-g[0], -g[1], -g[2]}, fn = sqrt(bs_dot3(f, f));
    if (!(fn > 0)) continue;
    double n[3] = {f[0] / fn, f[1] / fn, f[2] / fn};
    double vbar[3] = {0, 0, 0}, minv_bar = 0, minv[4];
    for (int a = 0; a <= c->nv; a++) {
      int32_t vv = c->v[a];
      minv[a] = (mask && !mask[vv]) || !(mass[vv] > 0) ? 0 : 1 / mass[vv];
      minv_bar += c->w[a] * c->w[a] * minv[a];
      for (int k = 0; k < 3; k++) vbar[k] += c->w[a] * v[3 * (size_t)vv + k];
    }
    if (!(minv_bar > 0)) continue;
    double vn = bs_dot3(vbar, n), j[3];
    for (int k = 0; k < 3; k++) j[k] = -(vbar[k] - vn * n[k]) / minv_bar;
    double jn = sqrt(bs_dot3(j, j)), lim = mu * fn * dt;
    if (!(jn > 0)) continue;
    double s = jn > lim ? lim / jn : 1;
    for (int a = 0; a <= c->nv; a++)
      for (int k = 0; k < 3; k++) v[3 * (size_t)c->v[a] + k] += c->w[a] * minv[a] * s * j[k];
    applied++;
  }
  if (n_contacts) *n_contacts = applied;
  return 0;
}

static int cmp_pair(const void *a, const void *b) {
  const int32_t *p = a, *q = b;
  if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
  return (p[1] > q[1]) - (p[1] < q[1]);
}

int bs_self_coupling_pairs(const bs_fem *fem, const double *x, double margin, int32_t **pairs, int64_t *n_pairs,
                           bs_error *err) {
  if (!fem || !pairs || !n_pairs)
    return bs_error_set(err, BS_EINPUT, "self-collision coupling pairs: fem, pairs and n_pairs must be non-NULL");
  *pairs = NULL;
  *n_pairs = 0;
  if (!isfinite(margin) || margin < 0)
    return bs_error_set(err, BS_EINPUT, "self-collision coupling pairs: margin = %g must be finite and >= 0", margin);
  const bs_mesh *m = fem->mesh;
  if (!x) x = m->x;
  if (m->n_faces < 1) return 0;
  bs_shim_tree *tree = NULL;
  int st = bs_shim_tree_create(x, m->n_vertices, m->faces, m->n_faces, &tree, err);
  if (st) return st;
  uint8_t *is_surf = bs_calloc((size_t)m->n_vertices + 1, 1, "the coupling pairs", err);
  int32_t *buf = bs_calloc((size_t)m->n_faces, sizeof(int32_t), "the coupling pairs", err);
  int64_t cap = 1024, n = 0;
  int32_t *out = malloc(sizeof(int32_t) * 2 * (size_t)cap);
  if (!is_surf || !buf || !out) st = bs_error_set(err, BS_ENOMEM, "out of memory listing coupling pairs");
  if (!st)
    for (int32_t f = 0; f < 3 * m->n_faces; f++) is_surf[m->faces[f]] = 1;
  for (int32_t pv = 0; !st && pv < m->n_vertices; pv++) {
    if (!is_surf[pv]) continue;
    const double *p = x + 3 * (size_t)pv;
    double lo[3] = {p[0] - margin, p[1] - margin, p[2] - margin}, hi[3] = {p[0] + margin, p[1] + margin, p[2] + margin};
    int64_t cnt = 0;
    if (bs_shim_tree_within(tree, lo, hi, buf, m->n_faces, &cnt) != 0) {
      st = bs_error_set(err, BS_ENUMERIC, "self-collision coupling pairs: query failed at vertex %d", (int)pv);
      break;
    }
    for (int64_t j = 0; j < cnt && !st; j++) {
      const int32_t *f = m->faces + 3 * buf[j];
      /* a triangle with no vertex near p: each of its vertices pairs with p off the pattern */
      if (near_vertex(fem->pattern, pv, f, 3) || tri_dist2(x, f, p) > margin * margin) continue;
      for (int a = 0; a < 3; a++) {
        if (n == cap) {
          int32_t *nb = realloc(out, sizeof(int32_t) * 4 * (size_t)cap);
          if (!nb) {
            st = bs_error_set(err, BS_ENOMEM, "out of memory listing coupling pairs");
            break;
          }
          out = nb;
          cap *= 2;
        }
        out[2 * n] = pv < f[a] ? pv : f[a];
        out[2 * n + 1] = pv < f[a] ? f[a] : pv;
        n++;
      }
    }
  }
  bs_shim_tree_destroy(&tree);
  free(is_surf);
  free(buf);
  if (st) {
    free(out);
    return st;
  }
  qsort(out, (size_t)n, 2 * sizeof(int32_t), cmp_pair);
  int64_t u = 0;
  for (int64_t i = 0; i < n; i++)
    if (u == 0 || out[2 * i] != out[2 * (u - 1)] || out[2 * i + 1] != out[2 * (u - 1) + 1]) {
      out[2 * u] = out[2 * i];
      out[2 * u + 1] = out[2 * i + 1];
      u++;
    }
  if (u == 0) {
    free(out);
    out = NULL;
  }
  *pairs = out;
  *n_pairs = u;
  return 0;
}
