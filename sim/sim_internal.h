/* sim_internal.h — what the simulation's files share (not installed). */
#ifndef BS_SIM_INTERNAL_H
#define BS_SIM_INTERNAL_H

#include "bs_memory.h"
#include "bs_sim.h"

/* sim_bodies.c: the merged, transformed mesh and per-vertex state, the
 * materials per tet, the scripted vertices and the initial state. */
int bs_sim_make_bodies_(bs_sim *s, bs_error *err);

/* sim_obstacles.c: the scene's obstacles (and their penalty terms, appended
 * to s->terms); the hooks handed to the integrator; scripted positions. */
int bs_sim_make_obstacles_(bs_sim *s, bs_error *err);
void bs_sim_hooks_(bs_sim *s, bs_step_hooks *hooks);
/* The friction impulse buffers (s->friction_impulse, s->v_pre) when a
 * dynamic scene has friction; after the obstacles and self-collision. */
int bs_sim_make_friction_(bs_sim *s, bs_error *err);
void bs_sim_script_positions_(double t, double *x, void *ctx);

#endif
