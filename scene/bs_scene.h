/* bs_scene.h — a scene: what to simulate (bodies, materials, scripted groups,
 * obstacles, self-collision), how (time, solver) and what to write.
 *
 * Two ways to make one:
 *  - from JSON (cJSON): bs_scene_load (a file) or bs_scene_parse (text), with
 *    "key.path=value" overrides applied before validation. Every key is
 *    checked: an unknown key, a wrong type, a missing mesh or group file, or
 *    an impossible value is BS_EINPUT (BS_EIO for a missing file) with a
 *    message naming the file and the key path, e.g.
 *    "scene.json: obstacles.0.friction: must be >= 0, got -0.5"; an unknown
 *    key names the nearest allowed one ("did you mean 'gravity'?"), a wrong
 *    type what it got ("must be a number, got string \"24\""), malformed
 *    JSON its line and column. The schema is documented in docs/scenes.md
 *    and docs/scene-keys.md and published as a JSON Schema (bs_scene_schema_json);
 *  - in C, without any JSON: bs_scene_create gives a scene holding every
 *    default of the JSON schema and no body; bs_scene_add_body,
 *    bs_scene_body_add_script, bs_scene_body_add_material and
 *    bs_scene_add_obstacle append parts (each with the schema's defaults)
 *    whose fields the caller then sets; bs_scene_validate checks the values
 *    with the same messages (key paths without a file name, "<scene>").
 *    bs_sim_create validates too.
 *
 * Units: SI (m, s, kg, Pa, N). Angles in degrees (rotate, keyframe rotate).
 *
 * Ownership: a scene is owned by its creator and freed with
 * bs_scene_destroy; every array and string inside is owned by the scene
 * (pointers returned by the add functions stay valid until the next add of
 * the same kind or the scene's destruction). A simulation borrows its scene:
 * the scene must outlive it and must not change while it runs.
 *
 * Example (a clamped beam, no JSON):
 *     bs_scene *sc; bs_scene_body *b; bs_scene_script *clamp;
 *     bs_scene_create(&sc, &err);
 *     bs_scene_add_body(sc, "box", &b, &err);
 *     b->box_cells[0] = 20; b->box_cells[1] = b->box_cells[2] = 2;
 *     b->box_size[0] = 1.0; b->box_size[1] = b->box_size[2] = 0.1;
 *     b->materials[0] = (bs_scene_material){.model = BS_MODEL_FIXED_COROTATED,
 *         .youngs = 1e7, .poisson = 0.3, .density = 1000};
 *     bs_scene_body_add_script(b, "xmin", BS_SCRIPT_FIXED, &clamp, &err);
 *     sc->mode = BS_MODE_STATIC;
 *     if (bs_scene_validate(sc, &err)) ... err.msg names the key
 */
#ifndef BS_SCENE_H
#define BS_SCENE_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_material.h"
#include "bs_mesh.h"
#include "bs_levelset.h"
#include "bs_obstacles.h"
#include "bs_step.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_MAX_NAME 256
/* Limits of a scene that can run (refused above them, naming the key):
 * time.fps in [BS_SCENE_MIN_FPS, BS_SCENE_MAX_FPS]; time.steps_per_frame (or
 * the count a time.dt gives) at most BS_SCENE_MAX_STEPS_PER_FRAME; frames x
 * steps_per_frame at most BS_SCENE_MAX_STEPS time steps in one run; a
 * rotation (bodies[].rotate, obstacles[].keyframes[].rotate) at most
 * BS_SCENE_MAX_ANGLE degrees. */
#define BS_SCENE_MIN_FPS 1e-9
#define BS_SCENE_MAX_FPS 1e9
#define BS_SCENE_MAX_STEPS_PER_FRAME 1000000
#define BS_SCENE_MAX_STEPS 1000000000LL
#define BS_SCENE_MAX_ANGLE 1e9
/* solver.cg_sigma_scale's default: c in the CG tolerance of cg_sigma "auto",
 * min(1/2, c sqrt(max(||grad E||, tau) / ||grad E_0||)). Smaller values cut
 * Newton iterations on the paper's scenes but slow the recovery from tangled
 * states (docs/scenes.md). */
#define BS_SCENE_SIGMA_SCALE 1.0

typedef enum { BS_SCRIPT_FIXED = 0, BS_SCRIPT_VELOCITY, BS_SCRIPT_KEYFRAMES } bs_script_kind;

