/* scene.h — JSON scenes (cJSON): parsing, strict validation, --set overrides.
 *
 * A scene file is validated key by key: an unknown key, a wrong type, a
 * missing mesh or group, or an impossible value is an error that names the
 * file and the key path (e.g. "scene.json: bodies.0.material.density: must be
 * > 0, got -1"). The schema is documented in README.md ("Scenes").
 *
 * Ownership: bs_scene_load returns a scene the caller frees with
 * bs_scene_destroy; strings inside are owned by the scene.
 */
#ifndef BS_SCENE_H
#define BS_SCENE_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_material.h"
#include "bs_mesh.h"
#include "bs_step.h"

#define BS_MAX_NAME 256
/* solver.cg_sigma_scale's default: c in the CG tolerance of cg_sigma "auto",
 * min(1/2, c sqrt(max(||grad E||, tau) / ||grad E_0||)). Smaller values cut
 * Newton iterations on the paper's scenes but slow the recovery from tangled
 * states (README, Scenes). */
#define BS_SCENE_SIGMA_SCALE 1.0

typedef enum { BS_SCRIPT_FIXED = 0, BS_SCRIPT_VELOCITY, BS_SCRIPT_KEYFRAMES } bs_script_kind;

typedef struct bs_scene_script {
  char group[BS_MAX_NAME];
  bs_script_kind kind;
  double velocity[3];    /* BS_SCRIPT_VELOCITY: constant velocity (m/s)        */
  int n_keys;            /* BS_SCRIPT_KEYFRAMES: offsets from rest, linear    */
  double *key_t;         /* n_keys times (s), increasing                      */
  double *key_offset;    /* 3 per key (m)                                     */
} bs_scene_script;

typedef struct bs_scene_material {
  char group[BS_MAX_NAME]; /* "" for the body's default                       */
  bs_model model;
  double youngs, poisson, density, rayleigh;
} bs_scene_material;

typedef enum { BS_INIT_REST = 0, BS_INIT_RANDOM, BS_INIT_POINT } bs_init_kind;

typedef struct bs_scene_body {
  char mesh[1024];         /* a path (resolved against the scene's folder) or "box" */
  int box_cells[3];
  double box_size[3];
  double mesh_size;        /* <= 0: the file's own                             */
  int refine;
  bs_order reorder;
  double translate[3], rotate[3] /* axis * angle (degrees) */, scale[3];
  int n_materials;         /* [0] is the default; others by group name          */
  bs_scene_material *materials;
  double velocity[3], angular_velocity[3];
  bs_init_kind init;
  double init_lo[3], init_hi[3]; /* random: box; point: init_lo is the point   */
  unsigned init_seed;
  int n_scripts;
  bs_scene_script *scripts;
} bs_scene_body;

/* An obstacle: a level set (analytic shape, optionally sampled onto a grid or
 * loaded from a grid file), how it collides, and its motion. */
typedef struct bs_scene_obstacle {
  char shape[32];          /* plane, sphere, box, cylinder, torus, grid        */
  double normal[3], offset;            /* plane                                */
  double center[3], radius, half_extents[3], axis[3], half_height, major, minor;
  int inside_out;
  char grid_file[1024];    /* shape "grid": a grid level-set file             */
  double grid_h;           /* > 0: sample the analytic shape onto a grid       */
  char collision[32];      /* constraint, penalty, postprocess                */
  double stiffness, friction;
  double velocity[3], angular_velocity[3];
  int n_keys;
  double *key_t, *key_translate, *key_rotate; /* rotate in degrees (axis-angle) */
} bs_scene_obstacle;

typedef enum { BS_MODE_DYNAMIC = 0, BS_MODE_STATIC } bs_scene_mode;

typedef struct bs_scene {
  char path[1024];         /* the scene file                                    */
  double fps;
  int frames, steps_per_frame;
  double dt;               /* derived: 1 / (fps * steps_per_frame)              */
  bs_integrator_opts solver;
  bs_scene_mode mode;
  int load_steps;
  int project_hessian;     /* PSD-project the elastic Hessian (Newton option)   */
  double gravity[3];
  double drag;
  int n_bodies;
  bs_scene_body *bodies;
  int n_obstacles;
  bs_scene_obstacle *obstacles;
  int self_collision;      /* penalty self-collisions (section 5.3)             */
  double self_stiffness, self_friction;
  char out_dir[1024];      /* "" : no output                                   */
  int vtu_every;           /* frames between VTU files (0: none)               */
  int stats_csv;
  int states;              /* write state.bin (x, v every frame)                */
} bs_scene;

/* Loads and validates a scene, applying the n_sets overrides "key.path=value"
 * (value parsed as JSON, else taken as a string) before validation. */
int bs_scene_load(const char *path, int n_sets, const char *const *sets, bs_scene **out, bs_error *err);
void bs_scene_destroy(bs_scene **s);

#endif
