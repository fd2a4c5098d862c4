/* linsolve.c — CG, block-Jacobi PCG, MINRES and CHOLMOD on 3x3 block CSR
 * matrices, restricted to the free dofs of a mask (see bs_linsolve.h).
 *
 * Masking: every work vector is kept zero on the constrained dofs (the masked
 * right-hand side is zero there and bs_bsr_mul with the mask writes zeros
 * there), so plain dot products over all 3n entries are the masked ones.
 *
 * Every inner product and norm is summed in the fixed order of bs_sum.h
 * (chunks cut by the length only), so iterates, iteration counts and exits
 * are bitwise the same with any thread count. */
#define _GNU_SOURCE /* dlsym's RTLD_DEFAULT */
#include "bs_linsolve.h"
#include "bs_sym3.h"

#include "bs_amg.h"
#include "bs_sum.h"

#include <cholmod.h>
#include <dlfcn.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct bs_linsolve {
  bs_lin_kind kind;
  int32_t n;    /* block size of the pattern                            */
  int64_t nnzb; /* stored blocks of the pattern (a cheap identity check) */
  int64_t N;    /* 3n                                                   */
  /* Krylov vectors (3n each); which ones exist depends on kind. */
  double *r, *p, *q, *z;      /* CG / PCG (z: PCG only); q also for residuals */
  double *y, *v, *w, *w1, *w2, *r2; /* MINRES (with r, q)                     */
  double *minv;               /* PCG: 9n, inverse diagonal blocks         */
  float *val32;               /* CG kinds, single precision: 9 nnzb + 4    */
  double kappa;               /* CG kinds: downhill test (0: off)          */
  double radius;              /* CG kinds: trust-region radius (0: off)    */
  double *xs;                 /* CG kinds with kappa > 0: 3n, the last
                                 iterate that passed it                    */
  bs_amg *amg;                /* AMG-PCG: the BoomerAMG V-cycle            */
  /* CHOLMOD: scalar lower-triangular CSC of the free dofs. */
  cholmod_common cm;
  int cm_started;
  int have_symbolic;
  uint8_t *cmask;   /* n: the mask the symbolic analysis was built for   */
  int32_t *fmap;    /* n: free vertex number, or -1                      */
  int32_t *fvert;   /* nfree: vertex of each free vertex number          */
  int32_t nfree;
  cholmod_sparse *C;
  cholmod_factor *L;
  cholmod_dense *B, *X, *Y, *E;
};

/* ---- names ------------------------------------------------------------ */

static const char *const kind_names[] = {"cg", "pcg", "cholmod", "minres", "amg"};

const char *bs_lin_kind_name(bs_lin_kind k) {
  if ((int)k < 0 || (int)k >= BS_LIN_KINDS) return "unknown";
  return kind_names[k];
}

int bs_lin_kind_parse(const char *name, bs_lin_kind *out, bs_error *err) {
  if (!name || !out)
    return bs_error_set(err, BS_EINPUT, "bs_lin_kind_parse: NULL argument");
  for (int k = 0; k < BS_LIN_KINDS; ++k)
    if (strcmp(name, kind_names[k]) == 0) {
      *out = (bs_lin_kind)k;
      return BS_OK;
    }
  return bs_error_set(err, BS_EINPUT,
                      "unknown linear solver \"%s\" (expected cg, pcg, amg, cholmod or minres)", name);
}

/* ---- vector kernels (OpenMP, static schedules, bs_sum.h sums) ----------- */

static double vdot(int64_t N, const double *a, const double *b) { return bs_sum_dot(N, a, b, 16384); }

/* ||r - q||^2 */
static double resid2(int64_t N, const double *r, const double *q) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(N);
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int64_t m = bs_sum_lo(P, c); m < bs_sum_hi(P, c); ++m) s += (r[m] - q[m]) * (r[m] - q[m]);
    part[c] = s;
  }
  return bs_sum_parts(P.count, part);
}

static void vcopy(int64_t N, const double *a, double *b) {
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int64_t k = 0; k < N; ++k) b[k] = a[k];
}

static void vzero(int64_t N, double *a) {
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int64_t k = 0; k < N; ++k) a[k] = 0.0;
}

/* r = b on the free dofs, 0 on the constrained ones; returns ||r||^2 and the
 * number of non-finite free entries of b in *bad. */
static double load_rhs(int32_t n, const uint8_t *mask, const double *b, double *r, int64_t *bad) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
  int64_t nb = 0;
#pragma omp parallel for schedule(static) reduction(+ : nb) if (n > 4096)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); ++i) {
      const int free_i = !mask || mask[i];
      for (int a = 0; a < 3; ++a) {
        const double bi = free_i ? b[3 * (int64_t)i + a] : 0.0;
        if (!isfinite(bi)) {
          ++nb;
          r[3 * (int64_t)i + a] = 0.0;
        } else {
          r[3 * (int64_t)i + a] = bi;
          s += bi * bi;
        }
      }
    }
    part[c] = s;
  }
  *bad = nb;
  return bs_sum_parts(P.count, part);
}

static int rhs_error(int32_t n, const uint8_t *mask, const double *b, bs_error *err) {
  for (int64_t k = 0; k < 3 * (int64_t)n; ++k)
    if ((!mask || mask[k / 3]) && !isfinite(b[k]))
      return bs_error_set(err, BS_ENUMERIC,
                          "linear solve: right-hand side entry %lld (vertex %lld, component %d) "
                          "is not finite (%g)",
                          (long long)k, (long long)(k / 3), (int)(k % 3), b[k]);
  return bs_error_set(err, BS_EINTERNAL, "linear solve: non-finite right-hand side not found");
}

/* Names the first non-finite entry of A among the free-free blocks, or
 * reports a numerical breakdown when A is finite. */
