/* bs_sum.h — floating-point sums whose bits do not depend on the number of
 * threads: dot products, norms, energies summed over vertices or tets.
 *
 * Why: an OpenMP reduction(+) adds one partial sum per thread, so the
 * association of the additions (and the last bits of the result) changes
 * with the thread count, and the serial branch of an `if (n > threshold)`
 * clause adds in yet another order. A dot product that differs in its last
 * bit changes a CG iteration count, a line-search step, then the state.
 *
 * The scheme: the index range [0, n) is cut into at most BS_SUM_CHUNKS
 * chunks of at least BS_SUM_MIN_LEN indices; the cut depends on n only
 * (never on the thread count). Each chunk is summed serially in index order
 * (the chunks in parallel, any schedule), each chunk sum goes to its own slot
 * of a partial array, and the slots are added serially in chunk order
 * (bs_sum_parts). The result is the same bit for bit with 1 or N threads, in
 * the serial branch of an `if` clause as in the parallel one, and whether or
 * not the file is compiled with OpenMP. Several sums fused in one loop use one
 * partial array each. Counts (integers) and min/max are exact in any order and
 * need none of this.
 *
 * Cost: a chunk is at least BS_SUM_MIN_LEN long, so the serial sum of the
 * slots is at most 1/BS_SUM_MIN_LEN of the work; with up to BS_SUM_CHUNKS
 * chunks a static schedule stays balanced on many threads.
 *
 * Use (the partial array lives on the caller's stack, BS_SUM_CHUNKS doubles):
 *
 *   double part[BS_SUM_CHUNKS];
 *   const bs_sum_plan P = bs_sum_plan_of(n);
 *   #pragma omp parallel for schedule(static) if (n > 16384)
 *   for (int c = 0; c < P.count; ++c) {
 *     double s = 0.0;
 *     for (int64_t i = bs_sum_lo(P, c); i < bs_sum_hi(P, c); ++i) s += a[i] * b[i];
 *     part[c] = s;
 *   }
 *   return bs_sum_parts(P.count, part);
 *
 * (bs_sum_dot is exactly that.) Nothing allocates, prints or fails.
 */
#ifndef BS_SUM_H
#define BS_SUM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define BS_SUM_CHUNKS 1024 /* most chunks of a range (the partial array's size) */
#define BS_SUM_MIN_LEN 64  /* fewest indices of a chunk (the last one may be shorter) */

/* The cut of [0, n): count chunks of len indices, the last one shorter. */
typedef struct bs_sum_plan {
  int64_t n;   /* indices in the range (>= 0)              */
  int64_t len; /* indices per chunk                          */
  int count;   /* chunks, 0 when n = 0, <= BS_SUM_CHUNKS    */
} bs_sum_plan;

static inline bs_sum_plan bs_sum_plan_of(int64_t n) {
  bs_sum_plan p;
  p.n = n > 0 ? n : 0;
  const int64_t even = (p.n + BS_SUM_CHUNKS - 1) / BS_SUM_CHUNKS;
  p.len = even > BS_SUM_MIN_LEN ? even : BS_SUM_MIN_LEN;
  p.count = (int)((p.n + p.len - 1) / p.len);
  return p;
}

/* First and one-past-last index of chunk c (0 <= c < p.count). */
static inline int64_t bs_sum_lo(bs_sum_plan p, int c) { return (int64_t)c * p.len; }
static inline int64_t bs_sum_hi(bs_sum_plan p, int c) {
  const int64_t h = ((int64_t)c + 1) * p.len;
  return h < p.n ? h : p.n;
}

/* part[0] + part[1] + ... + part[count - 1], left to right (0 when count = 0). */
static inline double bs_sum_parts(int count, const double *part) {
  double s = 0.0;
  for (int c = 0; c < count; ++c) s += part[c];
  return s;
}

/* a . b over n entries, in the fixed order above; parallel when n > par_min
 * (and the including file is compiled with OpenMP). */
static inline double bs_sum_dot(int64_t n, const double *a, const double *b, int64_t par_min) {
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(n);
#ifdef _OPENMP /* (a file compiled without OpenMP gets the same bits, serially) */
#pragma omp parallel for schedule(static) if (n > par_min)
#else
  (void)par_min;
#endif
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int64_t i = bs_sum_lo(P, c); i < bs_sum_hi(P, c); ++i) s += a[i] * b[i];
    part[c] = s;
  }
  return bs_sum_parts(P.count, part);
}

#ifdef __cplusplus
}
#endif
#endif
