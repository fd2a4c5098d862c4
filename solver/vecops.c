/* vecops.c — the minimizer's reductions, local or through a bs_vecops
 * (bs_vecops.h). */
#include <string.h>

#include "bs_vecops.h"
#include "minimize_impl.h"

int bs_minimizer_set_vecops(bs_minimizer *m, const bs_vecops *ops, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_minimizer_set_vecops: minimizer is NULL");
  if (ops && (!ops->dot || !ops->any || !ops->sum || !ops->solve))
    return bs_error_set(err, BS_EINPUT, "bs_minimizer_set_vecops: dot, any, sum and solve are all required");
  if (ops) m->vops = *ops;
  else memset(&m->vops, 0, sizeof m->vops);
  m->has_vops = ops != NULL;
  return BS_OK;
}

double bs__mdot(const bs_minimizer *m, const double *a, const double *b) {
  return m->has_vops ? m->vops.dot(m->n3, a, b, m->vops.ctx) : bs__dot(m->n3, a, b);
}

int bs__many(const bs_minimizer *m, int flag) { return m->has_vops ? m->vops.any(flag, m->vops.ctx) : flag != 0; }

double bs__msum(const bs_minimizer *m, double v) {
  if (m->has_vops) m->vops.sum(&v, 1, m->vops.ctx);
  return v;
}