static int matrix_error(const bs_bsr *A, const uint8_t *mask, const char *what, bs_error *err) {
  for (int32_t i = 0; i < A->n; ++i) {
    if (mask && !mask[i]) continue;
    for (int32_t s = A->row_ptr[i]; s < A->row_ptr[i + 1]; ++s) {
      if (mask && !mask[A->col[s]]) continue;
      for (int e = 0; e < 9; ++e)
        if (!isfinite(A->val[9 * (int64_t)s + e]))
          return bs_error_set(err, BS_ENUMERIC,
                              "%s: matrix block (%d,%d) entry (%d,%d) is not finite (%g)", what,
                              (int)i, (int)A->col[s], e / 3, e % 3, A->val[9 * (int64_t)s + e]);
    }
  }
  return bs_error_set(err, BS_ENUMERIC,
                      "%s: numerical breakdown (a non-finite inner product with finite A and b: "
                      "overflow)",
                      what);
}

/* ---- block Jacobi ------------------------------------------------------- */

/* What block_inverse made of a block. */
typedef enum { BJ_INVERSE = 0, BJ_ABS_EIGEN = 1, BJ_IDENTITY = 2 } bj_kind;

/* Eigenvalues at or below this fraction of the largest |lambda| of a block
 * count as zero in the fallback (a constraint's projection leaves its normal's
 * eigenvalue at rounding, about 1e-16 of the others). */
#define BJ_NULL_TOL 1e-12

/* Cholesky pivots at or below this fraction of the largest diagonal entry
 * send a block to the fallback. Rounding in a nearly singular block can leave
 * a positive last pivot of up to about eps/tau of the diagonal after a pivot
 * of tau (1e-7 at most of 1e5 projected blocks P S P with random normals,
 * 5e-8 on the block of a vertex of fig12 on its torus); a tolerance above
 * sqrt(eps) rejects those, where 1e-14 inverted them into an indefinite,
 * 1e7-times-too-large preconditioner block and PCG stalled. A definite block
 * sent to the fallback still gets its exact inverse there. */
#define BJ_PIVOT_TOL 1e-6

/* The fallback of block_inverse: Q diag(1/|lambda|) Q^T over the eigenvalues
 * of S above BJ_NULL_TOL max |lambda|, the others left out (a pseudo-inverse
 * of |S|). Positive semidefinite, so PCG's preconditioner stays definite on
 * the directions it acts on; an indefinite block (contacts) keeps its scale,
 * and the normal of a vertex on a constraint obstacle (a zero row and column
 * along the normal, whose residual is zero: bs_obstacles.h) gets nothing,
 * where the identity made that vertex's preconditioned residual its stiffness
 * (1e4 to 1e6 times too large) and took PCG 26 times the iterations of plain
 * CG on fig14. Leaving the negative eigenvalues out instead keeps the
 * residual along the contacts' negative directions and costs fig14 2.5x its
 * CG iterations. Returns 0 when no eigenvalue is above the floor (a zero
 * block). */
static int abs_pseudo_inverse(const double S[9], double *Mi) {
  double lam[3], Q[9];
  bs_sym3_eig(S, lam, Q);
  const double big = fmax(fabs(lam[0]), fabs(lam[2]));
  if (!(big > 0.0) || !isfinite(big)) return 0;
  double w[3];
  for (int k = 0; k < 3; ++k) w[k] = fabs(lam[k]) > BJ_NULL_TOL * big ? 1.0 / fabs(lam[k]) : 0.0;
  bs_sym3_from_eig(w, Q, Mi);
  return 1;
}

/* Inverse of the symmetric part S of a 3x3 block D if S is positive definite
 * (Cholesky pivots above BJ_PIVOT_TOL * max diagonal); else abs_pseudo_inverse;
 * else (a zero or non-finite block) the identity. Returns which. */
static bj_kind block_inverse(const double *D, double *Mi) {
  double S[9];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) S[3 * a + b] = 0.5 * (D[3 * a + b] + D[3 * b + a]);
  const double dmax = fmax(fabs(S[0]), fmax(fabs(S[4]), fabs(S[8])));
  const double floor_ = BJ_PIVOT_TOL * dmax;
  /* Cholesky S = L L^T. */
  int spd = dmax > 0.0 && isfinite(dmax);
  double l00 = 0, l10 = 0, l20 = 0, l11 = 0, l21 = 0, l22 = 0;
  if (spd) {
    double d0 = S[0];
    spd = d0 > floor_;
    if (spd) {
      l00 = sqrt(d0);
      l10 = S[3] / l00;
      l20 = S[6] / l00;
      double d1 = S[4] - l10 * l10;
      spd = d1 > floor_;
      if (spd) {
        l11 = sqrt(d1);
        l21 = (S[7] - l20 * l10) / l11;
        double d2 = S[8] - l20 * l20 - l21 * l21;
        spd = d2 > floor_;
        if (spd) l22 = sqrt(d2);
      }
    }
  }
  if (spd) {
    /* S^-1 = L^-T L^-1 with L^-1 lower triangular. */
    const double i00 = 1.0 / l00, i11 = 1.0 / l11, i22 = 1.0 / l22;
    const double i10 = -l10 * i00 * i11;
    const double i21 = -l21 * i11 * i22;
    const double i20 = -(l20 * i00 + l21 * i10) * i22;
    /* Mi = Li^T Li, Li = [[i00,0,0],[i10,i11,0],[i20,i21,i22]]. */
    Mi[0] = i00 * i00 + i10 * i10 + i20 * i20;
    Mi[1] = i10 * i11 + i20 * i21;
    Mi[2] = i20 * i22;
    Mi[4] = i11 * i11 + i21 * i21;
    Mi[5] = i21 * i22;
    Mi[8] = i22 * i22;
    Mi[3] = Mi[1];
    Mi[6] = Mi[2];
    Mi[7] = Mi[5];
    return BJ_INVERSE;
  }
  if (isfinite(dmax) && abs_pseudo_inverse(S, Mi)) return BJ_ABS_EIGEN;
  memset(Mi, 0, 9 * sizeof *Mi);
  Mi[0] = Mi[4] = Mi[8] = 1.0;
  return BJ_IDENTITY;
}

int bs_linsolve_block_inverse(const double D[9], double Mi[9]) { return (int)block_inverse(D, Mi); }

static void build_block_jacobi(const bs_bsr *A, const uint8_t *mask, double *minv) {
  const int32_t n = A->n;
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int32_t i = 0; i < n; ++i) {
    double *Mi = minv + 9 * (int64_t)i;
    if (mask && !mask[i])
      memset(Mi, 0, 9 * sizeof *Mi);
    else
      (void)block_inverse(A->val + 9 * (int64_t)A->diag[i], Mi);
  }
}