typedef struct bs_scene_script {
  char group[BS_MAX_NAME]; /* a physical group of the body's mesh               */
  bs_script_kind kind;
  double velocity[3];    /* BS_SCRIPT_VELOCITY: constant velocity (m/s)        */
  int n_keys;            /* BS_SCRIPT_KEYFRAMES: offsets from rest, linear    */
  double *key_t;         /* n_keys times (s), increasing                      */
  double *key_offset;    /* 3 per key (m)                                     */
} bs_scene_script;

typedef struct bs_scene_material {
  char group[BS_MAX_NAME]; /* "" for the body's default (materials[0])        */
  bs_model model;
  double youngs, poisson, density, rayleigh; /* Pa, 1, kg/m^3, s              */
} bs_scene_material;

/* bodies[].element: the finite element of a body. */
typedef enum { BS_ELEMENT_TET4 = 0, BS_ELEMENT_TET10 = 1 } bs_element_kind;

typedef enum { BS_INIT_REST = 0, BS_INIT_RANDOM, BS_INIT_POINT } bs_init_kind;

typedef struct bs_scene_body {
  char mesh[BS_MAX_PATH];  /* a path (resolved against the scene's folder) or "box" */
  int box_cells[3];        /* mesh "box": cells [4, 4, 4]                       */
  double box_size[3];      /* mesh "box": edge lengths (m) [1, 1, 1]            */
  double mesh_size;        /* <= 0: the file's own                             */
  double min_dihedral;     /* quality gate (degrees) of a mesh bigstep makes [10]; 0: none */
  int refine;              /* uniform refinements [0], 0..6                     */
  int close_holes;         /* a surface mesh (.off .obj .ply): close its small holes [0] */
  int mesher;              /* a closed surface at mesh_size: BS_SURFACE_AUTO / CGAL / REMESH [auto] */
  bs_order reorder;
  int element;             /* BS_ELEMENT_TET4 [default] or BS_ELEMENT_TET10 (bs_tet10.h: the
                              linear mesh gains its edge midpoints) */
  double translate[3], rotate[3] /* axis * angle (degrees) */, scale[3];
  int n_materials;         /* [0] is the default; others by group name          */
  bs_scene_material *materials;
  double velocity[3], angular_velocity[3]; /* initial (m/s, rad/s about the centroid) */
  bs_init_kind init;
  double init_lo[3], init_hi[3]; /* random: box; point: init_lo is the point   */
  unsigned init_seed;
  int n_scripts;
  bs_scene_script *scripts;
} bs_scene_body;

typedef enum {
  BS_SHAPE_PLANE = 0, /* normal . x >= offset is outside (a half-space floor)     */
  BS_SHAPE_SPHERE,
  BS_SHAPE_BOX,
  BS_SHAPE_CYLINDER,
  BS_SHAPE_TORUS,
  BS_SHAPE_GRID       /* a grid level-set file (bigstep levelset)                */
} bs_shape;

/* "plane", "sphere", "box", "cylinder", "torus", "grid"; parse: BS_EINPUT. */
const char *bs_shape_name(bs_shape s);
int bs_shape_parse(const char *name, bs_shape *out, bs_error *err);

/* An obstacle: a level set (analytic shape, optionally sampled onto a grid or
 * loaded from a grid file), how it collides, and its motion. */
typedef struct bs_scene_obstacle {
  bs_shape shape;
  double normal[3], offset;            /* plane                                */
  double center[3], radius, half_extents[3], axis[3], half_height, major, minor;
  int inside_out;
  char grid_file[BS_MAX_PATH]; /* shape grid: a grid level-set file           */
  double grid_h;           /* > 0: sample the analytic shape onto a grid (m)  */
  bs_collide_mode collision; /* constraint [default], penalty, postprocess, barrier */
  double stiffness, friction;
  double velocity[3], angular_velocity[3];
  int n_keys;
  double *key_t, *key_translate, *key_rotate; /* rotate in degrees (axis-angle) */
} bs_scene_obstacle;

/* A quantity of interest, written per frame to qoi.csv (bs_qoi.h). */
typedef enum {
  BS_QOI_DISPLACEMENT = 0, /* x - x0 (m), over a group or at the vertex nearest a point */
  BS_QOI_POSITION,         /* x (m)                                                  */
  BS_QOI_VELOCITY,         /* v (m/s)                                                */
  BS_QOI_REACTION,         /* the force a scripted group's support applies (N)       */
  BS_QOI_CONTACT,          /* the total contact force of one obstacle on the bodies (N) */
  BS_QOI_ENERGY            /* an energy of bs_sim_measure (J)                         */
} bs_qoi_kind;
typedef enum { BS_QOI_MEAN = 0, BS_QOI_MAX, BS_QOI_MIN } bs_qoi_reduce;
typedef enum { BS_QOI_KINETIC = 0, BS_QOI_ELASTIC, BS_QOI_GRAVITY, BS_QOI_TOTAL } bs_qoi_energy;

