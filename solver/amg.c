/* amg.c — hypre BoomerAMG (one V-cycle) as a preconditioner on the free dofs
 * of a 3x3 block CSR matrix (see bs_amg.h). */
#include "bs_amg.h"
#include "bs_sum.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <mpi.h>

#include <HYPRE.h>
#include <HYPRE_IJ_mv.h>
#include <HYPRE_parcsr_ls.h>
#include <HYPRE_utilities.h>

/* Open MPI keeps (and at finalize drops) allocations LeakSanitizer reports as
 * leaks; they are not ours, so leak checking is paused around MPI start-up and
 * shutdown in sanitizer builds. */
#if defined(__SANITIZE_ADDRESS__)
#define BS_HAVE_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BS_HAVE_LSAN 1
#endif
#endif
#ifdef BS_HAVE_LSAN
#include <sanitizer/lsan_interface.h>
#define LSAN_PAUSE() __lsan_disable()
#define LSAN_RESUME() __lsan_enable()
#else
#define LSAN_PAUSE() ((void)0)
#define LSAN_RESUME() ((void)0)
#endif

struct bs_amg {
  int32_t n;          /* vertices of the last setup's matrix                 */
  int32_t nfree;      /* free vertices of the last setup                     */
  int ready;          /* a setup succeeded                                   */
  uint8_t *smask;     /* n: the mask of the last setup (1 free)              */
  int32_t *fvert;     /* nfree: vertex of each free vertex number            */
  HYPRE_BigInt *idx;  /* 3 nfree: 0, 1, ... (hypre's row indices)            */
  double *buf;        /* 3 nfree: compact vector                             */
  HYPRE_IJMatrix A;
  HYPRE_IJVector b, x;
  HYPRE_ParCSRMatrix pA;
  HYPRE_ParVector pb, px;
  HYPRE_Solver solver;
  bs_amg_info info;
};

/* ---- MPI / hypre start-up (once per process) ---------------------------- */

static int g_started;       /* HYPRE_Init done                                */
static int g_we_init_mpi;   /* MPI_Init was ours: finalize it at exit         */

static void amg_at_exit(void) {
  int fin = 0;
  MPI_Finalized(&fin);
  if (fin) return;
  LSAN_PAUSE();
  HYPRE_Finalize();
  if (g_we_init_mpi) MPI_Finalize();
  LSAN_RESUME();
}

static int amg_start(bs_error *err) {
  if (g_started) return BS_OK;
  int inited = 0, fin = 0;
  MPI_Initialized(&inited);
  MPI_Finalized(&fin);
  if (fin) return bs_error_set(err, BS_EINTERNAL, "amg: MPI was already finalized");
  LSAN_PAUSE();
  const int rc = inited ? MPI_SUCCESS : MPI_Init(NULL, NULL);
  const int hrc = rc == MPI_SUCCESS ? (int)HYPRE_Init() : 0;
  LSAN_RESUME();
  if (rc != MPI_SUCCESS) return bs_error_set(err, BS_EINTERNAL, "amg: MPI_Init failed (MPI error %d)", rc);
  g_we_init_mpi = !inited;
  if (hrc) return bs_error_set(err, BS_EINTERNAL, "amg: HYPRE_Init failed (hypre error flag %d)", hrc);
  g_started = 1;
  atexit(amg_at_exit);
  return BS_OK;
}

/* ---- create / destroy ------------------------------------------------------ */

static void free_hierarchy(bs_amg *amg) {
  if (amg->solver) HYPRE_BoomerAMGDestroy(amg->solver);
  if (amg->A) HYPRE_IJMatrixDestroy(amg->A);
  if (amg->b) HYPRE_IJVectorDestroy(amg->b);
  if (amg->x) HYPRE_IJVectorDestroy(amg->x);
  amg->solver = NULL;
  amg->A = NULL;
  amg->b = amg->x = NULL;
  amg->pA = NULL;
  amg->pb = amg->px = NULL;
  free(amg->smask);
  free(amg->fvert);
  free(amg->idx);
  free(amg->buf);
  amg->smask = NULL;
  amg->fvert = NULL;
  amg->idx = NULL;
  amg->buf = NULL;
  amg->ready = 0;
  amg->n = amg->nfree = 0;
}

int bs_amg_create(bs_amg **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_amg_create: out is NULL");
  *out = NULL;
  int rc = amg_start(err);
  if (rc) return rc;
  bs_amg *amg = bs_calloc(1, sizeof *amg, "the AMG preconditioner", err);
  if (!amg) return BS_ENOMEM;
  *out = amg;
  return BS_OK;
}

