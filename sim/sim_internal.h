/* sim_internal.h — what the simulation's files share (not installed). */
#ifndef BS_SIM_INTERNAL_H
#define BS_SIM_INTERNAL_H

#include "bs_memory.h"
#include "bs_sim.h"

/* sim_bodies.c: the merged, transformed mesh and per-vertex state, the
 * materials per tet, the scripted vertices and the initial state. */
int bs__sim_make_bodies(bs_sim *s, bs_error *err);

/* sim_obstacles.c: the scene's obstacles (and their penalty terms, appended
 * to s->terms); the hooks handed to the integrator; scripted positions. */
int bs__sim_make_obstacles(bs_sim *s, bs_error *err);
void bs__sim_hooks(bs_sim *s, bs_step_hooks *hooks);
/* The friction impulse buffers (s->friction_impulse, s->v_pre) when a
 * dynamic scene has friction; after the obstacles and self-collision. */
int bs__sim_make_friction(bs_sim *s, bs_error *err);
void bs__sim_script_positions(double t, double *x, void *ctx);
/* sim_contact.c: the barrier self-contact term (self_collision.model
 * "barrier") into s->barrier and s->terms, and with self_collision.friction
 * > 0 its friction term (bs_ipc_friction.h) into s->barrier_friction and
 * s->terms after it; refuses a start whose surfaces intersect (naming the
 * bodies and the count) or touch. */
int bs__sim_make_barrier(bs_sim *s, bs_error *err);
/* sim_contact.c: the barrier against the obstacles with collision "barrier"
 * (bs_ipc_obstacle.h) into s->obstacle_barrier and s->terms (none without
 * such obstacles); refuses a start with a free surface vertex inside one. */
int bs__sim_make_obstacle_barrier(bs_sim *s, bs_error *err);

#endif
