/* dist.c — MPI and PETSc set-up of the distributed backend (bs_dist.h). */
#include <mpi.h>
#include <petsc.h>

#include "bs_dist.h"
#include "dist_internal.h"

static int started_mpi, started_petsc;

int bs__petsc_error(PetscErrorCode code, const char *what, bs_error *err) {
  const char *text = NULL;
  PetscErrorMessage(code, &text, NULL);
  return bs_error_set(err, BS_EINTERNAL, "PETSc error %d (%s) in %s", (int)code, text ? text : "?", what);
}

int bs_dist_init(int *argc, char ***argv, bs_error *err) {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (up) return BS_OK;
  int mpi_up = 0;
  MPI_Initialized(&mpi_up);
  if (!mpi_up) {
    if (MPI_Init(argc, argv) != MPI_SUCCESS) return bs_error_set(err, BS_EINTERNAL, "MPI_Init failed");
    started_mpi = 1;
  }
  PetscErrorCode ierr = PetscInitialize(argc, argv, NULL, NULL);
  if (ierr) return bs_error_set(err, BS_EINTERNAL, "PetscInitialize failed (PETSc error %d)", (int)ierr);
  started_petsc = 1;
  /* Errors come back as codes, printed by no one but the application. */
  BS_PETSC_TRY(PetscPushErrorHandler(PetscReturnErrorHandler, NULL), err);
  return BS_OK;
}

void bs_dist_finalize(void) {
  if (started_petsc) {
    PetscPopErrorHandler();
    PetscFinalize();
    started_petsc = 0;
  }
  int done = 0;
  MPI_Finalized(&done);
  if (started_mpi && !done) MPI_Finalize();
  started_mpi = 0;
}

int bs_dist_rank(void) {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (!up) return 0;
  int r = 0;
  MPI_Comm_rank(PETSC_COMM_WORLD, &r);
  return r;
}

int bs_dist_size(void) {
  PetscBool up = PETSC_FALSE;
  PetscInitialized(&up);
  if (!up) return 1;
  int s = 1;
  MPI_Comm_size(PETSC_COMM_WORLD, &s);
  return s;
}

static int allreduce(void *v, int n, MPI_Datatype type, MPI_Op op, bs_error *err) {
  if (n <= 0) return BS_OK;
  if (MPI_Allreduce(MPI_IN_PLACE, v, n, type, op, PETSC_COMM_WORLD) != MPI_SUCCESS)
    return bs_error_set(err, BS_EINTERNAL, "MPI_Allreduce of %d values failed", n);
  return BS_OK;
}

int bs_dist_sum(double *v, int n, bs_error *err) { return allreduce(v, n, MPI_DOUBLE, MPI_SUM, err); }
int bs_dist_sum_i64(int64_t *v, int n, bs_error *err) { return allreduce(v, n, MPI_INT64_T, MPI_SUM, err); }
int bs_dist_max(double *v, int n, bs_error *err) { return allreduce(v, n, MPI_DOUBLE, MPI_MAX, err); }
