/* bs_qoi.h — a scene's quantities of interest (bs_scene.qoi) resolved on a
 * simulation and evaluated at its current state, one value each:
 *   displacement, position, velocity: the mean, max or min over a physical
 *       group's vertices of component c (x, y, z, or the vector's length),
 *       or the value at the body's vertex nearest `at` (in the rest state
 *       after the body's transform); m, m, m/s;
 *   reaction: component c of the force the scripted group's support applies
 *       (bs_sim_reaction, N);
 *   contact: component c of the total contact force of obstacle `obstacle`
 *       on the bodies (bs_sim_force_contact summed, N);
 *   energy: kinetic, elastic, gravity or total (bs_sim_measure, J).
 * The run folder writes them per frame to qoi.csv (bs_runfolder.h).
 *
 * Ownership: bs_qoi_create copies what it needs (vertex lists) and keeps a
 * pointer to the simulation's scene; free with bs_qoi_destroy. Status:
 * 0, BS_EINPUT naming the key path (a body, group or obstacle that does not
 * exist, a reaction on a group that is not scripted), BS_ENOMEM, or the
 * forces' BS_ENUMERIC.
 *
 * Example:
 *     bs_qoi *q; double v[16];
 *     if (bs_qoi_create(s, &q, &err)) ...;
 *     bs_qoi_eval(q, s, v, &err);   v[i]: s->scene->qoi[i] now
 *     bs_qoi_destroy(&q);
 */
#ifndef BS_QOI_H
#define BS_QOI_H

#include "bs_base.h"
#include "bs_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_qoi bs_qoi;

int bs_qoi_create(const bs_sim *s, bs_qoi **out, bs_error *err);
/* values: s->scene->n_qoi doubles. */
int bs_qoi_eval(bs_qoi *q, const bs_sim *s, double *values, bs_error *err);
void bs_qoi_destroy(bs_qoi **q);

#ifdef __cplusplus
}
#endif
#endif
