/* scene_schema.c — the scene schema, one row per key (scene_schema.h), and
 * the lookups the loader makes in it. The defaults here are the ones
 * scene_build.c sets (test_scene_schema.c compares them with a resolved
 * scene); the ranges are the ones the loader and scene_check.c enforce. */
#include <ctype.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_scene.h"
#include "fields_json.h"
#include "scene_schema.h"

#define CHOICES(...) ((const char *const[]){__VA_ARGS__, NULL})
#define NUM BS_SCHEMA_NUMBER
#define INT BS_SCHEMA_INTEGER
#define STR BS_SCHEMA_STRING
#define BOOL BS_SCHEMA_BOOLEAN
#define VEC3 BS_SCHEMA_VEC3
#define ZERO3 "[0, 0, 0]"
/* The struct field a key is bound to (scene_schema.h), by section. */
#define BIND(T, m) .offset = offsetof(T, m), .size = sizeof(((T *)0)->m)
#define SC(m) BIND(bs_scene, m)
#define BD(m) BIND(bs_scene_body, m)
#define MT(m) BIND(bs_scene_material, m)
#define OB(m) BIND(bs_scene_obstacle, m)
#define QO(m) BIND(bs_scene_qoi, m)
#define VALUES(...) .values = ((const int[]){__VA_ARGS__})

