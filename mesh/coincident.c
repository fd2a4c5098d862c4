/* coincident.c — vertices at exactly the same position (bs__coincident). */
#include <stdlib.h>

#include "mesh_internal.h"

typedef struct {
  double p[3];
  int32_t i;
} keyed;

static int cmp_keyed(const void *a, const void *b) {
  const keyed *u = a, *v = b;
  for (int k = 0; k < 3; k++)
    if (u->p[k] != v->p[k]) return u->p[k] < v->p[k] ? -1 : 1;
  return (u->i > v->i) - (u->i < v->i);
}

int64_t bs__coincident(int64_t n, const double *x, int32_t *rep, bs_error *err) {
  keyed *k = malloc((size_t)(n > 0 ? n : 1) * sizeof *k);
  if (!k) {
    bs_error_set(err, BS_ENOMEM, "out of memory for the coincident-vertex search of %lld vertices", (long long)n);
    return -1;
  }
  for (int64_t i = 0; i < n; i++) {
    for (int c = 0; c < 3; c++) k[i].p[c] = x[3 * i + c];
    k[i].i = (int32_t)i;
    rep[i] = (int32_t)i;
  }
  qsort(k, (size_t)n, sizeof *k, cmp_keyed);
  int64_t count = 0;
  for (int64_t s = 1, first = 0; s < n; s++) {
    if (k[s].p[0] == k[first].p[0] && k[s].p[1] == k[first].p[1] && k[s].p[2] == k[first].p[2]) {
      rep[k[s].i] = k[first].i;
      count++;
    } else {
      first = s;
    }
  }
  free(k);
  return count;
}