typedef struct bs_scene_qoi {
  char name[BS_MAX_NAME];  /* the qoi.csv column: unique, no comma             */
  bs_qoi_kind kind;
  int component;           /* 0, 1, 2 (x, y, z) or 3 (the magnitude)          */
  bs_qoi_reduce reduce;    /* over the group's vertices (kinematic kinds)     */
  int body;                /* the group's body                                */
  char group[BS_MAX_NAME]; /* a physical group ("" : `at`)                    */
  int has_at;
  double at[3];            /* the vertex nearest this rest position (m)       */
  int obstacle;            /* BS_QOI_CONTACT: the obstacle's index            */
  bs_qoi_energy energy;    /* BS_QOI_ENERGY                                   */
} bs_scene_qoi;

typedef enum { BS_MODE_DYNAMIC = 0, BS_MODE_STATIC } bs_scene_mode;
typedef enum { BS_BACKEND_SERIAL = 0, BS_BACKEND_PETSC } bs_scene_backend;

/* self_collision.model: how surfaces in contact repel (bs_scene.self_model). */
enum { BS_SELF_MODEL_PENALTY = 0, BS_SELF_MODEL_BARRIER = 1 };

typedef struct bs_scene {
  char path[BS_MAX_PATH];  /* the scene file; "<scene>" for one built in C     */
  char *description;       /* "description" (owned, malloc'd); NULL: none       */
  double fps;
  int frames, steps_per_frame;
  double dt;               /* derived: 1 / (fps * steps_per_frame); the loader and */
                           /* bs_scene_validate set it                             */
  bs_integrator_opts solver;
  bs_scene_mode mode;
  bs_scene_backend backend; /* solver.backend: serial [default] or petsc (petsc/) */
  int load_steps;
  bs_psd_mode project_hessian; /* solver.project_hessian: the elastic Hessian's fix   */
  double gravity[3];
  double drag;
  int n_bodies;
  bs_scene_body *bodies;
  int n_obstacles;
  bs_scene_obstacle *obstacles;
  int n_qoi;
  bs_scene_qoi *qoi;       /* quantities of interest (qoi.csv)                  */
  int self_collision;      /* penalty self-collisions (section 5.3)             */
  double self_stiffness, self_friction;
  int self_model;          /* BS_SELF_MODEL_PENALTY (the paper's) or _BARRIER   */
  double contact_dhat;     /* barrier activation distance (m); 0: automatic,    */
                           /* 1e-3 x the bodies' bounding-box diagonal at t = 0 */
  double contact_kappa;    /* barrier stiffness (J/m^4); 0: automatic (IPC's    */
                           /* initial value, adapted per step)                  */
  double contact_eps_v;    /* barrier friction's smoothing speed (m/s; 1e-3)   */
  char out_dir[BS_MAX_PATH]; /* "" : no output                                 */
  int vtu_every;           /* frames between VTU files (0: none)               */
  int checkpoint_every;    /* frames between checkpoints (0: none; bs_runfolder.h) */
  int stats_csv;
  int states;              /* write state.bin (x, v every frame)                */
  uint32_t out_fields;     /* output.fields: a set of bs_field bits (bs_field_names.h) */
  int out_compress;        /* output.compress: zlib-compressed VTU frames       */
} bs_scene;

/* Loads and validates a scene file, applying the n_sets overrides
 * "key.path=value" (value parsed as JSON, else taken as a string) before
 * validation. Mesh and grid paths are resolved against the file's folder. */
int bs_scene_load(const char *path, int n_sets, const char *const *sets, bs_scene **out, bs_error *err);

/* The same from JSON text; `name` stands for the file in messages and is the
 * folder relative paths are resolved against (NULL: "<scene>", the current
 * folder). */
int bs_scene_parse(const char *json, const char *name, int n_sets, const char *const *sets, bs_scene **out,
                   bs_error *err);

void bs_scene_destroy(bs_scene **s);

/* ---- scenes built in C ------------------------------------------------ */

/* A scene with every default of the schema and no body. */
int bs_scene_create(bs_scene **out, bs_error *err);

