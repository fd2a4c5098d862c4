/* quality.c — element quality of a tet mesh at given positions.
 *
 * Per tet, with p0..p3 its vertices and a = p1-p0, b = p2-p0, c = p3-p0:
 *  - signed volume V = a.(b x c)/6;
 *  - face area vectors n_f = (q-p) x (r-p)/2 over bs_tet_face[f] (outward
 *    when V > 0); the dihedral angle at the edge shared by faces k and l is
 *    acos(-n_k.n_l / (|n_k||n_l|)) (the interior angle between the faces);
 *  - inradius r_in = 3|V| / sum_f |n_f|; circumradius
 *    R = | |a|^2 (b x c) + |b|^2 (c x a) + |c|^2 (a x b) | / (12 |V|),
 *    so the radius ratio 3 r_in / R = 108 V^2 / (S |num|), given the sign of
 *    V (negative for inverted tets, 0 for flat ones, 1 for a regular tet).
 * A serial loop (about 0.1 s per million tets): bs_mesh does not link
 * OpenMP, and the cost is small beside anything that uses the result.
 */
#include "bs_mesh.h"
#include "mesh_internal.h"
#include "bs_vec3.h"

#include <float.h>
#include <math.h>

void bs__tet_quality(const double *const p[4], bs__tet_measures *out) {
  const double rad2deg = 180.0 / acos(-1.0);
  double a[3], b[3], c[3], bc[3], ca[3], ab[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = p[1][k] - p[0][k];
    b[k] = p[2][k] - p[0][k];
    c[k] = p[3][k] - p[0][k];
  }
  bs_cross3(b, c, bc);
  bs_cross3(c, a, ca);
  bs_cross3(a, b, ab);
  double vol = bs_dot3(a, bc) / 6.0;

  double n[4][3], area[4], s = 0.0;
  for (int f = 0; f < 4; ++f) {
    const double *o = p[bs_tet_face[f][0]], *u = p[bs_tet_face[f][1]], *w = p[bs_tet_face[f][2]];
    double e1[3] = {u[0] - o[0], u[1] - o[1], u[2] - o[2]}, e2[3] = {w[0] - o[0], w[1] - o[1], w[2] - o[2]};
    bs_cross3(e1, e2, n[f]);
    for (int k = 0; k < 3; ++k) n[f][k] *= 0.5;
    area[f] = sqrt(bs_dot3(n[f], n[f]));
    s += area[f];
  }
  /* Edge (i, j) lies on the two faces opposite the other two vertices;
   * acos is decreasing, so only the extreme cosines need it. */
  double cmin = 2.0, cmax = -2.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      int k = -1, l = -1;
      for (int r = 0; r < 4; ++r)
        if (r != i && r != j) {
          if (k < 0) k = r;
          else l = r;
        }
      double cs = 1.0; /* a zero-area face: angle 0 */
      if (area[k] > 0 && area[l] > 0) {
        cs = -bs_dot3(n[k], n[l]) / (area[k] * area[l]);
        cs = cs > 1.0 ? 1.0 : (cs < -1.0 ? -1.0 : cs);
      }
      if (cs < cmin) cmin = cs;
      if (cs > cmax) cmax = cs;
    }
  double num[3];
  double la = bs_dot3(a, a), lb = bs_dot3(b, b), lc = bs_dot3(c, c);
  for (int k = 0; k < 3; ++k) num[k] = la * bc[k] + lb * ca[k] + lc * ab[k];
  double nn = sqrt(bs_dot3(num, num));
  double ratio = (vol != 0.0 && nn > 0.0 && s > 0.0) ? 108.0 * vol * vol / (s * nn) : 0.0;
  out->volume = vol;
  out->dihedral_min = acos(cmax) * rad2deg;
  out->dihedral_max = acos(cmin) * rad2deg;
  out->radius_ratio = vol < 0 ? -ratio : ratio;
}

void bs_mesh_quality_compute(const bs_mesh *m, const double *x, bs_mesh_quality *q) {
  if (!q) return;
  *q = (bs_mesh_quality){0};
  if (!m || m->n_tets <= 0) return;
  if (!x) x = m->x;
  q->vol_min = DBL_MAX;
  q->vol_max = -DBL_MAX;
  q->dihedral_min = DBL_MAX;
  q->dihedral_max = -DBL_MAX;
  q->radius_ratio_min = DBL_MAX;
  double ratio_sum = 0.0;
  for (int32_t t = 0; t < m->n_tets; ++t) {
    const int32_t *tv = m->tets + 4 * (size_t)t;
    const double *p[4] = {x + 3 * (size_t)tv[0], x + 3 * (size_t)tv[1], x + 3 * (size_t)tv[2], x + 3 * (size_t)tv[3]};
    bs__tet_measures tm;
    bs__tet_quality(p, &tm);
    double vol = tm.volume, dmin = tm.dihedral_min, dmax = tm.dihedral_max, ratio = tm.radius_ratio;
    if (vol < q->vol_min) q->vol_min = vol;
    if (vol > q->vol_max) q->vol_max = vol;
    if (dmin < q->dihedral_min) q->dihedral_min = dmin;
    if (dmax > q->dihedral_max) q->dihedral_max = dmax;
    if (ratio < q->radius_ratio_min) q->radius_ratio_min = ratio;
    ratio_sum += ratio;
    q->n_inverted += (vol <= 0.0);
    q->n_degenerate += (ratio < 1e-2 || dmin < 1.0);
    q->n_sliver += (dmin < 1.0);
  }
  q->radius_ratio_mean = ratio_sum / m->n_tets;
}
