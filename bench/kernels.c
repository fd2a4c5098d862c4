/* bench/kernels.c — per-tet kernels and memory-bound kernels on a structured
 * box (default 64^3 cells: 65^3 vertices, 824k dofs, 1.57M tets), printed as
 * a table with 1 and N threads and ratios to the 1-thread run, plus STREAM
 * triad as the bandwidth baseline measured in the same run. The last kernel,
 * "PCG iteration", is one block-Jacobi PCG iteration on the projected Hessian
 * plus M/dt^2 (dt = 1/24 s; 50 iterations, no convergence test met), in ms per
 * iteration; its GB/s column is the product's bytes over that time, so the
 * ratio of STREAM to it is the iteration's time over the product's bandwidth
 * floor. "PCG iteration (single values)" is the same with solver.cg_precision
 * "single" (bs_linsolve_set_single), against the same double bytes. "tet
 * hierarchy build" and "refit" are the self-collision term's bounding-volume
 * hierarchy over the tets (collision/bs_bvh.h), built at each time step's
 * start and refit at each evaluation, in ns per tet.
 *
 *   bench_kernels [CELLS] [REPEATS] [ONLY]
 *
 * Medians of REPEATS (default 5) timings. ONLY (e.g. "energy + gradient", "PCG"):
 * run only the kernels whose label contains it, with as many threads as
 * OMP_NUM_THREADS gives (for a profiler, or to compare two builds). Never run by the test suite. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_median.h"
#include "bs_bvh.h"
#include "bs_fem.h"
#include "bs_linsolve.h"
#include "bs_terms.h"

static double stream_triad(size_t n, int reps) {
  double *a = malloc(n * sizeof(double)), *b = malloc(n * sizeof(double)), *c = malloc(n * sizeof(double));
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; i++) {
    a[i] = 0;
    b[i] = 1;
    c[i] = 2;
  }
  double t[64];
  for (int r = 0; r < reps; r++) {
    double t0 = bs_seconds();
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) a[i] = b[i] + 3.0 * c[i];
    t[r] = bs_seconds() - t0;
  }
  double s = bench_median(t, reps);
  free(a);
  free(b);
  free(c);
  return 3.0 * n * sizeof(double) / s / 1e9;
}

/* The two "PCG iteration" rows (double values, then single:
 * solver.cg_precision) on A = projected Hessian at x + M/dt^2 (SPD, so PCG
 * runs its 50 iterations; b = 1 in g, the answer in y); their GB/s column is
 * the double product's bytes over the time. first: the 1-thread run, whose
 * medians go to base[*k] on as the ratios' reference. Nonzero (printed) when
 * the solver cannot be made. */
static int pcg_rows(const bs_fem *fem, const double *x, bs_bsr *H, double *g, double *y, double bytes, int reps,
                    const char *only, int nthreads, int first, double *base, int *k) {
  bs_error err;
  bs_bsr_zero(H);
  bs_fem_elastic_hessian(fem, x, 1, 1.0, H);
  const double idt2 = 24.0 * 24.0;
  for (int32_t v = 0; v < fem->n_vertices; v++) {
    double B[9] = {0};
    B[0] = B[4] = B[8] = fem->mass[v] * idt2;
    bs_bsr_add_block(H, v, v, B);
  }
  bs_linsolve *ls = NULL;
  if (bs_linsolve_create(H, BS_LIN_PCG, &ls, &err)) {
    fprintf(stderr, "%s\n", err.msg);
    return 1;
  }
  for (size_t i = 0; i < 3 * (size_t)fem->n_vertices; i++) g[i] = 1.0;
  for (int single = 0; single < 2; single++) {
    const char *label = single ? "PCG iteration (single values)" : "PCG iteration (block Jacobi)";
    if (only && !strstr(label, only)) continue;
    if (bs_linsolve_set_single(ls, single, &err)) {
      fprintf(stderr, "%s\n", err.msg);
      bs_linsolve_destroy(&ls);
      return 1;
    }
    int iters = 50;
    double rres = 0, t[64];
    for (int r = 0; r < reps; r++) {
      bs_lin_stats st;
      double t0 = bs_seconds();
      bs_linsolve_solve(ls, H, NULL, g, 0.0, 50, y, &st, &err);
      iters = st.iterations > 0 ? st.iterations : 1;
      rres = st.rel_residual;
      t[r] = (bs_seconds() - t0) / iters;
    }
    double m = bench_median(t, reps);
    if (first) base[*k] = m;
    printf("%-34s %8d %12.2f %12.1f %8.2f\n", label, nthreads, 1e3 * m, bytes / m / 1e9, base[*k] / m);
    (*k)++;
    if (iters != 50) printf("(PCG stopped after %d iterations)\n", iters);
    if (first) printf("(%s: relative residual %.3e after 50 iterations)\n", label, rres);
  }
  bs_linsolve_destroy(&ls);
  return 0;
}

/* The box's vertices moved by up to +-amp/2 per coordinate (xorshift, fixed
 * seed: the same positions in every run) into x. */
static void jitter(const bs_mesh *mesh, double amp, double *x) {
  uint64_t s = 88172645463325252ull;
  for (size_t i = 0; i < 3 * (size_t)mesh->n_vertices; i++) {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    x[i] = mesh->x[i] + amp * ((double)(s >> 11) / 9007199254740992.0 - 0.5);
  }
}

/* The unit box of cells^3 cells, its FEM (fixed corotated, E = 1e5) and a
 * matrix of its pattern. */