const bs_schema_key bs__schema_keys[] = {
    /* ---- the top level ---- */
    {"", "$schema", STR, .doc = "the JSON Schema this file follows (for editors; the loader ignores it)"},
    {"", "description", STR, .doc = "free text"},
    {"", "time", BS_SCHEMA_OBJECT, .sub = "time", .doc = "frames and time steps"},
    {"", "solver", BS_SCHEMA_OBJECT, .sub = "solver", .doc = "the integrator and its linear solver"},
    {"", "gravity", VEC3, .def = "[0, -9.8, 0]", SC(gravity), .doc = "gravitational acceleration (m/s^2)"},
    {"", "drag", NUM, .range = "[0, )", .def = "0",
     SC(drag), .doc = "simple drag coefficient k (1/s) of k/(2 dt) (x - x_n)^T M (x - x_n)"},
    {"", "bodies", BS_SCHEMA_ARRAY, 1, .sub = "bodies[]", .range = "[1, )", .doc = "the deformable bodies"},
    {"", "obstacles", BS_SCHEMA_ARRAY, .sub = "obstacles[]", .doc = "collision objects as level sets"},
    {"", "self_collision", BS_SCHEMA_OBJECT, .sub = "self_collision",
     .doc = "penalty self-collisions (section 5.3), also between bodies; absent: none"},
    {"", "contact", BS_SCHEMA_OBJECT, .sub = "contact",
     .doc = "parameters of the barrier contact model (self_collision.model \"barrier\")"},
    {"", "output", BS_SCHEMA_OBJECT, .sub = "output", .doc = "what is written, and where"},
    {"", "qoi", BS_SCHEMA_ARRAY, .sub = "qoi[]", .doc = "quantities of interest, written per frame to qoi.csv"},

    /* ---- time ---- */
    {"time", "fps", NUM, .range = "[1e-9, 1e9]", .def = "24", SC(fps), .doc = "frames per second"},
    {"time", "frames", INT, .range = "[0, 10000000]", .def = "24", SC(frames), .doc = "frames to simulate"},
    {"time", "steps_per_frame", INT, .range = "[1, 1000000]", .def = "1", SC(steps_per_frame), .doc = "time steps per frame"},
    {"time", "dt", NUM, .range = "(0, )",
     .doc = "time step (s) instead of steps_per_frame; 1/(fps dt) must be a whole number"},

    /* ---- solver ---- */
    {"solver", "method", STR, .choices = CHOICES("optimization", "newton", "newton_k"), .def = "\"optimization\"",
     SC(solver.method), .doc = "optimization (the paper's integrator), newton (the baseline), newton_k (k Newton steps)"},
    {"solver", "integrator", STR, .choices = CHOICES("backward_euler", "bdf2", "newmark"), SC(solver.integrator),
     .doc = "time integrator: backward_euler (the paper's, first order; the default), bdf2 or newmark (average "
            "acceleration, beta 1/4, gamma 1/2), each second order (written only when not the default)"},
    {"solver", "linear", STR, .choices = CHOICES("cg", "pcg", "amg", "cholmod"), .def = "\"cg\"",
     SC(solver.min.linear), VALUES(BS_LIN_CG, BS_LIN_PCG, BS_LIN_AMG, BS_LIN_CHOLMOD), .doc = "linear solver of the Newton steps"},
    {"solver", "tolerance", NUM, .range = "(0, )", .def = "0.001", SC(solver.min.tol), .doc = "tau on ||grad E|| (N)"},
    {"solver", "rtol", NUM, .range = "[0, 1)", .def = "0",
     SC(solver.min.rtol), .doc = "also converged when ||grad E|| < rtol x ||grad E|| at the step's initial guess (0: off)"},
    {"solver", "load_rtol", NUM, .range = "[0, 1)", .def = "0",
     SC(solver.min.load_rtol), .doc = "also converged when ||grad E|| < load_rtol x the external load's norm (gravity, N; 0: off)"},
    {"solver", "max_iterations", INT, .range = "[1, 100000000]", .def = "500", SC(solver.min.max_iter), .doc = "Newton iterations per step"},
    {"solver", "newton_max_iterations", INT, .range = "[1, 100000000]", .def = "50",
     SC(solver.min.newton_max_iter), .doc = "method newton: iterations per step (it also stops as soon as it diverges)"},
    {"solver", "cg_max_iterations", INT, .range = "[0, 100000000]", .def = "0",
     SC(solver.min.cg_max_iter), .doc = "Krylov iterations per solve; 0: 2 x free dofs + 100"},
    {"solver", "newton_k", INT, .range = "[1, 1000000]", .def = "1",
     SC(solver.newton_k), .doc = "k of newton_k (1: linearized backward Euler)"},
    {"solver", "backend", STR, .choices = CHOICES("serial", "petsc"), .def = "\"serial\"",
     SC(backend), .doc = "serial: this process; petsc: distributed over MPI ranks (mpirun -np N bigstep run SCENE)"},
    {"solver", "mode", STR, .choices = CHOICES("dynamic", "static"), .def = "\"dynamic\"",
     SC(mode), .doc = "dynamic, or static (minimize the potential energy alone)"},
    {"solver", "load_steps", INT, .range = "[1, 100000]", .def = "1", SC(load_steps), .doc = "load increments of a static solve"},
    {"solver", "project_hessian", STR, .choices = CHOICES("none", "all", "inverted", "auto"), .def = "\"none\"",
     SC(project_hessian), .doc = "definiteness fix of the tets' elastic Hessians: none, all (PSD projection), inverted (det F <= 0) "
            "only, auto (inverted where mu dt^2 / (rho h^2) >= 10)"},
    {"solver", "cg_sigma", BS_SCHEMA_NUM_OR_CHOICE, .choices = CHOICES("auto"), .range = "(0, )", .def = "\"auto\"",
     .doc = "sigma of the CG tolerance min(1/2, sigma sqrt(max(||grad E||, tau))), or auto (unitless)"},
    {"solver", "cg_sigma_scale", NUM, .range = "(0, )", .def = "1", .doc = "c of cg_sigma auto"},
    {"solver", "cg_forcing", STR, .choices = CHOICES("paper", "eisenstat_walker", "adaptive"), .def = "\"adaptive\"",
     SC(solver.min.forcing_ew), .doc = "CG forcing terms: the paper's, or also capped by Eisenstat and Walker's choice 2 (always, or "
            "adaptive: after a full Newton step)"},
    {"solver", "globalization", STR, .choices = CHOICES("line_search", "trust_region"), .def = "\"line_search\"",
     SC(solver.min.globalization), .doc = "how a step is found from the Newton direction: the paper's line search, or Steihaug's CG in a trust "
            "region (follows negative curvature; linear cg, pcg or amg)"},
    {"solver", "tr_radius", NUM, .range = "(0, )", .def = "0.1",
     SC(solver.min.tr_radius), .doc = "trust_region: the first radius of each step's solve, as an RMS displacement per free vertex (m)"},
    {"solver", "contact_hessian", STR, .choices = CHOICES("exact", "adaptive"), .def = "\"adaptive\"",
     SC(solver.min.convexify), .doc = "the Newton model's self-collision contacts: exact Hessians (the paper's), or adaptive: each "
            "contact's Hessian projected onto the PSD cone after a solve met negative curvature, until a full "
            "Newton step"},
    {"solver", "penalty_hessian", STR, .choices = CHOICES("exact", "obstacles", "all"), .def = "\"obstacles\"",
     SC(solver.penalty_secant), .doc = "the Newton model of the penalties: exact Hessians (the paper's), or the secant model (each "
            "contact's stiffness along its normal from its depth and the depth where the penalty balances the "
            "other forces) for the penalty obstacles, or for them and the self-collision contacts (optimization "
            "method)"},
    {"solver", "cg_downhill", BOOL, .def = "true",
     SC(solver.min.cg_downhill), .doc = "replace a Krylov answer failing the downhill test by the last CG iterate passing it"},
    {"solver", "cg_precision", STR, .choices = CHOICES("double", "single"), .def = "\"double\"",
     SC(solver.min.cg_single), .doc = "precision of the Hessian values inside cg, pcg and amg solves"},
    {"solver", "amg_matrix", STR, .choices = CHOICES("rest", "current"), .def = "\"rest\"",
     SC(solver.amg_at_rest), VALUES(1, 0), .doc = "what the AMG is built from: the rest-state stiffness, or the Hessian at the iterate"},
    {"solver", "amg_rebuild_factor", NUM, .range = "[0, )", .def = "3",
     SC(solver.min.amg_rebuild_factor), .doc = "rebuild the AMG when iterations per decade grow past this factor (0: never; else >= 1)"},
    {"solver", "amg_rebuild_every", INT, .range = "[0, 100000000]", .def = "0",
     SC(solver.min.amg_rebuild_every), .doc = "rebuild the AMG every N solves (0: never)"},

    /* ---- bodies[] ---- */
    {"bodies[]", "mesh", STR, 1, BD(mesh), .path = 1, .doc = "a mesh or geometry file (against the working, then the scene's folder), or box"},
    {"bodies[]", "box", BS_SCHEMA_OBJECT, .sub = "bodies[].box", .doc = "the structured box (required with mesh box)"},
    {"bodies[]", "mesh_size", NUM, .range = "[0, )", .def = "0",
     BD(mesh_size), .doc = "target mesh size (m) for geometry inputs; 0: the file's own"},
    {"bodies[]", "min_dihedral", NUM, .range = "[0, 70.5)", .def = "10",
     BD(min_dihedral), .doc = "quality gate (degrees) for a mesh bigstep makes (not a .msh): optimised until every tet's smallest "
            "dihedral angle reaches it, else an error naming the worst region; 0: no gate"},
    {"bodies[]", "mesher", STR, .choices = CHOICES("auto", "cgal", "remesh"), .def = "\"auto\"",
     BD(mesher), VALUES(BS_SURFACE_AUTO, BS_SURFACE_CGAL, BS_SURFACE_REMESH), .doc = "a closed surface at mesh_size: cgal (CGAL Mesh_3), remesh (CGAL remeshes the surface, Gmsh HXT meshes "
            "the volume) or auto (remesh above about 2e5 tets, else or if refused cgal)"},
    {"bodies[]", "refine", INT, .range = "[0, 6]", .def = "0", BD(refine), .doc = "uniform 1-to-8 refinements"},
    {"bodies[]", "close_holes", BOOL, .def = "false",
     BD(close_holes), .doc = "a surface (.off, .obj, .ply): close holes up to 0.2 of its bounding-box diagonal (else an open one is refused)"},
    {"bodies[]", "reorder", STR, .choices = CHOICES("none", "metis", "rcm"), .def = "\"none\"",
     BD(reorder), .doc = "vertex renumbering"},
    {"bodies[]", "element", STR, .choices = CHOICES("tet4", "tet10"), .def = "\"tet4\"",
     BD(element), VALUES(BS_ELEMENT_TET4, BS_ELEMENT_TET10), .doc = "the finite element: tet4 (linear) or tet10 (quadratic: "
            "10 nodes; geometry inputs meshed at order 2 with curved boundaries, other meshes gain edge midpoints, a .msh of 10-node tets is taken as it is; one body, no self-collision)"},
    {"bodies[]", "scale", BS_SCHEMA_NUM_OR_VEC3, .range = "(0, )", .def = "[1, 1, 1]",
     BD(scale), .doc = "scale factors (a number or 3), applied first"},
    {"bodies[]", "rotate", VEC3, .def = ZERO3, BD(rotate), .doc = "rotation axis x angle (degrees), applied after scale"},
    {"bodies[]", "translate", VEC3, .def = ZERO3, BD(translate), .doc = "translation (m), applied last"},
    {"bodies[]", "material", BS_SCHEMA_OBJECT, 1, .sub = "bodies[].material", .doc = "the body's material"},
    {"bodies[]", "materials", BS_SCHEMA_MAP, .sub = "bodies[].material",
     .doc = "{3-D physical group: material}: per group overrides"},
    {"bodies[]", "velocity", VEC3, .def = ZERO3, BD(velocity), .doc = "initial velocity (m/s)"},
    {"bodies[]", "angular_velocity", VEC3, .def = ZERO3,
     BD(angular_velocity), .doc = "initial angular velocity (rad/s) about the vertex centroid"},
    {"bodies[]", "initial_state", BS_SCHEMA_OBJECT, .sub = "bodies[].initial_state",
     .doc = "the free vertices' initial positions"},
    {"bodies[]", "scripted", BS_SCHEMA_ARRAY, .sub = "bodies[].scripted[]",
     .doc = "vertex groups whose positions are prescribed"},

    {"bodies[].box", "cells", BS_SCHEMA_IVEC3, 1, .range = "[1, 4096]", BD(box_cells), .doc = "cells [nx, ny, nz]"},
    {"bodies[].box", "size", VEC3, .range = "(0, )", .def = "[1, 1, 1]", BD(box_size), .doc = "edge lengths (m)"},

    {"bodies[].material", "model", STR,
     .choices = CHOICES("fixed_corotated", "corotated", "neo_hookean", "stable_neo_hookean", "linear"),
     .def = "\"fixed_corotated\"", MT(model), .doc = "constitutive model"},
    {"bodies[].material", "youngs", NUM, 1, .range = "(0, )", MT(youngs), .doc = "Young's modulus (Pa)"},
    {"bodies[].material", "poisson", NUM, 1, .range = "(-1, 0.5)", MT(poisson), .doc = "Poisson's ratio"},
    {"bodies[].material", "density", NUM, 1, .range = "(0, )", MT(density), .doc = "density (kg/m^3)"},
    {"bodies[].material", "rayleigh", NUM, .range = "[0, )", .def = "0", MT(rayleigh), .doc = "lagged Rayleigh damping k (s)"},

    {"bodies[].initial_state", "type", STR, 1, .choices = CHOICES("rest", "random", "point"),
     .doc = "rest, random (uniform in the box lo..hi) or point (all at one point)"},
    {"bodies[].initial_state", "lo", VEC3, .doc = "random: the box's low corner (m)"},
    {"bodies[].initial_state", "hi", VEC3, .doc = "random: the box's high corner (m)"},
    {"bodies[].initial_state", "point", VEC3, .def = ZERO3, .doc = "point: the point (m)"},
    {"bodies[].initial_state", "seed", INT, .range = "[0, 2147483647]", .def = "1", .doc = "random: the seed"},

    {"bodies[].scripted[]", "group", STR, 1, .doc = "a physical group of the body's mesh"},
    {"bodies[].scripted[]", "fixed", BOOL, .doc = "true: held at rest"},
    {"bodies[].scripted[]", "velocity", VEC3, .doc = "moved at this constant velocity (m/s)"},
    {"bodies[].scripted[]", "keyframes", BS_SCHEMA_ARRAY, .sub = "bodies[].scripted[].keyframes[]", .range = "[1, )",
     .doc = "offsets from the initial position, linear in between, held after the last"},
    {"bodies[].scripted[].keyframes[]", "t", NUM, 1, .doc = "time (s), increasing"},
    {"bodies[].scripted[].keyframes[]", "offset", VEC3, 1, .doc = "offset from the initial position (m)"},

    /* ---- obstacles[] ---- */
    {"obstacles[]", "shape", STR, 1, .choices = CHOICES("plane", "sphere", "box", "cylinder", "torus", "grid"),
     OB(shape), .doc = "the level set's shape"},
    {"obstacles[]", "normal", VEC3, .def = "[0, 1, 0]", OB(normal), .doc = "plane: outward normal"},
    {"obstacles[]", "offset", NUM, .def = "0", OB(offset), .doc = "plane: normal . x >= offset is outside (m)"},
    {"obstacles[]", "center", VEC3, .def = ZERO3, OB(center), .doc = "sphere, box, cylinder, torus: the center (m)"},
    {"obstacles[]", "radius", NUM, .def = "0.5", OB(radius), .doc = "sphere, cylinder: the radius (m)"},
    {"obstacles[]", "half_extents", VEC3, .def = "[0.5, 0.5, 0.5]", OB(half_extents), .doc = "box: half edge lengths (m)"},
    {"obstacles[]", "axis", VEC3, .def = "[0, 1, 0]", OB(axis), .doc = "cylinder, torus: the axis"},
    {"obstacles[]", "half_height", NUM, .def = "0.5", OB(half_height), .doc = "cylinder: half its height (m)"},
    {"obstacles[]", "major", NUM, .def = "1", OB(major), .doc = "torus: major radius (m)"},
    {"obstacles[]", "minor", NUM, .def = "0.25", OB(minor), .doc = "torus: minor radius (m)"},
    {"obstacles[]", "inside_out", BOOL, .def = "false", OB(inside_out), .doc = "the complement of the shape (a bowl, a hole)"},
    {"obstacles[]", "file", STR, .def = "\"\"", OB(grid_file), .path = 1, .doc = "grid: a grid level-set file (bigstep levelset)"},
    {"obstacles[]", "grid_h", NUM, .range = "[0, )", .def = "0",
     OB(grid_h), .doc = "> 0: sample the analytic shape onto a grid of this spacing (m)"},
    {"obstacles[]", "collision", STR, .choices = CHOICES("constraint", "penalty", "postprocess", "barrier"),
     .def = "\"constraint\"", OB(collision),
     .doc = "gradient projection, penalty k(-phi)^3, push out after the solve, or barrier (IPC: log barrier on the "
            "distance within contact.dhat, line searches bounded by continuous collision detection, friction in the "
            "solve)"},
    {"obstacles[]", "stiffness", NUM, .range = "(0, )", .def = "1000000", OB(stiffness), .doc = "penalty stiffness k"},
    {"obstacles[]", "friction", NUM, .range = "[0, )", .def = "0", OB(friction), .doc = "friction coefficient mu"},
    {"obstacles[]", "velocity", VEC3, .def = ZERO3, OB(velocity), .doc = "constant velocity (m/s)"},
    {"obstacles[]", "angular_velocity", VEC3, .def = ZERO3, OB(angular_velocity), .doc = "constant angular velocity (rad/s)"},
    {"obstacles[]", "keyframes", BS_SCHEMA_ARRAY, .sub = "obstacles[].keyframes[]", .range = "[1, )",
     .doc = "motion by keyframes (instead of velocity)"},
    {"obstacles[].keyframes[]", "t", NUM, 1, .doc = "time (s), increasing"},
    {"obstacles[].keyframes[]", "translate", VEC3, .def = ZERO3, .doc = "translation (m)"},
    {"obstacles[].keyframes[]", "rotate", VEC3, .def = ZERO3, .doc = "rotation axis x angle (degrees)"},

    /* ---- self_collision, output ---- */
    {"self_collision", "stiffness", NUM, .range = "(0, )", .def = "100000", SC(self_stiffness), .doc = "penalty stiffness k"},
    {"self_collision", "friction", NUM, .range = "[0, )", .def = "0", SC(self_friction),
     .doc = "friction coefficient mu (penalty: Coulomb friction after the solve; barrier: IPC's smoothed friction in "
            "the solve, lagged once per step, contact.eps_v)"},
    {"self_collision", "model", STR, .choices = CHOICES("penalty", "barrier"), .def = "\"penalty\"", SC(self_model),
     .doc = "penalty (the paper's, section 5.3) or barrier (IPC: log barrier within contact.dhat, line searches bounded "
            "by continuous collision detection, no intersections)"},
    {"contact", "dhat", NUM, .range = "(0, )", SC(contact_dhat),
     .doc = "barrier activation distance (m); absent: 1e-3 x the diagonal of the bodies' bounding box at t = 0"},
    {"contact", "kappa", NUM, .range = "(0, )", SC(contact_kappa),
     .doc = "barrier stiffness (J/m^4); absent: IPC's choice (balancing the other forces at t = 0 within [kappa_min, "
            "100 kappa_min]), doubled at a step's start while surfaces keep closing in below 1e-9 diagonals"},
    {"contact", "eps_v", NUM, .range = "(0, )", .def = "0.001", SC(contact_eps_v),
     .doc = "barrier friction's smoothing speed (m/s): below it, static friction is a stiff spring (IPC's epsilon_v; "
            "obstacles[].collision \"barrier\" and self_collision.model \"barrier\" with friction)"},

    {"output", "dir", STR, .def = "\"\"", SC(out_dir), .doc = "output folder (empty: no files)"},
    {"output", "vtu_every", INT, .range = "[0, 1000000]", .def = "1", SC(vtu_every), .doc = "frames between VTU files (0: none)"},
    {"output", "checkpoint_every", INT, .range = "[0, 1000000]", .def = "1",
     SC(checkpoint_every), .doc = "frames between checkpoints (checkpoint.bin, for bigstep run --resume; 0: none)"},
    {"output", "stats", BOOL, .def = "true", SC(stats_csv), .doc = "write stats.csv"},
    {"output", "states", BOOL, .def = "false", SC(states), .doc = "write state.bin (time, x, v of every frame)"},
    {"output", "fields", BS_SCHEMA_STRINGS, .choices = bs__field_names,
     .def = "[\"displacement\", \"velocity\", \"scripted\", \"body\", \"material\", \"detF\", \"inverted\", "
            "\"cauchy\", \"von_mises\", \"green_strain\", \"stretches\", \"energy_density\", \"elastic_force\", "
            "\"contact_force\", \"friction_impulse\"]",
     .doc = "the arrays of the VTU frames (docs/running.md, What the frames hold; displacement is always written)"},
    {"output", "compress", BOOL, .def = "false", SC(out_compress), .doc = "zlib-compressed VTU frames and obstacle surfaces"},
    {"qoi[]", "name", STR, 1, QO(name), .doc = "the qoi.csv column (unique, no comma)"},
    {"qoi[]", "quantity", STR, 1,
     .choices = CHOICES("displacement", "position", "velocity", "reaction", "contact", "energy"),
     QO(kind), .doc = "what is measured (docs/scenes.md, Quantities of interest)"},
    {"qoi[]", "component", STR, .choices = CHOICES("x", "y", "z", "magnitude"), .def = "\"x\"",
     QO(component), .doc = "the vector component (or its length)"},
    {"qoi[]", "reduce", STR, .choices = CHOICES("mean", "max", "min"), .def = "\"mean\"",
     QO(reduce), .doc = "over a group's vertices (displacement, position, velocity)"},
    {"qoi[]", "body", INT, .range = "[0, 1000000]", .def = "0", QO(body), .doc = "the body of `group` or `at`"},
    {"qoi[]", "group", STR, QO(group), .doc = "a physical group of the body's mesh (reaction: a scripted group)"},
    {"qoi[]", "at", VEC3, QO(at), .doc = "the body's vertex nearest this rest position (m), instead of a group"},
    {"qoi[]", "obstacle", INT, .range = "[0, 1000000]", .def = "0", QO(obstacle), .doc = "contact: the obstacle's index"},
    {"qoi[]", "term", STR, .choices = CHOICES("kinetic", "elastic", "gravity", "total"), .def = "\"total\"",
     QO(energy), .doc = "energy: which one (J)"},
};
const int bs__schema_n_keys = (int)(sizeof bs__schema_keys / sizeof bs__schema_keys[0]);

