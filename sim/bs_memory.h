/* bs_memory.h — the memory a run needs, estimated before it allocates, and
 * the refusal of a scene that would not fit in this machine's memory.
 *
 * The model (bytes of peak resident memory; fitted to `bigstep run` on boxes
 * of 8^3 to 32^3 cells, 3k to 197k tets, bench/memory.md):
 *   64 MiB (the libraries)
 *   + per tet: 1100 (cg, pcg, minres) or 1600 (amg): element data, the
 *     Hessian's blocks, the solver's vectors; +30% with self-collision;
 *   + cholmod: 190 bytes x dofs^(4/3) (the factor's fill on 3-D meshes).
 * It is an estimate, within about 10% on those boxes; meshes less regular
 * than a box fill CHOLMOD's factor differently.
 *
 * bs_sim_create refuses (BS_EINPUT, before allocating the meshes) a scene
 * whose structured boxes alone would need more than the machine has, passes
 * the tet count that fits to the mesh reader (so a file mesh, its refinement
 * and a Gmsh mesh size are refused before they are made), and refuses after
 * the meshes are read if the whole run would not fit. The message names the
 * body's key, the estimate and the machine's memory.
 *
 * Example:
 *     bs_memory_estimate e;
 *     if (bs_scene_memory_estimate(sc, &e, &err)) ... err.msg: "bodies.0.box: ..."
 *     printf("needs about %.1f GiB (%s)\n", e.bytes / 1073741824.0, e.exact ? "exact counts" : "boxes only");
 */
#ifndef BS_MEMORY_H
#define BS_MEMORY_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_memory_estimate {
  int64_t vertices, tets; /* of the bodies counted                                */
  double bytes;           /* estimated peak resident memory of the run            */
  double machine;         /* this machine's physical memory (0 if unknown)        */
  int exact;              /* 1: every body counted (all boxes, or after reading)  */
} bs_memory_estimate;

/* Peak bytes of a run of `sc`'s solver on a mesh of these counts. */
double bs_memory_run_bytes(const bs_scene *sc, int64_t vertices, int64_t tets);

/* The most tets a run of sc's solver can have on this machine. */
int64_t bs_memory_max_tets(const bs_scene *sc);

/* The estimate from the scene alone (box bodies counted exactly, refinement
 * included; file meshes are not read: e->exact 0 when there is one).
 * BS_EINPUT when it is more than the machine has. */
int bs_scene_memory_estimate(const bs_scene *sc, bs_memory_estimate *e, bs_error *err);

/* The same for read meshes of these total counts (e->exact 1). */
int bs_memory_check(const bs_scene *sc, int64_t vertices, int64_t tets, bs_memory_estimate *e, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
