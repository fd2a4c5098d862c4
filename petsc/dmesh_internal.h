/* dmesh_internal.h — private to petsc/: the steps of building a bs_dmesh. */
#ifndef BS_DMESH_INTERNAL_H
#define BS_DMESH_INTERNAL_H

#include "bs_dmesh.h"

/* The bs_dmesh of the distributed DM dm (taken over, destroyed on error):
 * section, local vertices, owned cells, groups. sec / ids: the original
 * vertex ids (1 dof per vertex) when known, else NULL (orig_id -1). */
int bs__dmesh_setup(DM dm, PetscSection sec, Vec ids, bs_dmesh **out, bs_error *err);

/* The group table of m->dm's labels into m (dmesh_groups.c). */
int bs__dmesh_groups(bs_dmesh *m, bs_error *err);

/* Per DMPlex point of dm's chart [pstart, pend): 1 if a leaf of the point SF
 * (owned by another rank). Caller frees. */
int bs__dmesh_ghost_points(DM dm, PetscInt pstart, PetscInt pend, uint8_t **ghost, bs_error *err);

#endif
