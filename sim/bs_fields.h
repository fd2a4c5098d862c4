/* bs_fields.h — the fields a run writes into its VTU frames, computed from a
 * simulation's current state.
 *
 * The fields and their names: bs_field_names.h (scene/), where a scene
 * chooses them.
 *
 * Ownership: bs_fields_create allocates every buffer the set needs once (a
 * run folder does it when it is made); bs_fields_compute and
 * bs_fields_write_vtu allocate nothing of their own (the VTU writer its
 * conversion buffers). Free with bs_fields_destroy (NULL accepted, pointer
 * nulled). The struct's fields are for reading: an array is NULL when its
 * field is not in the set.
 *
 * Status: 0, BS_EINPUT (an unknown field name or bit: the message names
 * output.fields and lists the allowed names), BS_ENOMEM, BS_EIO (writing).
 *
 * Threads: bs_fields_compute runs over the tets with OpenMP; each value is
 * computed by one thread, so the results do not depend on the thread count.
 *
 * Example:
 *     bs_fields *fl;
 *     if (bs_fields_create(sim, sim->scene->out_fields, &fl, &err)) ...
 *     ... after each frame:
 *     if (bs_fields_write_vtu(fl, sim, "out/frame_00001.vtu", &err)) ...
 *     bs_fields_destroy(&fl);
 */
#ifndef BS_FIELDS_H
#define BS_FIELDS_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_field_names.h"
#include "bs_mesh.h"
#include "bs_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_fields {
  uint32_t set;                /* what is computed and written (displacement always) */
  int32_t n_vertices, n_tets;
  /* point data */
  uint8_t *scripted;           /* n_vertices                                  */
  int32_t *point_body;         /* n_vertices                                  */
  /* cell data, per tet in mesh order */
  int32_t *cell_body, *material;
  double *J;                   /* detF (also computed for "inverted")         */
  uint8_t *inverted;
  double *P, *cauchy, *green;  /* 9 per tet                                   */
  double *von_mises, *psi;     /* 1 per tet                                   */
  double *stretch;             /* 3 per tet                                   */
  double *f_elastic, *f_contact; /* 3 per vertex (N)                          */
  double *friction;            /* 3 per vertex (N s)                          */
  /* the arrays handed to the VTU writer */
  int n_point_data, n_cell_data;
  bs_vtu_data point_data[6], cell_data[BS_FIELD_COUNT];
} bs_fields;

/* Buffers for the fields of `set` on s's mesh (and the fields that do not
 * change: scripted, body, material). An unknown bit is BS_EINPUT. */
int bs_fields_create(const bs_sim *s, uint32_t set, bs_fields **out, bs_error *err);
void bs_fields_destroy(bs_fields **f);

/* Computes the per-tet fields at s's current positions s->x. */
void bs_fields_compute(bs_fields *f, const bs_sim *s);

/* bs_fields_compute, then the VTU of s's current state with the fields of
 * the set, compressed when the scene's output.compress says so. */
int bs_fields_write_vtu(bs_fields *f, const bs_sim *s, const char *path, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
