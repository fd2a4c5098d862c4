/* The alpha wrap (bs_shim_alpha_wrap) and the inputs the surface repair
 * alone cannot mesh (issue 44), each made here: two cubes touching at an
 * edge (non-manifold), a soup of overlapping quads (a cube whose faces
 * overhang each other), a box with a non-planar 4-edge hole, an STL written
 * by the test. Every mesh must pass the quality gate, bs_mesh_check, a
 * closed 2-manifold boundary and the volume check. */
#define _GNU_SOURCE

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_shim.h"
#include "mesh_internal.h"

/* ---- soups made here ----------------------------------------------------- */

typedef struct tsoup {
  double x[3 * 256];
  int32_t t[3 * 512];
  int np, nt;
} tsoup;

static int add_point(tsoup *s, double a, double b, double c) {
  s->x[3 * s->np] = a, s->x[3 * s->np + 1] = b, s->x[3 * s->np + 2] = c;
  return s->np++;
}

static void add_tri(tsoup *s, int a, int b, int c) {
  s->t[3 * s->nt] = a, s->t[3 * s->nt + 1] = b, s->t[3 * s->nt + 2] = c;
  s->nt++;
}

/* The box [lo, hi] as 12 outward triangles; its 8 corners appended (corner
 * i at x = bit 0, y = bit 1, z = bit 2 of i). skip_top: no z = hi face. */
static void add_box(tsoup *s, const double lo[3], const double hi[3], int skip_top) {
  int c[8];
  for (int i = 0; i < 8; i++) c[i] = add_point(s, i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
  static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6; f++) {
    if (skip_top && f == 1) continue;
    add_tri(s, c[q[f][0]], c[q[f][1]], c[q[f][2]]);
    add_tri(s, c[q[f][0]], c[q[f][2]], c[q[f][3]]);
  }
}

static void write_off(const char *path, const tsoup *s) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  fprintf(f, "OFF\n%d %d 0\n", s->np, s->nt);
  for (int i = 0; i < s->np; i++) fprintf(f, "%.17g %.17g %.17g\n", s->x[3 * i], s->x[3 * i + 1], s->x[3 * i + 2]);
  for (int e = 0; e < s->nt; e++) fprintf(f, "3 %d %d %d\n", s->t[3 * e], s->t[3 * e + 1], s->t[3 * e + 2]);
  fclose(f);
}

/* A binary STL of the soup's triangles (each with its own three points). */
static void write_stl(const char *path, const tsoup *s) {
  FILE *f = fopen(path, "wb");
  cr_assert_not_null(f);
  char header[80] = "binary STL written by test_mesh_wrap";
  fwrite(header, 1, 80, f);
  uint32_t n = (uint32_t)s->nt;
  fwrite(&n, 4, 1, f);
  for (int e = 0; e < s->nt; e++) {
    float v[12] = {0};
    for (int k = 0; k < 3; k++)
      for (int c = 0; c < 3; c++) v[3 + 3 * k + c] = (float)s->x[3 * s->t[3 * e + k] + c];
    uint16_t attr = 0;
    fwrite(v, 4, 12, f);
    fwrite(&attr, 2, 1, f);
  }
  fclose(f);
}

static char *temp_path(const char *ext) {
  static char path[128];
  snprintf(path, sizeof path, "/tmp/bs_test_wrap_%d_%s", (int)getpid(), ext);
  return path;
}

/* ---- checks -------------------------------------------------------------- */

/* The wrap of s at h: closed, 2-manifold, no self-intersection (CGAL's PMP
 * in the shim), outward, and within the volume check of bs_shim.h against
 * volume (the true volume of the shape). */
