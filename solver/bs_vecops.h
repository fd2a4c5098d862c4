/* bs_vecops.h — the minimizer over a vector spread across processes.
 *
 * bs_minimize (bs_minimize.h) works on one array of 3n doubles. When that
 * array is one process's part of a larger vector (a distributed mesh: owned
 * and ghost vertices, ghosts holding their owner's values), everything the
 * minimizer decides from must be the same on every process. A bs_vecops set
 * on the minimizer supplies the four things that are not local:
 *   dot    a.b of the whole vector (each entry counted once over the
 *          processes: ghosts left out, then summed over the processes);
 *   any    1 if flag is nonzero on some process (non-finite values, a step
 *          that moved no free dof, a count of free dofs through sum);
 *   sum    in place, the sums over the processes of v[0..n);
 *   solve  the Newton system H d = r (replaces opts.linear and the Hessian
 *          storage: the objective's hessian callback assembles the caller's
 *          own matrix, and solve uses it): d from zero to ||r - H d|| <=
 *          rel ||r||, at most max_it iterations; the same contract as CG in
 *          bs_linsolve.h (negative curvature ends it with the last iterate, r
 *          on the first; with kappa > 0 the last iterate that passed the
 *          downhill test d.r >= kappa ||d|| ||r||), statistics in *ls; 0, or a
 *          negative status with err filled.
 * With a vecops the minimizer's per-process vectors and its mask are the
 * local ones (n local vertices, ghosts included); the callbacks of the
 * objective must return consistent values (E the global energy, gradients
 * consistent on ghosts). Every process calls bs_minimize together.
 *
 * Ownership: the minimizer copies the struct; ctx is borrowed.
 */
#ifndef BS_VECOPS_H
#define BS_VECOPS_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_linsolve.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_vecops {
  double (*dot)(int64_t N, const double *a, const double *b, void *ctx);
  int (*any)(int flag, void *ctx);
  void (*sum)(double *v, int n, void *ctx);
  int (*solve)(const uint8_t *mask, const double *r, double rel, int max_it, double kappa, double *d,
               bs_lin_stats *ls, bs_error *err, void *ctx);
  void *ctx;
} bs_vecops;

typedef struct bs_minimizer bs_minimizer;

/* Sets (ops non-NULL, every callback given) or clears (NULL) the vector
 * operations of m. BS_EINPUT when a callback is missing. */
int bs_minimizer_set_vecops(bs_minimizer *m, const bs_vecops *ops, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