const bs_schema_section bs__schema_sections[] = {
    {"", NULL},
    {"time", NULL},
    {"solver", NULL},
    {"bodies[]", NULL},
    {"bodies[].box", NULL},
    {"bodies[].material", NULL},
    {"bodies[].initial_state", NULL},
    {"bodies[].scripted[]", "fixed|velocity|keyframes"},
    {"bodies[].scripted[].keyframes[]", NULL},
    {"obstacles[]", NULL},
    {"obstacles[].keyframes[]", NULL},
    {"self_collision", NULL},
    {"contact", NULL},
    {"output", NULL},
    {"qoi[]", NULL},
};
const int bs__schema_n_sections = (int)(sizeof bs__schema_sections / sizeof bs__schema_sections[0]);

/* ---- lookups ------------------------------------------------------------- */

const bs_schema_key *bs__schema_find(const char *section, const char *key) {
  for (int i = 0; i < bs__schema_n_keys; i++)
    if (!strcmp(bs__schema_keys[i].section, section) && !strcmp(bs__schema_keys[i].key, key)) return &bs__schema_keys[i];
  return NULL;
}

int bs__schema_section_keys(const char *section, const char **keys, int cap) {
  int n = 0;
  for (int i = 0; i < bs__schema_n_keys && n + 1 < cap; i++)
    if (!strcmp(bs__schema_keys[i].section, section)) keys[n++] = bs__schema_keys[i].key;
  if (cap > 0) keys[n] = NULL;
  return n;
}