static void check_wrap(const tsoup *s, double h, double volume) {
  bs_error err;
  bs_error_clear(&err);
  bs_shim_wrap_opts o = {.size = h};
  bs_shim_wrap_out w;
  cr_assert_eq(bs_shim_alpha_wrap("soup", s->x, s->np, s->t, s->nt, &o, &w, &err), BS_OK, "%s", err.msg);
  bs_shim_surface_audit_out a;
  cr_assert_eq(bs_shim_surface_audit(w.points, w.n_points, w.tris, w.n_tris, &a, &err), BS_OK, "%s", err.msg);
  cr_expect(a.manifold && a.closed && !a.self_intersecting, "wrap: manifold %d closed %d self-intersecting %d",
            a.manifold, a.closed, a.self_intersecting);
  cr_expect_float_eq(a.volume, w.volume, 1e-9 * volume);
  cr_expect_eq(w.alpha, BS_WRAP_ALPHA * h);
  cr_expect_eq(w.offset, BS_WRAP_OFFSET * h);
  const double bound = 2 * w.offset * w.area_in + BS_WRAP_VOLUME_TOL * volume;
  cr_log_info("wrap at h %g: %lld triangles, volume %.6g vs %.6g (%+.3f%%, bound %.3f%%), %.3f s", h,
              (long long)w.n_tris, w.volume, volume, 100 * (w.volume - volume) / volume, 100 * bound / volume,
              w.seconds);
  cr_expect_leq(fabs(w.volume - volume), bound, "wrap volume %g vs %g", w.volume, volume);
  bs_shim_free(w.points);
  bs_shim_free(w.tris);
}

/* bs_mesh_read of path with o: the mesh passes bs_mesh_check, the gate,
 * has a closed 2-manifold boundary and a volume within vol_tol of volume. */
static bs_mesh *check_mesh(const char *path, bs_mesh_read_opts o, double volume, double vol_tol) {
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  bs_surface_report rep = {0};
  o.report = &rep;
  double t0 = bs_seconds();
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  const double v = bs_mesh_volume(m);
  cr_log_info("%s at h %g: %d tets, min dihedral %.2f, volume %.6g vs %.6g (%+.3f%%), wrapped %d (volume change "
              "%+.3f%%), tet remeshing %d (%.2f -> %.2f), %.2f s",
              path, o.size, m->n_tets, q.dihedral_min, v, volume, 100 * (v - volume) / volume, rep.wrapped,
              100 * rep.wrap_volume_change, rep.lifted, rep.lift_dihedral_in, rep.lift_dihedral, bs_seconds() - t0);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL, "min dihedral %g", q.dihedral_min);
  cr_expect_eq(bs__boundary_manifold(m, path, 0, &err), BS_OK, "%s", err.msg);
  cr_expect_leq(fabs(v - volume), vol_tol * volume, "volume %g vs %g", v, volume);
  return m;
}

/* ---- the failure classes -------------------------------------------------- */

/* Two unit cubes sharing the edge x = y = 1: a non-manifold edge. */
static void two_cubes(tsoup *s) {
  memset(s, 0, sizeof *s);
  add_box(s, (double[3]){0, 0, 0}, (double[3]){1, 1, 1}, 0);
  add_box(s, (double[3]){1, 1, 0}, (double[3]){2, 2, 1}, 0);
}

Test(mesh_wrap, two_cubes_touching_at_an_edge) {
  tsoup s;
  two_cubes(&s);
  check_wrap(&s, 0.2, 2.0);
  char *path = temp_path("edge.off");
  write_off(path, &s);
  bs_mesh *m = check_mesh(path, (bs_mesh_read_opts){.size = 0.2}, 2.0, 0.04);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* The unit cube as six quads, each overhanging its neighbours by 0.5% of the
 * edge and pushed out by 1e-4: nearly overlapping facets, no shared vertex. */
static void overlapping_quads(tsoup *s) {
  memset(s, 0, sizeof *s);
  const double e = 0.005, d = 1e-4;
  for (int axis = 0; axis < 3; axis++)
    for (int side = 0; side < 2; side++) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      int c[4];
      for (int k = 0; k < 4; k++) {
        double p[3];
        p[axis] = side ? 1 + d : -d;
        p[u] = (k == 1 || k == 2) ? 1 + e : -e;
        p[v] = (k >= 2) ? 1 + e : -e;
        c[k] = add_point(s, p[0], p[1], p[2]);
      }
      add_tri(s, c[0], c[1], c[2]);
      add_tri(s, c[0], c[2], c[3]);
    }
}

