/* dsim_internal.h — private to petsc/: the parts of bs_dsim_create that live
 * in dsim_obstacles.c. */
#ifndef BS_DSIM_INTERNAL_H
#define BS_DSIM_INTERNAL_H

#include "bs_dsim.h"

/* The scene's obstacles (s->obstacles, after the mask is set) and their
 * penalty terms appended to s->terms. */
int bs__dsim_make_obstacles(bs_dsim *s, bs_error *err);

/* The obstacles' constraint hooks on s->integrator (none without a
 * constraint obstacle). */
int bs__dsim_set_hooks(bs_dsim *s, bs_error *err);

#endif
