/* test_dist_plumbing: MPI and PETSc start, reduce and stop on N ranks. */
#include <petsc.h>

#include <string.h>

#include "dist_check.h"
#include "dist_internal.h"

/* The sum of rank ids is size (size - 1) / 2, in doubles and in int64. */
static void rank_sum(void) {
  bs_error err = {0};
  int r = bs_dist_rank(), s = bs_dist_size();
  double v[2] = {r, 1.0};
  CHECK_OK(bs_dist_sum(v, 2, &err), err);
  CHECK(v[0] == s * (s - 1) / 2.0, "sum of ranks %g, size %d", v[0], s);
  CHECK(v[1] == s, "count %g, size %d", v[1], s);
  int64_t w = r;
  CHECK_OK(bs_dist_sum_i64(&w, 1, &err), err);
  CHECK(w == (int64_t)s * (s - 1) / 2, "int64 sum %lld", (long long)w);
  double m = r;
  CHECK_OK(bs_dist_max(&m, 1, &err), err);
  CHECK(m == s - 1, "max rank %g", m);
  int mpi_size = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &mpi_size);
  CHECK(mpi_size == s, "MPI size %d, PETSc size %d", mpi_size, s);
}

/* A PETSc error comes back as a status with a message, printed by no one
 * (the handler bs_dist_init installs returns the code quietly). */
static PetscErrorCode failing_call(void) {
  SETERRQ(PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "index out of range on purpose");
}

static int call_failing(bs_error *err) {
  BS_PETSC_TRY(failing_call(), err);
  return BS_OK;
}

static void petsc_error_is_a_status(void) {
  bs_error err = {0};
  int rc = call_failing(&err);
  CHECK(rc == BS_EINTERNAL, "status %d", rc);
  CHECK(strstr(err.msg, "PETSc error") && strstr(err.msg, "failing_call"), "message: %s", err.msg);
}

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"rank_sum", rank_sum}, {"petsc_error_is_a_status", petsc_error_is_a_status}};
  return dist_check_main(argc, argv, tests, 2);
}