int bs__schema_choice(const bs_schema_key *k, const char *value) {
  if (!k || !k->choices) return -1;
  for (int i = 0; k->choices[i]; i++)
    if (!strcmp(k->choices[i], value)) return i;
  return -1;
}

/* One bound of "[lo, hi]": the number before `stop`, if any. */
static const char *parse_bound(const char *p, char stop, int *has, double *v) {
  while (*p == ' ') p++;
  *has = 0;
  if (*p != stop) {
    char *end;
    *v = strtod(p, &end);
    *has = end != p;
    p = end;
  }
  while (*p == ' ') p++;
  return p;
}

int bs__schema_range(const bs_schema_key *k, bs_schema_range *r) {
  memset(r, 0, sizeof *r);
  if (!k || !k->range) return 0;
  const char *p = k->range;
  r->lo_open = *p == '(';
  p = parse_bound(p + 1, ',', &r->has_lo, &r->lo);
  if (*p == ',') p++;
  while (*p == ' ') p++;
  int has = 0;
  double v = 0;
  const char *q = p;
  while (*q && *q != ')' && *q != ']') q++;
  r->hi_open = *q == ')';
  if (q != p) {
    parse_bound(p, *q, &has, &v);
    r->has_hi = has;
    r->hi = v;
  }
  return 1;
}