static int make_box(int cells, bs_mesh **mesh, bs_fem **fem, bs_bsr **H, bs_error *err) {
  double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  bs_material mat;
  int rc = bs_mesh_create_box(lo, hi, cells, cells, cells, mesh, err);
  if (!rc) rc = bs_material_init(BS_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, &mat, err);
  if (!rc) rc = bs_fem_create(*mesh, 1, &mat, NULL, fem, err);
  if (!rc) rc = bs_fem_matrix(*fem, H, err);
  return rc;
}

int main(int argc, char **argv) {
  int cells = argc > 1 ? atoi(argv[1]) : 64;
  int reps = argc > 2 ? atoi(argv[2]) : 5;
  const char *only = argc > 3 ? argv[3] : NULL;
  if (cells < 1 || reps < 1 || reps > 64) {
    fprintf(stderr, "usage: bench_kernels [CELLS] [REPEATS<=64] [ONLY]\n");
    return 2;
  }
  bs_error err;
  bs_mesh *mesh = NULL;
  bs_fem *fem = NULL;
  bs_bsr *H = NULL;
  if (make_box(cells, &mesh, &fem, &H, &err)) {
    fprintf(stderr, "%s\n", err.msg);
    return 1;
  }
  size_t n3 = 3 * (size_t)mesh->n_vertices;
  double *x = malloc(n3 * sizeof(double)), *g = malloc(n3 * sizeof(double)), *y = malloc(n3 * sizeof(double));
  jitter(mesh, 0.2 / cells, x);
  bs_bvh bvh; /* the self-collision term's hierarchy over the tets (bs_bvh.h) */
  if (bs_bvh_init(&bvh, mesh->tets, 4, mesh->n_tets, &err)) {
    fprintf(stderr, "%s\n", err.msg);
    return 1;
  }
  int maxt = omp_get_max_threads();
  printf("box %d^3 cells: %d vertices (%zu dofs), %d tets, %lld blocks, %d colours; medians of %d\n", cells,
         mesh->n_vertices, n3, mesh->n_tets, (long long)H->nnzb, fem->n_colors, reps);
  printf("%-34s %8s %12s %12s %8s\n", "kernel", "threads", "ms", "ns/tet|GB/s", "ratio");
  int threads[2] = {1, maxt};
  double base[16] = {0};
  const int ti0 = only && maxt > 1 ? 1 : 0; /* ONLY: one run, with maxt threads */
  for (int ti = ti0; ti < (maxt > 1 ? 2 : 1); ti++) {
    omp_set_num_threads(threads[ti]);
    double t[64];
    int k = 0;
#define TIME(label, body, per_tet, bytes)                                                                  \
  do {                                                                                                     \
    if (only && !strstr(label, only)) break;                                                               \
    for (int r = 0; r < reps; r++) {                                                                       \
      double t0 = bs_seconds();                                                                            \
      body;                                                                                                \
      t[r] = bs_seconds() - t0;                                                                            \
    }                                                                                                      \
    double m = bench_median(t, reps);                                                                     \
    if (ti == ti0) base[k] = m;                                                                              \
    double metric = per_tet ? 1e9 * m / mesh->n_tets : (bytes) / m / 1e9;                                  \
    printf("%-34s %8d %12.2f %12.1f %8.2f\n", label, threads[ti], 1e3 * m, metric, base[k] / m);           \
    k++;                                                                                                   \
  } while (0)
    TIME("energy", bs_fem_elastic_energy(fem, x), 1, 0);
    TIME("energy + gradient", (memset(g, 0, n3 * sizeof(double)), bs_fem_elastic_gradient(fem, x, g)), 1, 0);
    TIME("Hessian assembly", (bs_bsr_zero(H), bs_fem_elastic_hessian(fem, x, 0, 1.0, H)), 1, 0);
    TIME("projected Hessian assembly", (bs_bsr_zero(H), bs_fem_elastic_hessian(fem, x, 1, 1.0, H)), 1, 0);
    TIME("energy+gradient+Hessian",
         (memset(g, 0, n3 * sizeof(double)), bs_fem_elastic_gradient(fem, x, g), bs_bsr_zero(H),
          bs_fem_elastic_hessian(fem, x, 0, 1.0, H)),
         1, 0);
    TIME("tet hierarchy build", bs_bvh_build(&bvh, x, threads[ti]), 1, 0);
    TIME("tet hierarchy refit", bs_bvh_refit(&bvh, x, threads[ti]), 1, 0);
    double bytes = (double)H->nnzb * (9 * 8 + 4) + 4.0 * (mesh->n_vertices + 1) + 2 * n3 * 8.0;
    TIME("block CSR product y = A x", bs_bsr_mul(H, NULL, x, y), 0, bytes);
    if ((!only || strstr("PCG iteration (block Jacobi)", only) || strstr("PCG iteration (single values)", only)) &&
        pcg_rows(fem, x, H, g, y, bytes, reps, only, threads[ti], ti == ti0, base, &k))
      return 1;
    if (!only || strstr("STREAM triad", only)) {
      double triad = stream_triad(n3 * 8 > ((size_t)1 << 24) ? n3 * 8 : (size_t)1 << 24, reps); /* >= 384 MB */
      printf("%-34s %8d %12s %12.1f\n", "STREAM triad (GB/s)", threads[ti], "", triad);
    }
  }
  free(x);
  free(g);
  free(y);
  bs_bvh_free(&bvh);
  bs_bsr_destroy(&H);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&mesh);
  return 0;
}
