/* dist_internal.h — private to petsc/: turning a PETSc error code into a
 * bigstep status with a message. */
#ifndef BS_DIST_INTERNAL_H
#define BS_DIST_INTERNAL_H

#include <petsc.h>

#include "bs_base.h"

/* BS_EINTERNAL with PETSc's text for code and `what` (the call or object). */
int bs__petsc_error(PetscErrorCode code, const char *what, bs_error *err);

/* Runs a PETSc call; on error returns its bigstep status from the function. */
#define BS_PETSC_TRY(call, err)                                  \
  do {                                                           \
    PetscErrorCode bs__ierr = (call);                            \
    if (bs__ierr) return bs__petsc_error(bs__ierr, #call, err);  \
  } while (0)

/* The same, but jumps to the label `fail` with the status in `rc`. */
#define BS_PETSC_GOTO(call, rc, err)                             \
  do {                                                           \
    PetscErrorCode bs__ierr = (call);                            \
    if (bs__ierr) {                                              \
      rc = bs__petsc_error(bs__ierr, #call, err);                \
      goto fail;                                                 \
    }                                                            \
  } while (0)

#endif
