/* bench/amg.c — block-Jacobi PCG against BoomerAMG-preconditioned CG (linear
 * "amg") on a structured box of CELLS^3 cells (unit cube, fixed_corotated,
 * E = YOUNGS (default 1e5), nu = 0.3, rho = 1000): A = rest-state stiffness +
 * M/dt^2 (dt = 1/24 s), the x = 0 face fixed, a fixed pseudo-random
 * right-hand side. For each solver, in its own child process (so that peak
 * memory is its own): setup seconds (AMG hierarchy; 0 for PCG), iterations
 * and seconds to relative residual 1e-4 and 1e-6 (two solves from zero),
 * seconds per iteration, the true relative residual, and peak RSS (VmHWM)
 * before the solver is created and at the end.
 *
 *   bench_amg [CELLS] [YOUNGS]
 *
 * Threads: OMP_NUM_THREADS as usual (hypre itself is single-threaded in
 * Debian's build). Never run by the test suite. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bs_amg.h"
#include "bs_fem.h"
#include "bs_linsolve.h"
#include "bs_material.h"
#include "bs_mesh.h"

static long peak_rss_mb(void) {
  FILE *f = fopen("/proc/self/status", "r");
  char line[256];
  long kb = 0;
  while (f && fgets(line, sizeof line, f))
    if (!strncmp(line, "VmHWM:", 6)) sscanf(line + 6, "%ld", &kb);
  if (f) fclose(f);
  return kb / 1024;
}

static int run(int cells, double youngs, bs_lin_kind kind) {
  bs_error err = {0};
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  bs_mesh *mesh = NULL;
  bs_fem *fem = NULL;
  bs_bsr *A = NULL;
  bs_material mat;
  if (bs_mesh_create_box(lo, hi, cells, cells, cells, &mesh, &err) ||
      bs_material_init(BS_MODEL_FIXED_COROTATED, youngs, 0.3, 1000, &mat, &err) ||
      bs_fem_create(mesh, 1, &mat, NULL, &fem, &err) || bs_fem_matrix(fem, &A, &err)) {
    fprintf(stderr, "bench_amg: %s\n", err.msg);
    return 1;
  }
  bs_fem_elastic_hessian(fem, mesh->x, 1, 1.0, A);
  const double dt = 1.0 / 24;
  for (int32_t i = 0; i < A->n; ++i)
    for (int a = 0; a < 3; ++a) A->val[9 * (int64_t)A->diag[i] + 4 * a] += fem->mass[i] / (dt * dt);
  const size_t n = (size_t)(uint32_t)A->n, N = 3 * n;
  uint8_t *mask = malloc(n);
  double *b = malloc(N * sizeof *b), *x = malloc(N * sizeof *x), *q = malloc(N * sizeof *q);
  for (size_t i = 0; i < n; ++i) mask[i] = mesh->x[3 * i] > 1e-9;
  unsigned s = 12345u;
  for (size_t k = 0; k < N; ++k) {
    s = s * 1103515245u + 12345u;
    b[k] = ((s >> 8) & 0xffff) / 65536.0 - 0.5 + (k % 3 == 1 ? -1.0 : 0.0);
  }
  const long rss0 = peak_rss_mb();
  bs_linsolve *ls = NULL;
  if (bs_linsolve_create(A, kind, &ls, &err)) {
    fprintf(stderr, "bench_amg: %s\n", err.msg);
    return 1;
  }
  double setup = 0;
  if (kind == BS_LIN_AMG) {
    if (bs_linsolve_amg_setup(ls, A, mask, &err)) {
      fprintf(stderr, "bench_amg: %s\n", err.msg);
      return 1;
    }
    bs_amg_info info;
    bs_linsolve_amg_info(ls, &info);
    setup = info.setup_seconds;
  }
  const double tols[2] = {1e-4, 1e-6};
  int its[2];
  double secs[2], res[2];
  for (int t = 0; t < 2; ++t) {
    bs_lin_stats st;
    if (bs_linsolve_solve(ls, A, mask, b, tols[t], 100000, x, &st, &err)) {
      fprintf(stderr, "bench_amg: %s\n", err.msg);
      return 1;
    }
    bs_bsr_mul(A, mask, x, q);
    double rr = 0, bb = 0;
    for (size_t k = 0; k < N; ++k)
      if (mask[k / 3]) {
        rr += (b[k] - q[k]) * (b[k] - q[k]);
        bb += b[k] * b[k];
      }
    its[t] = st.iterations;
    secs[t] = st.seconds;
    res[t] = sqrt(rr / bb);
  }
  printf("%-7s %8zu %8.3f %6d %8.3f %6d %8.3f %9.5f %9.1e %8ld %8ld\n", bs_lin_kind_name(kind), N, setup, its[0],
         secs[0], its[1], secs[1], secs[1] / (its[1] > 0 ? its[1] : 1), res[1], rss0, peak_rss_mb());
  fflush(stdout);
  bs_linsolve_destroy(&ls);
  bs_bsr_destroy(&A);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&mesh);
  free(mask);
  free(b);
  free(x);
  free(q);
  return 0;
}

int main(int argc, char **argv) {
  const int cells = argc > 1 ? atoi(argv[1]) : 32;
  const double youngs = argc > 2 ? atof(argv[2]) : 1e5;
  if (cells < 1 || !(youngs > 0)) {
    fprintf(stderr, "usage: bench_amg [CELLS] [YOUNGS]\n");
    return 2;
  }
  printf("box %d^3 cells, E = %g, rest stiffness + M/dt^2, x = 0 face fixed\n", cells, youngs);
  printf("%-7s %8s %8s %6s %8s %6s %8s %9s %9s %8s %8s\n", "solver", "dofs", "setup_s", "it1e-4", "s_1e-4",
         "it1e-6", "s_1e-6", "s/iter", "relres", "MB_pre", "MB_peak");
  fflush(stdout);
  const bs_lin_kind kinds[2] = {BS_LIN_PCG, BS_LIN_AMG};
  int rc = 0;
  for (int k = 0; k < 2; ++k) {
    pid_t pid = fork();
    if (pid == 0) _exit(run(cells, youngs, kinds[k]));
    int st = 0;
    if (pid < 0 || waitpid(pid, &st, 0) < 0 || !WIFEXITED(st) || WEXITSTATUS(st)) rc = 1;
  }
  return rc;
}