void bs_amg_destroy(bs_amg **pa) {
  if (!pa || !*pa) return;
  free_hierarchy(*pa);
  free(*pa);
  *pa = NULL;
}

int bs_amg_ready(const bs_amg *amg) { return amg && amg->ready; }

int bs_amg_same_mask(const bs_amg *amg, int32_t n, const uint8_t *mask) {
  if (!amg || !amg->ready || amg->n != n) return 0;
  for (int32_t i = 0; i < n; ++i)
    if (amg->smask[i] != (uint8_t)(!mask || mask[i])) return 0;
  return 1;
}

void bs_amg_get_info(const bs_amg *amg, bs_amg_info *info) {
  if (!info) return;
  if (!amg) {
    memset(info, 0, sizeof *info);
    return;
  }
  *info = amg->info;
}

/* ---- setup ------------------------------------------------------------------ */

static int hypre_fail(bs_amg *amg, const char *what, bs_error *err) {
  const HYPRE_Int code = HYPRE_GetError();
  HYPRE_ClearAllErrors();
  free_hierarchy(amg);
  return bs_error_set(err, BS_EINTERNAL, "amg: hypre %s failed (hypre error flag %d)", what,
                      (int)code);
}

/* The elasticity settings of bs_amg.h. */
static void amg_settings(HYPRE_Solver s) {
  HYPRE_BoomerAMGSetPrintLevel(s, 0);
  HYPRE_BoomerAMGSetLogging(s, 0);
  HYPRE_BoomerAMGSetMaxIter(s, 1); /* one V-cycle per apply            */
  HYPRE_BoomerAMGSetTol(s, 0.0);   /* no convergence check             */
  HYPRE_BoomerAMGSetNumFunctions(s, 3);
  HYPRE_BoomerAMGSetNodal(s, 4);     /* nodal coarsening, row-sum block norm */
  HYPRE_BoomerAMGSetNodalDiag(s, 1);
  HYPRE_BoomerAMGSetCoarsenType(s, 10); /* HMIS                          */
  HYPRE_BoomerAMGSetAggNumLevels(s, 1); /* aggressive coarsening, 1 level */
  HYPRE_BoomerAMGSetInterpType(s, 6);   /* extended+i                    */
  HYPRE_BoomerAMGSetPMaxElmts(s, 4);
  HYPRE_BoomerAMGSetStrongThreshold(s, 0.5);
}

/* BS_ENUMERIC naming the first non-finite entry of a free-free block. */
static int check_finite(const bs_amg *amg, const bs_bsr *P, const int32_t *fmap, bs_error *err) {
  for (int32_t f = 0; f < amg->nfree; ++f) {
    const int32_t i = amg->fvert[f];
    for (int32_t s = P->row_ptr[i]; s < P->row_ptr[i + 1]; ++s) {
      if (fmap[P->col[s]] < 0) continue;
      for (int e = 0; e < 9; ++e)
        if (!isfinite(P->val[9 * (int64_t)s + e]))
          return bs_error_set(err, BS_ENUMERIC, "amg setup: matrix block (%d,%d) entry (%d,%d) is not finite",
                              (int)i, (int)P->col[s], e / 3, e % 3);
    }
  }
  return 0;
}

/* amg->idx filled and amg->A created and initialized with the row sizes of
 * the free-free blocks of P (N = 3 free vertices); *maxrow: most free blocks
 * in a row. */
static int create_matrix(bs_amg *amg, const bs_bsr *P, const int32_t *fmap, HYPRE_Int N, int32_t *maxrow,
                         bs_error *err) {
  HYPRE_Int *diag_sizes = bs_calloc((size_t)N, sizeof *diag_sizes, "amg row sizes", err);
  HYPRE_Int *offd_sizes = bs_calloc((size_t)N, sizeof *offd_sizes, "amg row sizes", err);
  if (!diag_sizes || !offd_sizes) {
    free(diag_sizes);
    free(offd_sizes);
    return BS_ENOMEM;
  }
  for (HYPRE_Int k = 0; k < N; ++k) amg->idx[k] = k;
  for (int32_t f = 0; f < amg->nfree; ++f) {
    const int32_t i = amg->fvert[f];
    int32_t c = 0;
    for (int32_t s = P->row_ptr[i]; s < P->row_ptr[i + 1]; ++s) c += fmap[P->col[s]] >= 0;
    for (int a = 0; a < 3; ++a) diag_sizes[3 * f + a] = 3 * c;
    if (c > *maxrow) *maxrow = c;
  }
  HYPRE_ClearAllErrors();
  HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, N - 1, 0, N - 1, &amg->A);
  HYPRE_IJMatrixSetObjectType(amg->A, HYPRE_PARCSR);
  HYPRE_IJMatrixSetDiagOffdSizes(amg->A, diag_sizes, offd_sizes);
  HYPRE_IJMatrixInitialize(amg->A);
  free(diag_sizes);
  free(offd_sizes);
  return HYPRE_GetError() ? hypre_fail(amg, "matrix creation", err) : 0;
}

