/* dist_check.h — checks for the MPI tests of petsc/ (plain C, no Criterion).
 *
 * CHECK(cond, fmt, ...) records a failure on this rank (printed with the rank,
 * file and line); CHECK_REL(a, b, tol, what) checks |a - b| <= tol max(|a|,
 * |b|, tiny). dist_check_main runs the test functions in order, then every
 * rank learns the total number of failures (MPI_Allreduce) and the program
 * exits 1 if any rank failed, 0 otherwise. A bs status that is not 0 is a
 * failure that prints its message (CHECK_OK). */
#ifndef DIST_CHECK_H
#define DIST_CHECK_H

#include <math.h>
#include <mpi.h>
#include <stdio.h>

#include "bs_dist.h"

static int dist_check_failures;

#define CHECK(cond, ...)                                                          \
  do {                                                                            \
    if (!(cond)) {                                                                \
      fprintf(stderr, "[rank %d] %s:%d: check failed: %s: ", bs_dist_rank(), __FILE__, __LINE__, #cond); \
      fprintf(stderr, __VA_ARGS__);                                               \
      fprintf(stderr, "\n");                                                      \
      dist_check_failures++;                                                      \
    }                                                                             \
  } while (0)

#define CHECK_OK(status, err) CHECK((status) == 0, "status %d: %s", (int)(status), (err).msg)

#define CHECK_REL(a, b, tol, what)                                                       \
  do {                                                                                   \
    double ca_ = (a), cb_ = (b);                                                         \
    double cs_ = fmax(fmax(fabs(ca_), fabs(cb_)), 1e-300);                               \
    CHECK(fabs(ca_ - cb_) <= (tol) * cs_, "%s: %.17g vs %.17g (rel %.3g)", what, ca_, cb_, \
          fabs(ca_ - cb_) / cs_);                                                        \
  } while (0)

typedef struct dist_test {
  const char *name;
  void (*fn)(void);
} dist_test;

static inline int dist_check_main(int argc, char **argv, const dist_test *tests, int n) {
  bs_error err = {0};
  if (bs_dist_init(&argc, &argv, &err)) {
    fprintf(stderr, "%s\n", err.msg);
    return 1;
  }
  for (int i = 0; i < n; i++) {
    int before = dist_check_failures;
    tests[i].fn();
    int mine = dist_check_failures - before, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (bs_dist_rank() == 0)
      printf("%-40s %s (%d ranks)\n", tests[i].name, all ? "FAILED" : "ok", bs_dist_size());
  }
  int total = 0;
  MPI_Allreduce(&dist_check_failures, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  bs_dist_finalize();
  return total ? 1 : 0;
}

#endif
