/* Results do not depend on the thread count: the same scene run with 1 and
 * with 2 OpenMP threads in one process gives the same final x and v bit for
 * bit (memcmp) and the same Newton, Krylov and line-search counts. The scenes
 * are large enough that the parallel branches of the kernels run (more than
 * 4096 vertices, 16384 dofs, 2048 surface vertices for self-collision):
 * (a) an 18^3 box pulled apart (CG, and block-Jacobi PCG in single
 * precision), (b) two sliding boxes in contact with penalty self-collision,
 * friction, a constraint ground and a penalty wall with friction, (c) the box
 * with CHOLMOD (OpenBLAS, when it is the BLAS, also runs with 1 and 2
 * threads) and with the AMG preconditioner. Then the fixed-order sums of
 * bs_sum.h themselves. */
#define _GNU_SOURCE /* dlsym's RTLD_DEFAULT */
#include <criterion/criterion.h>
#include <dlfcn.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "bs_sum.h"
#include "sim_util.h"

#define SCENES BS_SOURCE_DIR "/data/scenes/"

/* The final state and counts of one run. */
typedef struct run_out {
  size_t n3;
  double *x, *v;
  bs_run_totals T;
} run_out;

static void run_out_free(run_out *o) {
  free(o->x);
  free(o->v);
  memset(o, 0, sizeof *o);
}

/* Runs scene (a file with overrides `sets`, or JSON text when file is NULL)
 * with `threads` OpenMP threads and, when the BLAS is OpenBLAS, as many
 * OpenBLAS threads (CHOLMOD's); the counts are restored afterwards. */