/* The free-free blocks of P into the initialized amg->A, one vertex (three
 * scalar rows) per SetValues call; maxrow: most free blocks in a row. */
static int fill_matrix(bs_amg *amg, const bs_bsr *P, const int32_t *fmap, int32_t maxrow, bs_error *err) {
  HYPRE_Int ncols[3];
  HYPRE_BigInt rows[3];
  HYPRE_BigInt *cols = malloc(sizeof *cols * 9 * (size_t)(maxrow > 0 ? maxrow : 1));
  double *vals = malloc(sizeof *vals * 9 * (size_t)(maxrow > 0 ? maxrow : 1));
  if (!cols || !vals) {
    free(cols);
    free(vals);
    return bs_error_set(err, BS_ENOMEM, "amg setup: out of memory (row buffers)");
  }
  for (int32_t f = 0; f < amg->nfree; ++f) {
    const int32_t i = amg->fvert[f];
    int k = 0;
    for (int a = 0; a < 3; ++a) {
      rows[a] = 3 * f + a;
      ncols[a] = 0;
      for (int32_t s = P->row_ptr[i]; s < P->row_ptr[i + 1]; ++s) {
        const int32_t fj = fmap[P->col[s]];
        if (fj < 0) continue;
        const double *blk = P->val + 9 * (int64_t)s;
        for (int b = 0; b < 3; ++b) {
          cols[k] = 3 * (HYPRE_BigInt)fj + b;
          vals[k] = blk[3 * a + b];
          ++k;
          ++ncols[a];
        }
      }
    }
    HYPRE_IJMatrixSetValues(amg->A, 3, ncols, rows, cols, vals);
  }
  free(cols);
  free(vals);
  return 0;
}

/* A zero hypre vector of N entries (errors: HYPRE_GetError). */
static void make_vector(HYPRE_Int N, HYPRE_IJVector *v, HYPRE_ParVector *pv) {
  HYPRE_IJVectorCreate(MPI_COMM_SELF, 0, N - 1, v);
  HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR);
  HYPRE_IJVectorInitialize(*v);
  HYPRE_IJVectorAssemble(*v);
  HYPRE_IJVectorGetObject(*v, (void **)pv);
}