/* z_i = M_i r_i for one vertex (M_i the 3x3 inverse block); returns r_i . z_i. */
static inline double block_jacobi_row(const double *M, double r0, double r1, double r2, double *zi) {
  const double z0 = M[0] * r0 + M[1] * r1 + M[2] * r2;
  const double z1 = M[3] * r0 + M[4] * r1 + M[5] * r2;
  const double z2 = M[6] * r0 + M[7] * r1 + M[8] * r2;
  zi[0] = z0;
  zi[1] = z1;
  zi[2] = z2;
  return r0 * z0 + r1 * z1 + r2 * z2;
}

/* z = M^-1 r; returns r . z. */
static double apply_block_jacobi(int32_t n, const double *minv, const double *r, double *z) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); ++i) {
      const double *ri = r + 3 * (int64_t)i;
      s += block_jacobi_row(minv + 9 * (int64_t)i, ri[0], ri[1], ri[2], z + 3 * (int64_t)i);
    }
    part[c] = s;
  }
  return bs_sum_parts(P.count, part);
}

/* ---- CG / PCG ----------------------------------------------------------- */

/* One pass of a CG iteration: x += alpha p, r -= alpha q; returns ||r||^2
 * and sets *xx = ||x||^2; with minv (block Jacobi) also z = M^-1 r and
 * *rz = r . z (z is wasted only on the last iteration). */
static double cg_update(int32_t n, double alpha, const double *p, const double *q, const double *minv, double *x,
                        double *r, double *z, double *xx, double *rz) {
  double part_r[BS_SUM_CHUNKS], part_x[BS_SUM_CHUNKS], part_z[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0, sx = 0.0, sz = 0.0;
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); ++i) {
      const int64_t m = 3 * (int64_t)i;
      const double x0 = x[m] + alpha * p[m], x1 = x[m + 1] + alpha * p[m + 1], x2 = x[m + 2] + alpha * p[m + 2];
      x[m] = x0;
      x[m + 1] = x1;
      x[m + 2] = x2;
      sx += x0 * x0 + x1 * x1 + x2 * x2;
      const double r0 = r[m] - alpha * q[m], r1 = r[m + 1] - alpha * q[m + 1], r2 = r[m + 2] - alpha * q[m + 2];
      r[m] = r0;
      r[m + 1] = r1;
      r[m + 2] = r2;
      s += r0 * r0 + r1 * r1 + r2 * r2;
      if (minv) sz += block_jacobi_row(minv + 9 * (int64_t)i, r0, r1, r2, z + m);
    }
    part_r[c] = s;
    part_x[c] = sx;
    part_z[c] = sz;
  }
  *xx = bs_sum_parts(P.count, part_x);
  if (minv) *rz = bs_sum_parts(P.count, part_z);
  return bs_sum_parts(P.count, part_r);
}

/* a.b and b.b in one pass (deterministic sums). */
static void dots2(int64_t N, const double *a, const double *b, double *ab, double *bb) {
  double part_ab[BS_SUM_CHUNKS], part_bb[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(N);
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0, t = 0.0;
    for (int64_t m = bs_sum_lo(P, c); m < bs_sum_hi(P, c); ++m) {
      s += a[m] * b[m];
      t += b[m] * b[m];
    }
    part_ab[c] = s;
    part_bb[c] = t;
  }
  *ab = bs_sum_parts(P.count, part_ab);
  *bb = bs_sum_parts(P.count, part_bb);
}

/* Steihaug's step to the trust-region boundary: x += s p and r -= s q (q =
 * A p) with s = shift + tau, where x_b = x + shift p is the iterate the step
 * starts from (shift = 0, or -alpha to go back from an iterate outside the
 * ball) and tau >= 0 solves ||x_b + tau p|| = radius. xx = ||x||^2 before the
 * call. Returns the new ||r||^2. */
static double to_boundary(int64_t N, double radius, double shift, double xx, const double *p, const double *q,
                          double *x, double *r) {
  double xp, pp;
  dots2(N, x, p, &xp, &pp);
  if (!(pp > 0.0)) return vdot(N, r, r);
  const double xbp = xp + shift * pp, xbb = xx + 2.0 * shift * xp + shift * shift * pp;
  const double disc = fmax(xbp * xbp + pp * (radius * radius - xbb), 0.0);
  const double tau = fmax((-xbp + sqrt(disc)) / pp, 0.0), s = shift + tau;
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(N);
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int c = 0; c < P.count; ++c) {
    double t = 0.0;
    for (int64_t m = bs_sum_lo(P, c); m < bs_sum_hi(P, c); ++m) {
      x[m] += s * p[m];
      r[m] -= s * q[m];
      t += r[m] * r[m];
    }
    part[c] = t;
  }
  return bs_sum_parts(P.count, part);
}

/* run_cg's answer when the single-precision values overflowed (a value beyond
 * FLT_MAX): the caller solves again in double. Positive, so never a bs status. */
#define BS_RETRY_DOUBLE 1
/* With single-precision values, the iteration whose product makes the copy:
 * products before it read the double values. A product in single saves about
 * a third of one in double on a large matrix and the copying one costs about
 * one more (bench_kernels), so the copy pays after 3 more iterations. */
#define SINGLE_FROM 4

/* run_cg's preconditioner (by bs_lin_kind: cg, pcg, amg). */
typedef enum {
  PC_NONE = 0,         /* plain CG                                     */
  PC_BLOCK_JACOBI = 1, /* the 3x3 block Jacobi of block_inverse (pcg)  */
  PC_AMG = 2           /* one BoomerAMG V-cycle, set up beforehand    */
} pc_kind;

/* Conjugate gradient from x = 0 (Hestenes–Stiefel), optionally preconditioned
 * (pc_kind). Stops on ||r|| <= rel_tol ||b||, max_iter, or
 * p^T A p <= 0 (negative curvature: the last iterate, or b on the first
 * iteration, is returned with indefinite = 1). With ls->radius > 0 (Steihaug
 * 1983; Nocedal & Wright, Algorithm 7.2) negative curvature and an iterate
 * leaving the ball ||x|| <= radius both end on its boundary along p
 * (boundary = 1). With ls->kappa > 0, an answer
 * that fails the downhill test b.x >= kappa ||b|| ||x|| is replaced by the
 * last iterate that passed it (kept in ls->xs; stats.downhill_iterate). */