static void run_with(const char *file, const char *sets, const char *json, int threads, run_out *o) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  int (*blas_get)(void) = NULL;
  void (*blas_set)(int) = NULL;
  *(void **)(&blas_get) = dlsym(RTLD_DEFAULT, "openblas_get_num_threads");
  *(void **)(&blas_set) = dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
  const int blas_saved = blas_get && blas_set ? blas_get() : 0;
  if (blas_saved) blas_set(threads);
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_error err;
  bs_error_clear(&err);
  if (file)
    sc = sim_load(file, sets);
  else
    cr_assert_eq(bs_scene_parse(json, NULL, 0, NULL, &sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  memset(&o->T, 0, sizeof o->T);
  cr_assert_eq(bs_sim_run(s, NULL, NULL, &o->T, &err), 0, "%d threads: %s", threads, err.msg);
  o->n3 = 3 * (size_t)s->mesh->n_vertices;
  o->x = malloc(o->n3 * sizeof *o->x);
  o->v = malloc(o->n3 * sizeof *o->v);
  cr_assert(o->x && o->v);
  memcpy(o->x, s->x, o->n3 * sizeof *o->x);
  memcpy(o->v, s->v, o->n3 * sizeof *o->v);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  omp_set_num_threads(saved);
  if (blas_saved) blas_set(blas_saved);
}

static double max_abs_diff(size_t n, const double *a, const double *b) {
  double m = 0;
  for (size_t i = 0; i < n; i++) {
    const double d = fabs(a[i] - b[i]);
    if (d > m || d != d) m = d;
  }
  return m;
}

/* Runs with 1 and 2 threads and asserts identical results; returns the
 * 1-thread totals. */
static bs_run_totals same_with_1_and_2(const char *label, const char *file, const char *sets, const char *json) {
  run_out a = {0}, b = {0};
  run_with(file, sets, json, 1, &a);
  run_with(file, sets, json, 2, &b);
  cr_assert_eq(a.n3, b.n3);
  const double dx = max_abs_diff(a.n3, a.x, b.x), dv = max_abs_diff(a.n3, a.v, b.v);
  cr_log_info("%s: %zu dofs; 1 thread: %ld steps, %ld Newton, %ld Krylov, %ld line-search; 2 threads: %ld, %ld, "
              "%ld, %ld; %ld CHOLMOD fallbacks; max |dx| %.3g m, max |dv| %.3g m/s",
              label, a.n3, a.T.steps, a.T.iterations, a.T.cg, a.T.ls, b.T.steps, b.T.iterations, b.T.cg, b.T.ls,
              a.T.chol_fb, dx, dv);
  cr_expect_eq(a.T.failed, b.T.failed, "%s: failed steps %ld vs %ld", label, a.T.failed, b.T.failed);
  cr_expect_gt(a.T.iterations, 0, "%s: no Newton iteration ran", label);
  cr_expect_eq(a.T.iterations, b.T.iterations, "%s: Newton iterations %ld (1 thread) vs %ld (2)", label,
               a.T.iterations, b.T.iterations);
  cr_expect_eq(a.T.cg, b.T.cg, "%s: Krylov iterations %ld vs %ld", label, a.T.cg, b.T.cg);
  cr_expect_eq(a.T.ls, b.T.ls, "%s: line-search evaluations %ld vs %ld", label, a.T.ls, b.T.ls);
  cr_expect_eq(a.T.indefinite, b.T.indefinite, "%s: indefinite exits %ld vs %ld", label, a.T.indefinite,
               b.T.indefinite);
  cr_expect_eq(a.T.chol_fb, b.T.chol_fb, "%s: CHOLMOD fallbacks %ld vs %ld", label, a.T.chol_fb, b.T.chol_fb);
  cr_expect(memcmp(a.x, b.x, a.n3 * sizeof *a.x) == 0, "%s: x differs, max |dx| = %.3g m", label, dx);
  cr_expect(memcmp(a.v, b.v, a.n3 * sizeof *a.v) == 0, "%s: v differs, max |dv| = %.3g m/s", label, dv);
  const bs_run_totals T = a.T;
  run_out_free(&a);
  run_out_free(&b);
  return T;
}

/* Most runs below stop their step after a few Newton iterations (the step
 * then counts as failed, the same with 1 and 2 threads): tens of CG
 * iterations and line-search trials, in seconds. (Before the fixed-order
 * sums, box_18_cg already differed by 0.18 m in x after these 6.) */
#define FEW_NEWTON "time.frames=1 solver.max_iterations=6 "

/* (a) The scene: cube_stretch on 18^3 cells, the first frame (the
 * pull), with CG; then with block-Jacobi PCG in single precision (the float
 * products). */
Test(threads, box_18_cg, .timeout = 600) {
  (void)same_with_1_and_2("box 18^3 cg", SCENES "cube_stretch.json", FEW_NEWTON "bodies.0.box.cells=[18,18,18]", NULL);
}

/* 12 Newton iterations: the last solves run past the 4 double products and
 * read the float copy of the matrix. */
Test(threads, box_18_pcg_single, .timeout = 600) {
  (void)same_with_1_and_2(
      "box 18^3 pcg single", SCENES "cube_stretch.json",
      "time.frames=1 solver.max_iterations=12 bodies.0.box.cells=[18,18,18] solver.linear=pcg solver.cg_precision=single",
      NULL);
}

/* (b) Two 14^3 boxes (3375 vertices, 1178 surface vertices each), B pressed
 * 1 cm into A, A sliding on the ground (constraint, friction) and into a
 * penalty wall with friction; self-collision with friction. */
static const char *const contact_scene =
    "{\"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"optimization\", \"linear\": \"cg\", \"tolerance\": 1e-3, \"max_iterations\": 8},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [\n"
    "  {\"mesh\": \"box\", \"box\": {\"cells\": [14, 14, 14], \"size\": [0.5, 0.5, 0.5]}, \"velocity\": [1, 0, 0],\n"
    "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 500, \"rayleigh\": 0.01}},\n"
    "  {\"mesh\": \"box\", \"box\": {\"cells\": [14, 14, 14], \"size\": [0.5, 0.5, 0.5]},\n"
    "   \"translate\": [0.1, 0.49, 0.05], \"velocity\": [-0.5, -1, 0],\n"
    "   \"material\": {\"youngs\": 5e4, \"poisson\": 0.3, \"density\": 500, \"rayleigh\": 0.01}}],\n"
    " \"self_collision\": {\"stiffness\": 1e6, \"friction\": 0.3},\n"
    " \"obstacles\": [\n"
    "  {\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": 0, \"collision\": \"constraint\", \"friction\": 0.5},\n"
    "  {\"shape\": \"plane\", \"normal\": [-1, 0, 0], \"offset\": -0.51, \"collision\": \"penalty\",\n"
    "   \"stiffness\": 1e7, \"friction\": 0.2}]}\n";

Test(threads, contact_friction, .timeout = 600) { (void)same_with_1_and_2("contact and friction", NULL, NULL, contact_scene); }

/* (c) The direct and the AMG-preconditioned solvers. CHOLMOD on a tenth of
 * the pull (a 240 Hz frame): the Hessian is positive definite, so every
 * Newton step is a factorization (no CG fallback). */
Test(threads, box_cholmod, .timeout = 600) {
  const bs_run_totals T = same_with_1_and_2("box 16^3 cholmod", SCENES "cube_stretch.json",
                                            "time.frames=1 time.fps=240 bodies.0.box.cells=[16,16,16] "
                                            "solver.linear=cholmod",
                                            NULL);
  cr_expect_lt(T.chol_fb, T.iterations, "no CHOLMOD factorization succeeded (%ld fallbacks in %ld Newton iterations)",
               T.chol_fb, T.iterations);
}

Test(threads, box_amg, .timeout = 600) {
  (void)same_with_1_and_2("box 18^3 amg", SCENES "cube_stretch.json",
                          FEW_NEWTON "bodies.0.box.cells=[18,18,18] solver.linear=amg", NULL);
}

/* bs_sum.h: the cut covers [0, n) in at most BS_SUM_CHUNKS chunks of at least
 * BS_SUM_MIN_LEN indices (but the last), and a dot product has the same bits
 * with 1 to 4 threads and in the serial branch of its `if` clause. */
Test(threads, sum_plan_and_dot) {
  const int64_t sizes[] = {0, 1, 63, 64, 65, 1000, 16385, 65537, 100003, 1 << 20, 3000001};
  const int64_t nmax = 3000001;
  double *a = malloc(sizeof *a * nmax), *b = malloc(sizeof *b * nmax);
  cr_assert(a && b);
  uint64_t r = 88172645463325252ull;
  for (int64_t i = 0; i < nmax; i++) { /* xorshift: values of mixed signs and magnitudes */
    r ^= r << 13, r ^= r >> 7, r ^= r << 17;
    a[i] = ((double)(r >> 11) / 9007199254740992.0 - 0.5) * exp2((double)(r % 40) - 20);
    b[i] = ((double)((r >> 3) & 0xffff) - 32768.0) / 1024.0;
  }
  const int saved = omp_get_max_threads();
  for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++) {
    const int64_t n = sizes[k];
    const bs_sum_plan P = bs_sum_plan_of(n);
    cr_assert_leq(P.count, BS_SUM_CHUNKS, "n %lld: %d chunks", (long long)n, P.count);
    cr_assert_eq(P.count == 0, n == 0);
    int64_t next = 0;
    for (int c = 0; c < P.count; c++) {
      cr_assert_eq(bs_sum_lo(P, c), next);
      cr_assert_gt(bs_sum_hi(P, c), bs_sum_lo(P, c));
      cr_assert(c == P.count - 1 || bs_sum_hi(P, c) - bs_sum_lo(P, c) >= BS_SUM_MIN_LEN);
      next = bs_sum_hi(P, c);
    }
    cr_assert_eq(next, n, "n %lld: the chunks end at %lld", (long long)n, (long long)next);
    const double serial = bs_sum_dot(n, a, b, INT64_MAX);
    long double ref = 0, mag = 0;
    for (int64_t i = 0; i < n; i++) ref += (long double)a[i] * b[i], mag += fabsl((long double)a[i] * b[i]);
    cr_assert_leq(fabsl(serial - ref), 1e-13L * mag + 1e-300L, "n %lld: %.17g vs %.17Lg", (long long)n, serial, ref);
    for (int t = 1; t <= 4; t++) {
      omp_set_num_threads(t);
      const double par = bs_sum_dot(n, a, b, 0);
      cr_assert(memcmp(&par, &serial, sizeof par) == 0, "n %lld, %d threads: %.17g vs serial %.17g", (long long)n, t,
                par, serial);
    }
  }
  omp_set_num_threads(saved);
  free(a);
  free(b);
}