int bs_amg_setup(bs_amg *amg, const bs_bsr *P, const uint8_t *mask, bs_error *err) {
  if (!amg || !P) return bs_error_set(err, BS_EINPUT, "bs_amg_setup: NULL argument");
  const double t0 = bs_seconds();
  free_hierarchy(amg);
  const int32_t n = P->n;
  const size_t nn = n > 0 ? (size_t)n : 1;
  amg->smask = bs_calloc(nn, 1, "amg mask", err);
  amg->fvert = bs_calloc(nn, sizeof *amg->fvert, "amg free vertices", err);
  int32_t *fmap = bs_calloc(nn, sizeof *fmap, "amg free map", err);
  if (!amg->smask || !amg->fvert || !fmap) {
    free(fmap);
    free_hierarchy(amg);
    return BS_ENOMEM;
  }
  int32_t nf = 0;
  for (int32_t i = 0; i < n; ++i) {
    const int fr = !mask || mask[i];
    amg->smask[i] = (uint8_t)fr;
    fmap[i] = fr ? nf : -1;
    if (fr) amg->fvert[nf++] = i;
  }
  amg->n = n;
  amg->nfree = nf;
  int rc = check_finite(amg, P, fmap, err);
  if (rc) {
    free(fmap);
    free_hierarchy(amg);
    return rc;
  }
  if (nf == 0) {
    free(fmap);
    amg->ready = 1;
    amg->info.setups++;
    amg->info.free_dofs = 0;
    amg->info.setup_seconds = bs_seconds() - t0;
    return BS_OK;
  }
  if (3 * (int64_t)nf > INT32_MAX) {
    free(fmap);
    free_hierarchy(amg);
    return bs_error_set(err, BS_EINPUT, "amg setup: %lld free dofs exceed hypre's int range",
                        (long long)(3 * (int64_t)nf));
  }
  const HYPRE_Int N = (HYPRE_Int)(3 * nf);
  amg->idx = bs_calloc((size_t)N, sizeof *amg->idx, "amg indices", err);
  amg->buf = bs_calloc((size_t)N, sizeof *amg->buf, "amg vector", err);
  int32_t maxrow = 0; /* most free blocks in a row */
  if (!amg->idx || !amg->buf) rc = BS_ENOMEM;
  else rc = create_matrix(amg, P, fmap, N, &maxrow, err);
  if (rc) {
    free(fmap);
    free_hierarchy(amg);
    return rc;
  }
  rc = fill_matrix(amg, P, fmap, maxrow, err);
  free(fmap);
  if (rc) {
    free_hierarchy(amg);
    return rc;
  }
  HYPRE_IJMatrixAssemble(amg->A);
  HYPRE_IJMatrixGetObject(amg->A, (void **)&amg->pA);
  if (HYPRE_GetError()) return hypre_fail(amg, "matrix assembly", err);
  make_vector(N, &amg->b, &amg->pb);
  make_vector(N, &amg->x, &amg->px);
  if (HYPRE_GetError()) return hypre_fail(amg, "vector creation", err);
  HYPRE_BoomerAMGCreate(&amg->solver);
  amg_settings(amg->solver);
  HYPRE_BoomerAMGSetup(amg->solver, amg->pA, amg->pb, amg->px);
  if (HYPRE_GetError()) return hypre_fail(amg, "BoomerAMG setup", err);
  amg->ready = 1;
  amg->info.setups++;
  amg->info.free_dofs = N;
  amg->info.setup_seconds = bs_seconds() - t0;
  return BS_OK;
}

/* ---- apply ------------------------------------------------------------------ */

int bs_amg_apply(bs_amg *amg, const double *r, double *z, double *rz, bs_error *err) {
  if (!amg || !r || !z) return bs_error_set(err, BS_EINPUT, "bs_amg_apply: NULL argument");
  if (!amg->ready) return bs_error_set(err, BS_EINPUT, "bs_amg_apply: no setup yet");
  const int32_t n = amg->n, nf = amg->nfree;
  memset(z, 0, sizeof *z * 3 * (size_t)n);
  if (nf == 0) {
    if (rz) *rz = 0.0;
    return BS_OK;
  }
  const HYPRE_Int N = (HYPRE_Int)(3 * nf);
  double *buf = amg->buf;
  const int32_t *fv = amg->fvert;
#pragma omp parallel for schedule(static) if (nf > 4096)
  for (int32_t f = 0; f < nf; ++f)
    for (int a = 0; a < 3; ++a) buf[3 * f + a] = r[3 * (int64_t)fv[f] + a];
  HYPRE_IJVectorSetValues(amg->b, N, amg->idx, buf);
  HYPRE_ParVectorSetConstantValues(amg->px, 0.0);
  HYPRE_BoomerAMGSolve(amg->solver, amg->pA, amg->pb, amg->px);
  HYPRE_IJVectorGetValues(amg->x, N, amg->idx, buf);
  const HYPRE_Int code = HYPRE_GetError();
  HYPRE_ClearAllErrors();
  if (code & ~HYPRE_ERROR_CONV)
    return bs_error_set(err, BS_EINTERNAL, "amg: hypre BoomerAMG cycle failed (hypre error flag %d)",
                        (int)code);
  /* r . z summed as in bs_sum.h: the same bits with any thread count */
  double part[BS_SUM_CHUNKS];
  const bs_sum_plan P = bs_sum_plan_of(nf);
#pragma omp parallel for schedule(static) if (nf > 4096)
  for (int c = 0; c < P.count; ++c) {
    double s = 0.0;
    for (int32_t f = (int32_t)bs_sum_lo(P, c); f < (int32_t)bs_sum_hi(P, c); ++f)
      for (int a = 0; a < 3; ++a) {
        const int64_t m = 3 * (int64_t)fv[f] + a;
        z[m] = buf[3 * f + a];
        s += r[m] * z[m];
      }
    part[c] = s;
  }
  if (rz) *rz = bs_sum_parts(P.count, part);
  return BS_OK;
}