static int run_cg(bs_linsolve *ls, const bs_bsr *A, const uint8_t *mask, const double *b,
                  double rel_tol, int max_iter, pc_kind precond, int single, double *x, bs_lin_stats *st,
                  bs_error *err) {
  const int32_t n = ls->n;
  const int64_t N = ls->N;
  double *r = ls->r, *p = ls->p, *q = ls->q, *z = precond != PC_NONE ? ls->z : ls->r;
  int64_t bad = 0;
  double rr = load_rhs(n, mask, b, r, &bad);
  if (bad) return rhs_error(n, mask, b, err);
  vzero(N, x);
  const double bnorm = sqrt(rr);
  if (bnorm == 0.0) {
    st->converged = 1;
    return BS_OK;
  }
  double rz = rr;
  int rc;
  if (precond == PC_BLOCK_JACOBI) {
    build_block_jacobi(A, mask, ls->minv);
    rz = apply_block_jacobi(n, ls->minv, r, z);
  } else if (precond == PC_AMG && (rc = bs_amg_apply(ls->amg, r, z, &rz, err))) {
    return rc;
  }
  const char *name = precond == PC_AMG ? "amg-pcg" : precond == PC_BLOCK_JACOBI ? "pcg" : "cg";
  if (precond == PC_AMG && !(rz > 0.0)) { /* B not SPD: return the right-hand side */
    if (!isfinite(rz)) return matrix_error(A, mask, name, err);
    st->precond_failed = 1;
    vcopy(N, r, x);
    bs_bsr_mul(A, mask, x, q);
    st->rel_residual = sqrt(resid2(N, r, q)) / bnorm;
    return BS_OK;
  }
  vcopy(N, z, p);
  const double target = rel_tol * bnorm;
  /* Downhill bookkeeping: b.x by the PCG identity b.p_k = r_k.z_k (so
     b.x_{k+1} = b.x_k + alpha_k r_k.z_k), ||x||^2 summed in the update pass;
     last_ok is the last iterate that passed (0: none), and ls->xs holds it
     once a later iterate has failed (xs_rr: its ||r||^2). */
  const double kappa2 = ls->kappa * ls->kappa * rr;
  double bx = 0.0, xs_rr = rr, xnorm2 = 0.0;
  int last_ok = 0, xs_holds = 0;
  for (int k = 0; k < max_iter; ++k) {
    /* single: product SINGLE_FROM, in double, rounds the values into val32 on
       its way (it costs about two products: a solve that ends before it never
       pays for it); the later ones read val32 (see bs_linsolve_set_single) */
    const double pq = !single || k < SINGLE_FROM ? bs_bsr_mul_dot(A, mask, p, q)
                      : k == SINGLE_FROM         ? bs_bsr_mul_dot_round32(A, mask, p, q, ls->val32)
                                                 : bs_bsr_mul_dot32(A, ls->val32, mask, p, q);
    if (!isfinite(pq)) return single && k > SINGLE_FROM ? BS_RETRY_DOUBLE : matrix_error(A, mask, name, err);
    if (pq <= 0.0) {
      st->indefinite = 1;
      if (ls->radius > 0.0) { /* Steihaug: along p to the boundary */
        rr = to_boundary(N, ls->radius, 0.0, xnorm2, p, q, x, r);
        st->boundary = 1;
      } else if (k == 0) {
        /* No iterate yet: return the right-hand side (r still holds masked b). */
        vcopy(N, r, x);
        bs_bsr_mul(A, mask, x, q);
        rr = resid2(N, r, q);
      }
      break;
    }
    const double alpha = rz / pq;
    double rz_new = 0.0, xx = 0.0;
    const double rr_k = rr;
    rr = cg_update(n, alpha, p, q, precond == PC_BLOCK_JACOBI ? ls->minv : NULL, x, r, z, &xx, &rz_new);
    st->iterations = k + 1;
    if (!isfinite(rr)) return matrix_error(A, mask, name, err);
    if (ls->radius > 0.0 && xx >= ls->radius * ls->radius) { /* Steihaug: back to the boundary */
      rr = to_boundary(N, ls->radius, -alpha, xx, p, q, x, r);
      st->boundary = 1;
      break;
    }
    xnorm2 = xx;
    bx += alpha * rz;
    if (kappa2 > 0.0) {
      if (bx > 0.0 && bx * bx >= kappa2 * xx) {
        last_ok = k + 1;
      } else if (last_ok == k && k > 0) { /* x_k passed, x_{k+1} fails: keep x_k */
        double *xs = ls->xs;
#pragma omp parallel for schedule(static) if (N > 16384)
        for (int64_t m = 0; m < N; ++m) xs[m] = x[m] - alpha * p[m];
        xs_rr = rr_k;
        xs_holds = 1;
      }
    }
    if (sqrt(rr) <= target) {
      st->converged = 1;
      break;
    }
    if (precond == PC_NONE) rz_new = rr;
    else if (precond == PC_AMG && (rc = bs_amg_apply(ls->amg, r, z, &rz_new, err))) return rc;
    if (precond == PC_AMG && !(rz_new > 0.0)) { /* B not SPD (built from an indefinite matrix?) */
      if (!isfinite(rz_new)) return matrix_error(A, mask, name, err);
      st->precond_failed = 1;
      break;
    }
    const double beta = rz_new / rz;
    rz = rz_new;
#pragma omp parallel for schedule(static) if (N > 16384)
    for (int64_t m = 0; m < N; ++m) p[m] = z[m] + beta * p[m];
  }
  /* The answer is x_{iterations} (b itself after an indefinite first
     iteration, which passes). */
  if (kappa2 > 0.0 && !st->boundary && st->iterations > 0 && last_ok != st->iterations && xs_holds) {
    vcopy(N, ls->xs, x);
    rr = xs_rr;
    st->downhill_iterate = last_ok;
  }
  st->rel_residual = sqrt(rr) / bnorm;
  return BS_OK;
}