Test(mesh_wrap, soup_of_overlapping_quads) {
  tsoup s;
  overlapping_quads(&s);
  check_wrap(&s, 0.125, 1.0);
  char *path = temp_path("quads.off");
  write_off(path, &s);
  bs_mesh *m = check_mesh(path, (bs_mesh_read_opts){.size = 0.125}, 1.0, 0.04);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* A box 2 x 1 x 1 whose top is a non-planar quad (corners (0,0) and (2,1)
 * raised to z = 1.3: a saddle) left open: a hole of 4 edges, closed on
 * request. Closed along one diagonal or the other, it encloses 2.4 or 2.2. */
Test(mesh_wrap, non_planar_four_edge_hole) {
  tsoup s;
  memset(&s, 0, sizeof s);
  add_box(&s, (double[3]){0, 0, 0}, (double[3]){2, 1, 1}, 1);
  s.x[3 * 4 + 2] = 1.3; /* corner 4: (0, 0, 1) */
  s.x[3 * 7 + 2] = 1.3; /* corner 7: (2, 1, 1) */
  char *path = temp_path("hole.off");
  write_off(path, &s);
  bs_mesh *m = check_mesh(path, (bs_mesh_read_opts){.size = 0.15, .close_holes = 1, .max_hole = 1}, 2.3, 0.045);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* Two unit cubes 0.01 apart, meshed at 0.25: one mesh per solid, so no tet
 * joins them (meshed whole, the mesh had volume 2.031: the gap filled). A third cube, 0.2 on a side (diagonal 0.35, under
 * twice the size), is meshed at half its diagonal rather than lost. The
 * corpus's bones.off is of this class. */
Test(mesh_wrap, separate_solids_closer_than_the_size_stay_apart) {
  tsoup s;
  memset(&s, 0, sizeof s);
  add_box(&s, (double[3]){0, 0, 0}, (double[3]){1, 1, 1}, 0);
  add_box(&s, (double[3]){1.01, 0, 0}, (double[3]){2.01, 1, 1}, 0);
  add_box(&s, (double[3]){3, 0, 0}, (double[3]){3.2, 0.2, 0.2}, 0);
  char *path = temp_path("apart.off");
  write_off(path, &s);
  bs_mesh *m = check_mesh(path, (bs_mesh_read_opts){.size = 0.25}, 2.008, 0.005);
  bs_error err;
  bs_error_clear(&err);
  cr_expect_eq(bs__boundary_manifold(m, path, 3, &err), BS_OK, "three pieces: %s", err.msg);
  int32_t small = 0; /* vertices of the small cube */
  for (int32_t v = 0; v < m->n_vertices; v++) small += m->x[3 * v] > 2.5;
  cr_expect_geq(small, 8, "the small cube has %d vertices", small);
  double gap_lo = INFINITY, gap_hi = -INFINITY; /* no vertex inside the gap */
  for (int32_t v = 0; v < m->n_vertices; v++)
    if (m->x[3 * v] > 1 + 1e-9 && m->x[3 * v] < 1.01 - 1e-9) gap_lo = fmin(gap_lo, m->x[3 * v]), gap_hi = fmax(gap_hi, m->x[3 * v]);
  cr_expect(!isfinite(gap_lo), "vertices in the gap, x in [%g, %g]", gap_lo, gap_hi);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* A unit cube with a fin 0.04 thick and 2 long on one side (an extruded L:
 * volume 1.08), meshed at 0.25 (the fin is h / 6 thick): whether a mesher
 * takes it or every one, the wrap's mesh too, refuses it (today: "the mesh's
 * boundary is not a closed 2-manifold"), the report keeps the surface the
 * repair made, not the wrap's that was tried and dropped. */
Test(mesh_wrap, a_refused_wrap_leaves_the_report_on_the_repaired_surface) {
  static const double xz[8][2] = {{0, 0}, {1, 0}, {1, 0.48}, {3, 0.48}, {3, 0.52}, {1, 0.52}, {1, 1}, {0, 1}};
  static const int cap[6][3] = {{0, 1, 2}, {0, 2, 5}, {0, 5, 6}, {0, 6, 7}, {2, 3, 4}, {2, 4, 5}};
  tsoup s;
  memset(&s, 0, sizeof s);
  for (int y = 0; y < 2; y++)
    for (int i = 0; i < 8; i++) add_point(&s, xz[i][0], y, xz[i][1]);
  for (int k = 0; k < 6; k++) {
    add_tri(&s, cap[k][0], cap[k][1], cap[k][2]);
    add_tri(&s, cap[k][0] + 8, cap[k][2] + 8, cap[k][1] + 8);
  }
  for (int i = 0; i < 8; i++) {
    const int j = (i + 1) % 8;
    add_tri(&s, i, j + 8, j);
    add_tri(&s, i, i + 8, j + 8);
  }
  char *path = temp_path("fin.off");
  write_off(path, &s);
  bs_surface_report rep = {0};
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  const int rc = bs_mesh_read(path, &(bs_mesh_read_opts){.size = 0.25, .report = &rep}, &m, &err);
  cr_log_info("%s: rc %d, %s; report: %lld triangles, volume %g, wrapped %d (alpha %g)", path, rc, err.msg,
              (long long)rep.tris_out, rep.volume, rep.wrapped, rep.wrap_alpha);
  if (rc) {
    cr_expect_eq(rc, BS_EINPUT, "%s", err.msg);
    cr_expect_eq(rep.wrapped, 0);
    cr_expect_eq(rep.tris_out, 28, "the report shows %lld triangles, the repaired surface has 28",
                 (long long)rep.tris_out);
    cr_expect_float_eq(rep.volume, 1.08, 1e-12, "the report's volume %g is not the surface's 1.08", rep.volume);
  } else {
    cr_expect_float_eq(bs_mesh_volume(m), 1.08, 0.0108, "a mesh of volume %g", bs_mesh_volume(m));
  }
  bs_mesh_destroy(&m);
  unlink(path);
}

/* The two cubes as a binary STL (every triangle its own points): the same
 * repair and wrap path as OFF. */
Test(mesh_wrap, stl_written_by_the_test) {
  tsoup s;
  two_cubes(&s);
  char *path = temp_path("cubes.stl");
  write_stl(path, &s);
  bs_mesh *m = check_mesh(path, (bs_mesh_read_opts){.size = 0.2}, 2.0, 0.04);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* An open surface without close_holes is still refused (the wrap would
 * seal what was not asked to be sealed). */
Test(mesh_wrap, open_surface_still_refused) {
  tsoup s;
  memset(&s, 0, sizeof s);
  add_box(&s, (double[3]){0, 0, 0}, (double[3]){1, 1, 1}, 1);
  char *path = temp_path("open.off");
  write_off(path, &s);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  cr_expect_eq(bs_mesh_read(path, &(bs_mesh_read_opts){.size = 0.2}, &m, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "not closed") != NULL, "%s", err.msg);
  bs_mesh_destroy(&m);
  unlink(path);
}

/* A soup of collinear triangles has nothing to wrap: a refusal, not a
 * crash inside CGAL. */
Test(mesh_wrap, degenerate_soup_refused) {
  static const double x[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  static const int32_t t[6] = {0, 1, 1, 0, 1, 2};
  bs_error err;
  bs_error_clear(&err);
  bs_shim_wrap_out w;
  cr_expect_eq(bs_shim_alpha_wrap("line", x, 3, t, 2, &(bs_shim_wrap_opts){.size = 0.1}, &w, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "degenerate") != NULL, "%s", err.msg);
}