/* Appends a body with the schema's defaults (scale 1, a 4^3-cell unit box
 * when mesh is "box", one default material of fixed corotated with E, nu and
 * rho left 0 for the caller to set). mesh: "box" or a path to a mesh. */
int bs_scene_add_body(bs_scene *s, const char *mesh, bs_scene_body **out, bs_error *err);

/* Appends a material for the 3-D physical group `group` of the body's mesh,
 * a copy of the body's default material (materials[0]) to edit. */
int bs_scene_body_add_material(bs_scene_body *b, const char *group, bs_scene_material **out, bs_error *err);

/* Appends a scripted group of kind `kind` (velocity zero, no keyframes: set
 * them, or call bs_scene_script_set_keyframes). */
int bs_scene_body_add_script(bs_scene_body *b, const char *group, bs_script_kind kind, bs_scene_script **out,
                             bs_error *err);

/* Copies n keyframes (times t, offsets 3 per key) into a script, making it
 * BS_SCRIPT_KEYFRAMES. */
int bs_scene_script_set_keyframes(bs_scene_script *sc, int n, const double *t, const double *offset, bs_error *err);

/* Appends an obstacle of the given shape with the schema's defaults (plane
 * normal +y offset 0, radius 0.5, constraint collision, stiffness 1e6, no
 * friction). */
int bs_scene_add_obstacle(bs_scene *s, bs_shape shape, bs_scene_obstacle **out, bs_error *err);

/* Appends a quantity of interest named `name` of the given kind (component
 * x, reduce mean, body 0, no group, obstacle 0, energy total: set them). */
int bs_scene_add_qoi(bs_scene *s, const char *name, bs_qoi_kind kind, bs_scene_qoi **out, bs_error *err);

/* The offset from rest of a scripted group at time t (s): 0 for fixed, the
 * velocity times t, or the keyframes interpolated linearly (held before the
 * first and after the last key), in metres. */
void bs_scene_script_offset(const bs_scene_script *sc, double t, double off[3]);

/* Obstacle o as a level set (bs_levelset.h; the caller frees it): its shape
 * (or grid file), complement, motion, and with grid_h > 0 an analytic shape
 * sampled on a grid over the box [lo - margin, hi + margin] (m). */
int bs_scene_obstacle_levelset(const bs_scene_obstacle *o, const double lo[3], const double hi[3], double margin,
                               bs_levelset **out, bs_error *err);

/* Sets s->dt = 1 / (fps * steps_per_frame), then bs_scene_check. */
int bs_scene_validate(bs_scene *s, bs_error *err);

/* Checks every value the JSON loader checks (time, solver, materials,
 * bodies, scripts, obstacles, output), and that dt is the one fps and
 * steps_per_frame give: 0, or BS_EINPUT naming the key path. Meshes and
 * groups are checked by bs_sim_create, which calls this first. */
int bs_scene_check(const bs_scene *s, bs_error *err);

/* ---- the schema and the resolved scene -------------------------------- */

/* The scene schema as a JSON Schema (draft-07) text, generated from the table
 * the loader checks keys, types, integer ranges and allowed strings with
 * (data/scene.schema.json holds a copy; `bigstep schema` prints it). *out is
 * malloc'd (free it), ending in a newline. 0, or BS_ENOMEM. */
int bs_scene_schema_json(char **out, bs_error *err);

/* The scene-key reference as Markdown, generated from the same table: one
 * table per section, one row per key (path, type, default, range or
 * choices, description, and a link to its design note where there is one).
 * docs/scene-keys.md holds a copy; `bigstep schema --markdown` prints it.
 * *out is malloc'd (free it), ending in a newline. 0, or BS_ENOMEM. */
int bs_scene_schema_markdown(char **out, bs_error *err);

/* The resolved scene as JSON text in the input layout: every key the loader
 * reads, with its value (defaults filled in), mesh and grid paths made
 * absolute when they name an existing file; "time.dt" is left out (fps and
 * steps_per_frame give it). bs_scene_parse of the text gives back the same
 * scene, and writing that again the same text. *out is malloc'd (free it),
 * ending in a newline. 0, or BS_ENOMEM. */
int bs_scene_write_json(const bs_scene *s, char **out, bs_error *err);

/* The same written to the file `path`, replaced through a temporary file
 * (path.tmp, renamed over path: the old file or the new one, never a part):
 * 0, BS_ENOMEM, or BS_EIO naming the file and the reason. */
int bs_scene_write_json_file(const bs_scene *s, const char *path, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