/* ---- MINRES --------------------------------------------------------------- */

/* y -= f r; returns ||y||^2. */
static double sub_norm2(int64_t N, double f, const double *r, double *y) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(N);
#pragma omp parallel for schedule(static) if (N > 16384)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int64_t m = bs_sum_lo(P, c); m < bs_sum_hi(P, c); ++m) {
      y[m] -= f * r[m];
      s += y[m] * y[m];
    }
    part[c] = s;
  }
  return bs_sum_parts(P.count, part);
}

/* r = b - y on the free dofs, 0 on the constrained ones; returns ||r||^2. */
static double masked_residual(int32_t n, const uint8_t *mask, const double *b, const double *y, double *r) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int32_t i = (int32_t)bs_sum_lo(P, c); i < (int32_t)bs_sum_hi(P, c); ++i)
      for (int a = 0; a < 3; ++a) {
        const int64_t m = 3 * (int64_t)i + a;
        const double ri = (!mask || mask[i]) ? b[m] - y[m] : 0.0;
        r[m] = ri;
        s += ri * ri;
      }
    part[c] = s;
  }
  return bs_sum_parts(P.count, part);
}

/* MINRES of Paige and Saunders (1975) for symmetric A, following the
 * reference implementation's recurrences: Lanczos vectors v_k, a QR
 * factorization of the tridiagonal by Givens rotations (cs, sn), and the
 * update x += phi w. phibar is the residual norm in exact arithmetic; when it
 * meets the target the true residual is computed and, if rounding left it above
 * the target, MINRES restarts on it (at most 4 times, counted in max_iter). */
static int run_minres(bs_linsolve *ls, const bs_bsr *A, const uint8_t *mask, const double *b,
                      double rel_tol, int max_iter, double *x, bs_lin_stats *st, bs_error *err) {
  const int32_t n = ls->n;
  const int64_t N = ls->N;
  double *r1 = ls->r, *r2 = ls->r2, *y = ls->y, *v = ls->v, *w = ls->w, *w1 = ls->w1,
         *w2 = ls->w2;
  int64_t bad = 0;
  const double bb = load_rhs(n, mask, b, r1, &bad);
  if (bad) return rhs_error(n, mask, b, err);
  vzero(N, x);
  const double bnorm = sqrt(bb);
  if (bnorm == 0.0) {
    st->converged = 1;
    return BS_OK;
  }
  const double target = rel_tol * bnorm;
  double rnorm = bnorm, prev_rnorm = INFINITY;
  int its = 0;
  for (int restart = 0;; ++restart) {
    /* r1 holds the true residual b - A x, masked; rnorm its norm. */
    if (rnorm <= target) {
      st->converged = 1;
      break;
    }
    if (its >= max_iter || restart > 4 || !(rnorm < prev_rnorm)) break;
    prev_rnorm = rnorm;
    const double beta1 = rnorm;
    vcopy(N, r1, r2); /* r2: the current Lanczos vector times beta */
    vzero(N, w);
    vzero(N, w2);
    double oldb = 0.0, beta = beta1, dbar = 0.0, epsln = 0.0, phibar = beta1, cs = -1.0,
           sn = 0.0;
    int first = 1;
    while (its < max_iter) {
      ++its;
      const double sc = 1.0 / beta;
#pragma omp parallel for schedule(static) if (N > 16384)
      for (int64_t m = 0; m < N; ++m) v[m] = sc * r2[m];
      bs_bsr_mul(A, mask, v, y);
      if (!first) {
        const double f = beta / oldb;
#pragma omp parallel for schedule(static) if (N > 16384)
        for (int64_t m = 0; m < N; ++m) y[m] -= f * r1[m];
      }
      first = 0;
      const double alfa = vdot(N, v, y);
      if (!isfinite(alfa)) return matrix_error(A, mask, "minres", err);
      const double s = sub_norm2(N, alfa / beta, r2, y);
      /* r1 <- r2, r2 <- y; the old r1 becomes the next y buffer. */
      double *t = r1;
      r1 = r2;
      r2 = y;
      y = t;
      oldb = beta;
      beta = sqrt(s);
      if (!isfinite(beta)) return matrix_error(A, mask, "minres", err);
      /* Apply the previous rotation, then compute and apply the next one. */
      const double oldeps = epsln;
      const double delta = cs * dbar + sn * alfa;
      const double gbar = sn * dbar - cs * alfa;
      epsln = sn * beta;
      dbar = -cs * beta;
      double gamma = hypot(gbar, beta);
      if (gamma < DBL_MIN) gamma = DBL_MIN;
      cs = gbar / gamma;
      sn = beta / gamma;
      const double phi = cs * phibar;
      phibar = sn * phibar;
      /* w1 <- w2, w2 <- w, w <- (v - oldeps w1 - delta w2) / gamma; x += phi w. */
      t = w1;
      w1 = w2;
      w2 = w;
      w = t;
      const double ig = 1.0 / gamma;
#pragma omp parallel for schedule(static) if (N > 16384)
      for (int64_t m = 0; m < N; ++m) {
        w[m] = (v[m] - oldeps * w1[m] - delta * w2[m]) * ig;
        x[m] += phi * w[m];
      }
      if (phibar <= target || beta == 0.0) break;
    }
    /* True residual into r1. */
    bs_bsr_mul(A, mask, x, y);
    rnorm = sqrt(masked_residual(n, mask, b, y, r1));
    if (!isfinite(rnorm)) return matrix_error(A, mask, "minres", err);
  }
  st->iterations = its;
  st->rel_residual = rnorm / bnorm;
  return BS_OK;
}

/* ---- CHOLMOD ------------------------------------------------------------ */

static int cholmod_status_error(bs_linsolve *ls, const char *what, bs_error *err) {
  const int s = ls->cm.status;
  if (s == CHOLMOD_OUT_OF_MEMORY)
    return bs_error_set(err, BS_ENOMEM, "cholmod: %s: out of memory", what);
  return bs_error_set(err, BS_EINTERNAL, "cholmod: %s failed (CHOLMOD status %d)", what, s);
}

