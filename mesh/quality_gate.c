/* quality_gate.c — the minimum-dihedral-angle gate for meshes bigstep makes
 * (bs_mesh_dihedral_gate, bs__mesh_gate). */
#include <float.h>
#include <math.h>

#include "mesh_internal.h"

double bs__mesh_gate(const bs_mesh_read_opts *opts) {
  double g = opts ? opts->min_dihedral : 0.0;
  if (g < 0 || isnan(g)) return 0.0;
  return g > 0 ? g : BS_MESH_MIN_DIHEDRAL;
}

int bs_mesh_dihedral_gate(const bs_mesh *m, double gate, const char *what, bs_error *err) {
  if (!m || !(gate > 0)) return BS_OK;
  double worst = DBL_MAX, at[3] = {0, 0, 0}, lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
  int32_t under = 0;
  for (int32_t t = 0; t < m->n_tets; t++) {
    const int32_t *tv = m->tets + 4 * (size_t)t;
    const double *p[4] = {m->x + 3 * (size_t)tv[0], m->x + 3 * (size_t)tv[1], m->x + 3 * (size_t)tv[2],
                          m->x + 3 * (size_t)tv[3]};
    bs__tet_measures q;
    bs__tet_quality(p, &q);
    if (q.dihedral_min >= gate) continue;
    under++;
    for (int k = 0; k < 3; k++) {
      double c = 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k]);
      lo[k] = fmin(lo[k], c);
      hi[k] = fmax(hi[k], c);
      if (q.dihedral_min < worst) at[k] = c;
    }
    if (q.dihedral_min < worst) worst = q.dihedral_min;
  }
  if (!under) return BS_OK;
  return bs_error_set(err, BS_EINPUT,
                      "%s: the mesh's smallest dihedral angle is %.3g degrees, under the gate of %g: %d of %d tets are "
                      "under it, the worst centred at (%.6g, %.6g, %.6g), all of them in [%.6g, %.6g] x [%.6g, %.6g] x "
                      "[%.6g, %.6g] (relax the gate with --min-dihedral or bodies[].min_dihedral; 0 = none)",
                      what, worst, gate, under, m->n_tets, at[0], at[1], at[2], lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
}