int bs__schema_in_range(const bs_schema_range *r, double v) {
  if (r->has_lo && (r->lo_open ? !(v > r->lo) : !(v >= r->lo))) return 0;
  if (r->has_hi && (r->hi_open ? !(v < r->hi) : !(v <= r->hi))) return 0;
  return 1;
}

void bs__schema_range_text(const bs_schema_range *r, char *out, size_t n) {
  if (r->has_lo && r->has_hi)
    snprintf(out, n, "%c%.17g, %.17g%c", r->lo_open ? '(' : '[', r->lo, r->hi, r->hi_open ? ')' : ']');
  else if (r->has_lo) snprintf(out, n, "%s %.17g", r->lo_open ? ">" : ">=", r->lo);
  else if (r->has_hi) snprintf(out, n, "%s %.17g", r->hi_open ? "<" : "<=", r->hi);
  else snprintf(out, n, "any value");
}

/* ---- "did you mean" ----------------------------------------------------- */

/* Optimal string alignment distance of a and b, case-insensitive; words of
 * up to 63 characters (longer ones are far from everything). */
static int osa_distance(const char *a, const char *b) {
  int na = (int)strlen(a), nb = (int)strlen(b);
  if (na > 63 || nb > 63) return 1000;
  int d[64][64];
  for (int i = 0; i <= na; i++) d[i][0] = i;
  for (int j = 0; j <= nb; j++) d[0][j] = j;
  for (int i = 1; i <= na; i++)
    for (int j = 1; j <= nb; j++) {
      int ca = tolower((unsigned char)a[i - 1]), cb = tolower((unsigned char)b[j - 1]);
      int v = d[i - 1][j - 1] + (ca != cb);
      if (d[i - 1][j] + 1 < v) v = d[i - 1][j] + 1;
      if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
      if (i > 1 && j > 1 && ca == tolower((unsigned char)b[j - 2]) && tolower((unsigned char)a[i - 2]) == cb &&
          d[i - 2][j - 2] + 1 < v)
        v = d[i - 2][j - 2] + 1;
      d[i][j] = v;
    }
  return d[na][nb];
}