static void chol_free_symbolic(bs_linsolve *ls) {
  if (!ls->cm_started) return;
  cholmod_free_factor(&ls->L, &ls->cm);
  cholmod_free_sparse(&ls->C, &ls->cm);
  cholmod_free_dense(&ls->B, &ls->cm);
  cholmod_free_dense(&ls->X, &ls->cm);
  cholmod_free_dense(&ls->Y, &ls->cm);
  cholmod_free_dense(&ls->E, &ls->cm);
  ls->have_symbolic = 0;
}

/* Scalar lower-triangular CSC pattern of A on the free dofs. Column J = 3 f(j)
 * + b holds rows I = 3 f(i) + a >= J; by symmetry A(I,J) = A(J,I) = entry (b,a)
 * of block (j,i), so column J is read from block row j, columns i >= j. Free
 * vertices keep their order, so the rows come out sorted. Then the symbolic
 * analysis (fill-reducing ordering, supernodes). */
static int chol_setup(bs_linsolve *ls, const bs_bsr *A, const uint8_t *mask, bs_error *err) {
  chol_free_symbolic(ls);
  const int32_t n = A->n;
  int32_t nf = 0;
  for (int32_t i = 0; i < n; ++i) {
    const int free_i = !mask || mask[i];
    ls->cmask[i] = (uint8_t)free_i;
    ls->fmap[i] = free_i ? nf : -1;
    if (free_i) ls->fvert[nf++] = i;
  }
  ls->nfree = nf;
  int64_t nnz = 0;
  for (int32_t f = 0; f < nf; ++f) {
    const int32_t j = ls->fvert[f];
    for (int32_t s = A->diag[j]; s < A->row_ptr[j + 1]; ++s)
      if (ls->fmap[A->col[s]] >= 0) nnz += A->col[s] == j ? 6 : 9;
  }
  if (nnz > INT32_MAX - 1 || 3 * (int64_t)nf > INT32_MAX)
    return bs_error_set(err, BS_EINPUT,
                        "cholmod: %lld scalar nonzeros exceed the int32 CHOLMOD interface",
                        (long long)nnz);
  const size_t Nf = 3 * (size_t)nf;
  ls->C = cholmod_allocate_sparse(Nf, Nf, (size_t)(nnz > 0 ? nnz : 1), 1, 1, -1, CHOLMOD_REAL,
                                  &ls->cm);
  ls->B = cholmod_allocate_dense(Nf, 1, Nf, CHOLMOD_REAL, &ls->cm);
  if (!ls->C || !ls->B) return cholmod_status_error(ls, "allocation", err);
  int *Cp = ls->C->p, *Ci = ls->C->i;
  int k = 0;
  for (int32_t f = 0; f < nf; ++f) {
    const int32_t j = ls->fvert[f];
    for (int bcol = 0; bcol < 3; ++bcol) {
      Cp[3 * f + bcol] = k;
      for (int32_t s = A->diag[j]; s < A->row_ptr[j + 1]; ++s) {
        const int32_t fi = ls->fmap[A->col[s]];
        if (fi < 0) continue;
        for (int a = (A->col[s] == j ? bcol : 0); a < 3; ++a) Ci[k++] = 3 * fi + a;
      }
    }
  }
  Cp[Nf] = k;
  ls->L = cholmod_analyze(ls->C, &ls->cm);
  if (!ls->L) return cholmod_status_error(ls, "symbolic analysis", err);
  ls->have_symbolic = 1;
  return BS_OK;
}

/* Copies the values of A into the CSC (same traversal as chol_setup);
 * returns the number of non-finite entries met. */
static int64_t chol_copy_values(bs_linsolve *ls, const bs_bsr *A) {
  const int *Cp = ls->C->p;
  double *Cx = ls->C->x;
  int64_t bad = 0;
  const int32_t nf = ls->nfree;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (nf > 4096)
  for (int32_t f = 0; f < nf; ++f) {
    const int32_t j = ls->fvert[f];
    for (int bcol = 0; bcol < 3; ++bcol) {
      int k = Cp[3 * f + bcol];
      for (int32_t s = A->diag[j]; s < A->row_ptr[j + 1]; ++s) {
        if (ls->fmap[A->col[s]] < 0) continue;
        const double *blk = A->val + 9 * (int64_t)s;
        for (int a = (A->col[s] == j ? bcol : 0); a < 3; ++a) {
          const double vv = blk[3 * bcol + a];
          if (!isfinite(vv)) ++bad;
          Cx[k++] = vv;
        }
      }
    }
  }
  return bad;
}

static int run_cholmod(bs_linsolve *ls, const bs_bsr *A, const uint8_t *mask, const double *b,
                       double *x, bs_lin_stats *st, bs_error *err) {
  const int32_t n = ls->n;
  const int64_t N = ls->N;
  int64_t bad = 0;
  const double bb = load_rhs(n, mask, b, ls->r, &bad);
  if (bad) return rhs_error(n, mask, b, err);
  /* The symbolic analysis is tied to the mask: redo it if the mask changed. */
  int same = ls->have_symbolic;
  for (int32_t i = 0; same && i < n; ++i)
    if (ls->cmask[i] != (uint8_t)(!mask || mask[i])) same = 0;
  if (!same) {
    int rc = chol_setup(ls, A, mask, err);
    if (rc) return rc;
  }
  if (chol_copy_values(ls, A)) return matrix_error(A, mask, "cholmod", err);
  const double bnorm = sqrt(bb);
  if (bnorm == 0.0) {
    vzero(N, x);
    st->converged = 1;
    return BS_OK;
  }
  if (ls->nfree == 0) { /* unreachable: b != 0 needs a free dof */
    vzero(N, x);
    st->converged = 1;
    return BS_OK;
  }
  ls->cm.status = CHOLMOD_OK;
  const int ok = cholmod_factorize(ls->C, ls->L, &ls->cm);
  if (ls->cm.status == CHOLMOD_NOT_POSDEF || (ok && ls->L->minor < ls->L->n)) {
    st->not_pd = 1;
    return BS_OK; /* x untouched: the caller falls back to CG */
  }
  if (!ok || ls->cm.status < CHOLMOD_OK) return cholmod_status_error(ls, "factorization", err);
  double *Bx = ls->B->x;
  for (int32_t f = 0; f < ls->nfree; ++f)
    for (int a = 0; a < 3; ++a) Bx[3 * f + a] = ls->r[3 * (int64_t)ls->fvert[f] + a];
  if (!cholmod_solve2(CHOLMOD_A, ls->L, ls->B, NULL, &ls->X, NULL, &ls->Y, &ls->E, &ls->cm))
    return cholmod_status_error(ls, "solve", err);
  const double *Xx = ls->X->x;
  vzero(N, x);
  for (int32_t f = 0; f < ls->nfree; ++f)
    for (int a = 0; a < 3; ++a) x[3 * (int64_t)ls->fvert[f] + a] = Xx[3 * f + a];
  /* Residual of the direct solve (one product). */
  bs_bsr_mul(A, mask, x, ls->q);
  st->rel_residual = sqrt(resid2(N, ls->r, ls->q)) / bnorm;
  if (!isfinite(st->rel_residual))
    return bs_error_set(err, BS_ENUMERIC, "cholmod: non-finite solution (A nearly singular?)");
  st->converged = 1;
  return BS_OK;
}

