/* surface_parts.c — a closed surface made of several separate solids, split
 * into one soup per solid, and their meshes put back together
 * (bs__soup_solids, bs__mesh_concat; see mesh_internal.h).
 *
 * Why: Mesh_3 meshes the inside of the whole surface at once, and where two
 * solids are closer than the size its cells bridge the gap (the corpus's
 * bones.off at diagonal/25: 6 bones, a mesh whose boundary has 3 parts).
 * Meshed one at a time, two solids cannot be joined: a mesh of solid i only
 * has tets inside solid i's surface. A surface whose components are not all
 * outward (a cavity: a component that bounds a void inside another) is not
 * split, since a solid with a cavity must be meshed with it. */
#include <stdlib.h>
#include <string.h>

#include "mesh_internal.h"

void bs__soup_parts_free(bs_soup_part *parts, int64_t n) {
  for (int64_t i = 0; parts && i < n; i++) free(parts[i].x), free(parts[i].tris);
  free(parts);
}

/* The triangles of component c (label per point) as a soup of their own
 * points, renumbered (id: np scratch entries). */
static int extract(const double *x, int64_t np, const int32_t *tris, int64_t nt, const int32_t *label, int32_t c,
                   int32_t *id, bs_soup_part *p) {
  int64_t n = 0, m = 0;
  for (int64_t v = 0; v < np; v++) id[v] = label[v] == c ? (int32_t)n++ : -1;
  for (int64_t f = 0; f < nt; f++) m += label[tris[3 * f]] == c;
  p->x = malloc(3 * (size_t)n * sizeof *p->x);
  p->tris = malloc(3 * (size_t)m * sizeof *p->tris);
  if (!p->x || !p->tris) return -1;
  for (int64_t v = 0; v < np; v++)
    if (id[v] >= 0) memcpy(p->x + 3 * (size_t)id[v], x + 3 * v, 3 * sizeof *x);
  m = 0;
  for (int64_t f = 0; f < nt; f++) {
    if (label[tris[3 * f]] != c) continue;
    for (int k = 0; k < 3; k++) p->tris[3 * m + k] = id[tris[3 * f + k]];
    m++;
  }
  p->np = n, p->nt = m;
  p->volume = bs__soup_volume(p->x, p->tris, p->nt);
  double lo[3], hi[3];
  bs_bbox(n, p->x, lo, hi);
  p->diag = bs_bbox_diagonal(lo, hi);
  return 0;
}

int bs__soup_solids(const char *path, const double *x, int64_t np, const int32_t *tris, int64_t nt,
                    bs_soup_part **parts, int64_t *n_parts, bs_error *err) {
  *parts = NULL, *n_parts = 0;
  int32_t *label = malloc(((size_t)np + 1) * sizeof *label), *id = malloc(((size_t)np + 1) * sizeof *id);
  const int64_t k = label && id ? bs__soup_label_components(tris, nt, np, label) : -1;
  bs_soup_part *p = k > 1 ? calloc((size_t)k, sizeof *p) : NULL;
  int rc = BS_OK, outward = 1;
  if (k < 0 || (k > 1 && !p)) rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory splitting the surface", path);
  for (int64_t c = 0; !rc && k > 1 && c < k && outward; c++) {
    if (extract(x, np, tris, nt, label, (int32_t)c, id, &p[c]))
      rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory splitting the surface", path);
    else outward = p[c].volume > 0;
  }
  free(label), free(id);
  if (rc || k < 2 || !outward) {
    bs__soup_parts_free(p, k > 1 ? k : 0);
    return rc;
  }
  *parts = p, *n_parts = k;
  return BS_OK;
}

int bs__mesh_concat(const char *path, bs_mesh *const *meshes, int64_t n, bs_mesh **out, bs_error *err) {
  int64_t nv = 0, nt = 0;
  for (int64_t i = 0; i < n; i++) nv += meshes[i]->n_vertices, nt += meshes[i]->n_tets;
  if (nv > BS_MESH_MAX_TETS || nt > BS_MESH_MAX_TETS)
    return bs_error_set(err, BS_EINPUT, "%s: %lld vertices and %lld tets exceed the 32-bit index range", path,
                        (long long)nv, (long long)nt);
  double *x = malloc((3 * (size_t)nv + 1) * sizeof *x);
  int32_t *t = malloc((4 * (size_t)nt + 1) * sizeof *t);
  int rc = BS_OK;
  if (!x || !t) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory joining the meshes of its solids", path);
  } else {
    int64_t v0 = 0, t0 = 0;
    for (int64_t i = 0; i < n; i++) {
      const bs_mesh *m = meshes[i];
      memcpy(x + 3 * v0, m->x, 3 * (size_t)m->n_vertices * sizeof *x);
      for (int64_t j = 0; j < 4 * (int64_t)m->n_tets; j++) t[4 * t0 + j] = m->tets[j] + (int32_t)v0;
      v0 += m->n_vertices, t0 += m->n_tets;
    }
    rc = bs__mesh_default_groups(path, (int32_t)nv, x, (int32_t)nt, t, out, err);
  }
  free(x), free(t);
  return rc;
}
