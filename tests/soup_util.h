/* soup_util.h — the tests' closed surfaces from the corpus (data/meshes/,
 * extracted by setup.sh): read as a soup with its bounding-box diagonal and
 * enclosed volume, the two-sided Hausdorff distance of a mesh's boundary to
 * it, and the checks every mesh made from it at a size must pass. */
#ifndef BS_TEST_SOUP_UTIL_H
#define BS_TEST_SOUP_UTIL_H

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "mesh_internal.h"

typedef struct soup {
  double *x;
  int32_t *t;
  int64_t np, nt;
  double diag, volume;
} soup;

static inline int have(const char *rel, char *path, size_t n) {
  snprintf(path, n, "%s/%s", BS_SOURCE_DIR, rel);
  return access(path, R_OK) == 0;
}

static inline void soup_read(const char *path, soup *s) {
  bs_error err;
  bs_error_clear(&err);
  *s = (soup){0};
  cr_assert_eq(bs_shim_read_surface(path, &s->x, &s->np, &s->t, &s->nt, &err), 0, "%s", err.msg);
  double lo[3], hi[3];
  bs_bbox(s->np, s->x, lo, hi);
  s->diag = bs_bbox_diagonal(lo, hi);
  s->volume = fabs(bs__soup_volume(s->x, s->t, s->nt));
}

/* The soup of rel (its path into path), or the test is skipped without it. */
static inline void soup_or_skip(const char *rel, char *path, size_t n, soup *s) {
  if (!have(rel, path, n)) cr_skip_test("%s missing (bash setup.sh extracts it from libcgal-demo)", rel);
  soup_read(path, s);
}

static inline void soup_free(soup *s) {
  bs_shim_free(s->x);
  bs_shim_free(s->t);
}

/* Two-sided sampled Hausdorff distance between m's boundary and the soup. */
static inline double hausdorff(const bs_mesh *m, const soup *s, double spacing) {
  bs_error err;
  bs_error_clear(&err);
  double d1 = -1, d2 = -1;
  cr_assert_eq(bs_shim_surface_distance(m->x, m->n_vertices, m->faces, m->n_faces, s->x, s->np, s->t, s->nt, spacing,
                                        &d1, NULL, &err),
               0, "%s", err.msg);
  cr_assert_eq(bs_shim_surface_distance(s->x, s->np, s->t, s->nt, m->x, m->n_vertices, m->faces, m->n_faces, spacing,
                                        &d2, NULL, &err),
               0, "%s", err.msg);
  return fmax(d1, d2);
}

/* The soup as bs_mesh_read meshes it: repaired by bs_surface_prepare
 * (holes closed when close_holes), its diagonal and volume. */
static inline void soup_read_repaired(const char *path, int close_holes, soup *s) {
  bs_error err;
  bs_error_clear(&err);
  *s = (soup){0};
  bs_mesh_read_opts o = {.close_holes = close_holes};
  cr_assert_eq(bs_surface_prepare(path, &s->x, &s->np, &s->t, &s->nt, &o, NULL, &err), 0, "%s", err.msg);
  double lo[3], hi[3];
  bs_bbox(s->np, s->x, lo, hi);
  s->diag = bs_bbox_diagonal(lo, hi);
  s->volume = fabs(bs__soup_volume(s->x, s->t, s->nt));
}

static inline void mesh_checked_soup(const char *rel, const char *path, soup *s, bs_mesh_read_opts o, double vol_tol,
                                     double haus_over_h);

/* Meshes rel at h = diagonal / n with the mesher (BS_SURFACE_*) and checks
 * what every such mesh must hold (mesh_checked_soup). */
static inline void mesh_checked_with(const char *rel, double n, int mesher, double vol_tol, double haus_over_h) {
  char path[1024];
  soup s;
  soup_or_skip(rel, path, sizeof path, &s);
  mesh_checked_soup(rel, path, &s, (bs_mesh_read_opts){.size = s.diag / n, .surface_mesher = mesher}, vol_tol,
                    haus_over_h);
}

/* The same for a surface that needs the repair (holes closed when
 * close_holes), against the repaired surface, with the mesher auto. */
static inline void mesh_checked_repaired(const char *rel, double n, int close_holes, double vol_tol,
                                         double haus_over_h) {
  char path[1024];
  soup s;
  if (!have(rel, path, sizeof path)) cr_skip_test("%s missing (bash setup.sh extracts it from libcgal-demo)", rel);
  soup_read_repaired(path, close_holes, &s);
  mesh_checked_soup(rel, path, &s, (bs_mesh_read_opts){.size = s.diag / n, .close_holes = close_holes}, vol_tol,
                    haus_over_h);
}

/* Meshes path with o and checks what every such mesh must hold:
 * bs_mesh_check, no inverted tet, a boundary that is a closed 2-manifold
 * (bs__boundary_manifold), the gate, volume and Hausdorff bounds against
 * the soup s (freed), the default groups. */
static inline void mesh_checked_soup(const char *rel, const char *path, soup *s, bs_mesh_read_opts o, double vol_tol,
                                     double haus_over_h) {
  double hb = o.size, *h = &hb;
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_mesh_check(m, &err), 0, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_log_info("%s at h %g: %d tets, %d vertices, dihedral min %.3f, radius ratio min %.4f, volume %.6g vs %.6g", rel,
              *h, m->n_tets, m->n_vertices, q.dihedral_min, q.radius_ratio_min, bs_mesh_volume(m), s->volume);
  cr_expect_eq(q.n_inverted, 0, "%d inverted tets", q.n_inverted);
  cr_expect_eq(bs__boundary_manifold(m, path, 0, &err), BS_OK, "%s", err.msg);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL, "min dihedral %g under the default gate", q.dihedral_min);
  double rel_err = fabs(bs_mesh_volume(m) - s->volume) / s->volume;
  cr_expect_leq(rel_err, vol_tol, "volume %g vs the surface's %g: %.3g%% off", bs_mesh_volume(m), s->volume,
                100 * rel_err);
  double d = hausdorff(m, s, *h / 4);
  cr_log_info("%s: Hausdorff distance %g = %.3f h", rel, d, d / *h);
  cr_expect_leq(d, haus_over_h * *h, "Hausdorff distance %g = %.3f h", d, d / *h);
  cr_expect_not_null(bs_mesh_group(m, "body"));
  cr_expect_not_null(bs_mesh_group(m, "surface_1"));
  bs_mesh_destroy(&m);
  soup_free(s);
}

#endif
