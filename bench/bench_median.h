/* bench_median.h — the median of n timings (sorts t in place), shared by the
 * benchmark programs of bench/. */
#ifndef BENCH_MEDIAN_H
#define BENCH_MEDIAN_H
#include <stdlib.h>

static int bench_cmp_d(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static inline double bench_median(double *t, int n) {
  qsort(t, (size_t)n, sizeof(double), bench_cmp_d);
  return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}
#endif
