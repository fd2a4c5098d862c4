/* sim.h — a scene turned into a simulation: the merged mesh of all bodies,
 * the fem cache, the energy terms the scene asks for, the scripted vertices
 * and the integrator. Used by `bigstep run` (and later `study`, `check`).
 *
 * The simulation owns everything it creates; free with bs_sim_destroy. */
#ifndef BS_SIM_H
#define BS_SIM_H

#include <stdint.h>

#include "bs_fem.h"
#include "bs_mesh.h"
#include "bs_obstacles.h"
#include "bs_step.h"
#include "bs_terms.h"
#include "scene.h"

typedef struct bs_sim_script {
  const bs_scene_script *script;
  int32_t n;           /* vertices scripted by it            */
  int32_t *vertices;
} bs_sim_script;

typedef struct bs_sim {
  const bs_scene *scene;
  bs_mesh *mesh;        /* all bodies merged                  */
  double *x0;           /* 3n: positions at t = 0 (transformed rest) */
  double size;          /* m: diagonal of the bounding box of x0 */
  double *x, *v;        /* 3n: current state                   */
  uint8_t *mask;        /* n: 1 free, 0 scripted               */
  int n_scripts;
  bs_sim_script *scripts;
  int n_materials;
  bs_material *materials;
  int32_t *tet_material;
  bs_fem *fem;
  int n_terms;
  bs_term *terms[64];      /* the scene's terms (penalty terms are the obstacles') */
  bs_obstacles *obstacles; /* NULL when the scene has none                  */
  bs_term *self;           /* the self-collision term (in terms[]) or NULL  */
  bs_step_hooks obstacle_hooks;
  bs_step_data step;    /* filled by the integrator each step */
  bs_integrator *integrator;
  double time;
} bs_sim;

int bs_sim_create(const bs_scene *scene, bs_sim **out, bs_error *err);
void bs_sim_destroy(bs_sim **s);

/* Vertices inside obstacles at the current state deeper than 1e-10 of the
 * bodies' size (the constraint guarantee: a projection lands on phi = 0 up to
 * rounding), and the largest depth (m, over all vertices). */
void bs_sim_penetration(const bs_sim *s, int32_t *count, double *max_depth);

/* Self-colliding vertices at the current state and the largest depth (m). */
void bs_sim_self_contacts(bs_sim *s, int32_t *count, double *max_depth);

#endif