/* Characters a and b share at their start. */
static int common_prefix(const char *a, const char *b) {
  int k = 0;
  while (a[k] && a[k] == b[k]) k++;
  return k;
}

/* The nearest candidate; of equally near ones, the one sharing the longest
 * start with the word ("yx" is taken for "y", not "x"). */
const char *bs__schema_nearest(const char *word, const char *const *cands, int n) {
  int len = (int)strlen(word), best = 1000, best_prefix = -1;
  const char *pick = NULL;
  for (int i = 0; n >= 0 ? i < n : cands[i] != NULL; i++) {
    int d = osa_distance(word, cands[i]), pre = common_prefix(word, cands[i]);
    if (d < best || (d == best && pre > best_prefix)) {
      best = d;
      best_prefix = pre;
      pick = cands[i];
    }
  }
  int limit = len >= 6 ? 2 : 1;
  return pick && best <= limit && best < len ? pick : NULL;
}

/* ---- keys bound to struct fields ---------------------------------------- */

int bs__schema_bound(const bs_schema_key *k) { return k && k->size > 0; }

int bs__schema_choice_value(const bs_schema_key *k, int i) { return k->values ? k->values[i] : i; }

const char *bs__schema_choice_name(const bs_schema_key *k, int v) {
  for (int i = 0; k && k->choices && k->choices[i]; i++)
    if (bs__schema_choice_value(k, i) == v) return k->choices[i];
  return NULL;
}