/* OpenBLAS (the usual BLAS under CHOLMOD on Debian) splits some kernels of
 * the supernodal factorization by its own thread count (OPENBLAS_NUM_THREADS,
 * else OMP_NUM_THREADS at load), which changes the factor's last bits (seen:
 * 2e-16 m in x, 5e-15 m/s in v after one frame of a 16^3 box with 1 and 2
 * BLAS threads). So CHOLMOD runs with one BLAS thread, and the count is put
 * back afterwards. Found by name at run time (no link dependency): a BLAS
 * without these entries is left alone. Returns the count to restore (0:
 * nothing to restore). */
typedef int (*blas_get_fn)(void);
typedef void (*blas_set_fn)(int);

static blas_set_fn blas_setter(void) {
  blas_set_fn set = NULL;
  *(void **)(&set) = dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
  return set;
}

static int blas_one_thread(void) {
  blas_get_fn get = NULL;
  *(void **)(&get) = dlsym(RTLD_DEFAULT, "openblas_get_num_threads");
  blas_set_fn set = blas_setter();
  if (!get || !set) return 0;
  const int n = get();
  if (n <= 1) return 0;
  set(1);
  return n;
}

static void blas_restore_threads(int n) {
  blas_set_fn set = n > 1 ? blas_setter() : NULL;
  if (set) set(n);
}

/* ---- create / destroy / solve ------------------------------------------ */

void bs_linsolve_destroy(bs_linsolve **lsp) {
  if (!lsp || !*lsp) return;
  bs_linsolve *ls = *lsp;
  if (ls->cm_started) {
    chol_free_symbolic(ls);
    cholmod_finish(&ls->cm);
  }
  free(ls->r);
  free(ls->p);
  free(ls->q);
  free(ls->z);
  free(ls->y);
  free(ls->v);
  free(ls->w);
  free(ls->w1);
  free(ls->w2);
  free(ls->r2);
  free(ls->minv);
  free(ls->val32);
  free(ls->xs);
  bs_amg_destroy(&ls->amg);
  free(ls->cmask);
  free(ls->fmap);
  free(ls->fvert);
  free(ls);
  *lsp = NULL;
}

int bs_linsolve_create(const bs_bsr *pattern, bs_lin_kind kind, bs_linsolve **out,
                       bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_linsolve_create: out is NULL");
  *out = NULL;
  if (!pattern) return bs_error_set(err, BS_EINPUT, "bs_linsolve_create: pattern is NULL");
  if ((int)kind < 0 || (int)kind >= BS_LIN_KINDS)
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_create: unknown solver kind %d", (int)kind);
  bs_linsolve *ls = bs_calloc(1, sizeof *ls, "bs_linsolve", err);
  if (!ls) return BS_ENOMEM;
  ls->kind = kind;
  ls->n = pattern->n;
  ls->nnzb = pattern->nnzb;
  ls->N = 3 * (int64_t)pattern->n;
  const size_t N = ls->N > 0 ? (size_t)ls->N : 1, n = pattern->n > 0 ? (size_t)pattern->n : 1;
  int ok = 1;
#define BS_ALLOC(ptr, count, what)                              \
  do {                                                          \
    (ptr) = bs_calloc((count), sizeof *(ptr), (what), err);     \
    ok = ok && (ptr) != NULL;                                   \
  } while (0)
  BS_ALLOC(ls->r, N, "linsolve residual");
  BS_ALLOC(ls->q, N, "linsolve product");
  switch (kind) {
  case BS_LIN_AMG:
  case BS_LIN_PCG:
    BS_ALLOC(ls->z, N, "pcg preconditioned residual");
    if (kind == BS_LIN_PCG) BS_ALLOC(ls->minv, 9 * n, "pcg block Jacobi");
    else if (ok && bs_amg_create(&ls->amg, err)) ok = 0;
    /* fall through */
  case BS_LIN_CG:
    BS_ALLOC(ls->p, N, "cg direction");
    break;
  case BS_LIN_MINRES:
    BS_ALLOC(ls->y, N, "minres vector");
    BS_ALLOC(ls->v, N, "minres vector");
    BS_ALLOC(ls->w, N, "minres vector");
    BS_ALLOC(ls->w1, N, "minres vector");
    BS_ALLOC(ls->w2, N, "minres vector");
    BS_ALLOC(ls->r2, N, "minres vector");
    break;
  case BS_LIN_CHOLMOD:
    BS_ALLOC(ls->cmask, n, "cholmod mask");
    BS_ALLOC(ls->fmap, n, "cholmod free map");
    BS_ALLOC(ls->fvert, n, "cholmod free vertices");
    if (ok) {
      cholmod_start(&ls->cm);
      ls->cm_started = 1;
      ls->cm.print = 0;            /* a library never prints */
      ls->cm.error_handler = NULL;
      ls->cm.supernodal = CHOLMOD_SUPERNODAL;
      ls->cm.quick_return_if_not_posdef = 1;
    }
    break;
  }
#undef BS_ALLOC
  if (!ok) {
    bs_linsolve_destroy(&ls);
    return BS_ENOMEM;
  }
  *out = ls;
  return BS_OK;
}

