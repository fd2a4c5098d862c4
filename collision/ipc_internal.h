/* ipc_internal.h — small helpers shared by the barrier terms' sources
 * (ipc_term.c, ipc_friction_term.c); not installed. */
#ifndef BS_IPC_INTERNAL_H
#define BS_IPC_INTERNAL_H

#include <stdint.h>
#include <stdlib.h>

#include "bs_base.h"

/* Grows *buf (elem bytes each) to hold at least n, doubling from 64
 * (amortised growth: the pair lists); 0 or BS_ENOMEM (*buf unchanged). */
static inline int bs__ipc_grow(void **buf, int64_t *cap, int64_t n, size_t elem) {
  if (n <= *cap) return 0;
  int64_t c = *cap > 0 ? *cap : 64;
  while (c < n) c *= 2;
  void *p = realloc(*buf, (size_t)c * elem);
  if (!p) return BS_ENOMEM;
  *buf = p;
  *cap = c;
  return 0;
}

/* A pair's 4 vertices at x (3 per vertex) into y[12]. */
static inline void bs__ipc_gather(const double *x, const int32_t v[4], double y[12]) {
  for (int a = 0; a < 4; a++)
    for (int k = 0; k < 3; k++) y[3 * a + k] = x[3 * (size_t)v[a] + k];
}

#endif