/* The numbers of a default "x" or "[x, y, z]" into v (up to 3); the count. */
static int def_numbers(const char *def, double v[3]) {
  const char *p = def + (*def == '[');
  int n = 0;
  while (n < 3) {
    char *end;
    double x = strtod(p, &end);
    if (end == p) break;
    v[n++] = x;
    p = end;
    while (*p == ' ' || *p == ',') p++;
  }
  return n;
}

/* A default string "\"text\"" into out (size n), without the quotes. */
static void def_string(const char *def, char *out, size_t n) {
  size_t len = strlen(def);
  if (len >= 2 && def[0] == '"') snprintf(out, n, "%.*s", (int)(len - 2), def + 1);
  else snprintf(out, n, "%s", def);
}

static void set_default(const bs_schema_key *k, char *field) {
  double v[3] = {0, 0, 0};
  char text[BS_MAX_NAME];
  switch (k->type) {
  case BS_SCHEMA_NUMBER: def_numbers(k->def, v); memcpy(field, &v[0], sizeof(double)); break;
  case BS_SCHEMA_INTEGER: def_numbers(k->def, v); *(int *)(void *)field = (int)v[0]; break;
  case BS_SCHEMA_BOOLEAN: *(int *)(void *)field = !strcmp(k->def, "true"); break;
  case BS_SCHEMA_VEC3:
  case BS_SCHEMA_NUM_OR_VEC3:
    if (def_numbers(k->def, v) == 1) v[1] = v[2] = v[0];
    memcpy(field, v, sizeof v);
    break;
  case BS_SCHEMA_IVEC3:
    def_numbers(k->def, v);
    for (int i = 0; i < 3; i++) ((int *)(void *)field)[i] = (int)v[i];
    break;
  case BS_SCHEMA_STRING:
    if (!k->choices) {
      def_string(k->def, field, k->size);
      break;
    }
    def_string(k->def, text, sizeof text);
    *(int *)(void *)field = bs__schema_choice_value(k, bs__schema_choice(k, text));
    break;
  default: break;
  }
}

void bs__schema_defaults(const char *section, void *base) {
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    if (bs__schema_bound(k) && k->def && !strcmp(k->section, section)) set_default(k, (char *)base + k->offset);
  }
}