int bs_linsolve_solve(bs_linsolve *ls, const bs_bsr *A, const uint8_t *mask, const double *b,
                      double rel_tol, int max_iter, double *x, bs_lin_stats *st, bs_error *err) {
  bs_lin_stats local;
  if (!st) st = &local;
  memset(st, 0, sizeof *st);
  const double t0 = bs_seconds();
  if (!ls || !A || !b || !x)
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_solve: NULL argument");
  if (A->n != ls->n || A->nnzb != ls->nnzb)
    return bs_error_set(err, BS_EINPUT,
                        "bs_linsolve_solve: matrix (n = %d, %lld blocks) does not match the "
                        "workspace pattern (n = %d, %lld blocks)",
                        (int)A->n, (long long)A->nnzb, (int)ls->n, (long long)ls->nnzb);
  if (!(rel_tol >= 0.0))
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_solve: rel_tol = %g must be >= 0", rel_tol);
  if (max_iter <= 0) max_iter = ls->N > INT32_MAX ? INT32_MAX : (int)(ls->N > 0 ? ls->N : 1);
  int rc = BS_OK;
  switch (ls->kind) {
  case BS_LIN_CG:
  case BS_LIN_PCG:
  case BS_LIN_AMG: {
    const pc_kind precond = ls->kind == BS_LIN_CG ? PC_NONE : ls->kind == BS_LIN_PCG ? PC_BLOCK_JACOBI : PC_AMG;
    /* No hierarchy for this mask yet: build it from A itself (A must be SPD). */
    if (precond == PC_AMG && !bs_amg_same_mask(ls->amg, ls->n, mask)) rc = bs_linsolve_amg_setup(ls, A, mask, err);
    if (rc == BS_OK) rc = run_cg(ls, A, mask, b, rel_tol, max_iter, precond, ls->val32 != NULL, x, st, err);
    if (rc == BS_RETRY_DOUBLE) {
      memset(st, 0, sizeof *st);
      st->single_overflow = 1;
      rc = run_cg(ls, A, mask, b, rel_tol, max_iter, precond, 0, x, st, err);
    }
    break;
  }
  case BS_LIN_MINRES:
    rc = run_minres(ls, A, mask, b, rel_tol, max_iter, x, st, err);
    break;
  case BS_LIN_CHOLMOD: {
    const int blas_threads = blas_one_thread();
    rc = run_cholmod(ls, A, mask, b, x, st, err);
    blas_restore_threads(blas_threads);
    break;
  }
  }
  st->seconds = bs_seconds() - t0;
  return rc;
}

int bs_linsolve_set_downhill(bs_linsolve *ls, double kappa, bs_error *err) {
  if (!ls) return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_downhill: NULL workspace");
  if (!(kappa >= 0.0 && kappa < 1.0))
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_downhill: kappa must be in [0, 1), got %g", kappa);
  if (kappa == 0.0) {
    free(ls->xs);
    ls->xs = NULL;
    ls->kappa = 0.0;
    return BS_OK;
  }
  if (ls->kind != BS_LIN_CG && ls->kind != BS_LIN_PCG && ls->kind != BS_LIN_AMG)
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_downhill: the workspace is for %s, not cg, pcg or amg",
                        bs_lin_kind_name(ls->kind));
  if (!ls->xs && !(ls->xs = bs_calloc((size_t)(ls->N > 0 ? ls->N : 1), sizeof *ls->xs, "linsolve downhill iterate", err)))
    return BS_ENOMEM;
  ls->kappa = kappa;
  return BS_OK;
}

int bs_linsolve_set_radius(bs_linsolve *ls, double radius, bs_error *err) {
  if (!ls) return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_radius: NULL workspace");
  if (!(radius >= 0.0) || isinf(radius))
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_radius: radius must be finite and >= 0, got %g", radius);
  if (radius > 0.0 && ls->kind != BS_LIN_CG && ls->kind != BS_LIN_PCG && ls->kind != BS_LIN_AMG)
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_radius: the workspace is for %s, not cg, pcg or amg",
                        bs_lin_kind_name(ls->kind));
  ls->radius = radius;
  return BS_OK;
}

int bs_linsolve_set_single(bs_linsolve *ls, int on, bs_error *err) {
  if (!ls) return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_single: NULL workspace");
  if (!on) {
    free(ls->val32);
    ls->val32 = NULL;
    return BS_OK;
  }
  if (ls->kind != BS_LIN_CG && ls->kind != BS_LIN_PCG && ls->kind != BS_LIN_AMG)
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_set_single: the workspace is for %s, not cg, pcg or amg",
                        bs_lin_kind_name(ls->kind));
  if (ls->val32) return BS_OK;
  ls->val32 = bs_calloc(9 * (size_t)ls->nnzb + 4, sizeof *ls->val32,
                        "linsolve single-precision values", err);
  return ls->val32 ? BS_OK : BS_ENOMEM;
}

int bs_linsolve_amg_setup(bs_linsolve *ls, const bs_bsr *P, const uint8_t *mask, bs_error *err) {
  if (!ls || !P) return bs_error_set(err, BS_EINPUT, "bs_linsolve_amg_setup: NULL argument");
  if (ls->kind != BS_LIN_AMG)
    return bs_error_set(err, BS_EINPUT, "bs_linsolve_amg_setup: the workspace is for %s, not amg",
                        bs_lin_kind_name(ls->kind));
  if (P->n != ls->n)
    return bs_error_set(err, BS_EINPUT,
                        "bs_linsolve_amg_setup: matrix has n = %d vertices, the workspace %d",
                        (int)P->n, (int)ls->n);
  return bs_amg_setup(ls->amg, P, mask, err);
}

int bs_linsolve_amg_ready(const bs_linsolve *ls, const uint8_t *mask) {
  return ls && ls->kind == BS_LIN_AMG && bs_amg_same_mask(ls->amg, ls->n, mask);
}

void bs_linsolve_amg_info(const bs_linsolve *ls, bs_amg_info *info) {
  bs_amg_get_info(ls && ls->kind == BS_LIN_AMG ? ls->amg : NULL, info);
}
