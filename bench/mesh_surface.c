/* bench/mesh_surface.c — closed surfaces meshed into tets by CGAL's Mesh_3
 * (the shim, as bs_mesh_read does it; row "cgal"), by CGAL's isotropic
 * surface remeshing then Gmsh's HXT and optimisers to the 10 degree gate
 * (bs_mesh_read with BS_SURFACE_REMESH; row "remesh") and by Gmsh
 * (reparametrised surface; row "gmsh") on the same input and size: a table of tets, seconds, tets per second,
 * smallest dihedral angle, smallest radius ratio, volume error against the
 * surface's enclosed volume and the two-sided sampled Hausdorff distance of
 * the boundary to the input (in units of h).
 *
 *   bench_mesh_surface [options] FILE:N [FILE:N ...]
 *
 * FILE:N meshes FILE at h = (bounding-box diagonal) / N. Options:
 *   --smoother odt|lloyd|none  (default odt)   --iters K (smoother iterations, 10)
 *   --rounds R (perturb + exude rounds, 3)     --target DEG (sliver bound, 10)
 *   --feature DEG (feature angle, 60; 0 none)  --distance F (facet_distance = h / F, 10)
 *   --facet F (facet_size = edge_size = h / F, 1)
 *   scans (not CAD-like) only: --scan-distance F (facet_distance h / F, 25), --angle A
 *   (facet_angle, 30), --radius-edge R (cell_radius_edge_ratio, 2), --sizing K (local size
 *   from the thickness: K elements across thin parts, 2; 0 none), --grad G (its
 *   gradation, 0.5), --floor F (its floor h / F, 8)
 *   --no-perturb  --no-exude  --no-cgal  --no-remesh  --no-gmsh
 *   --close-holes (close small holes, as `bigstep mesh --close-holes`)
 *   --where (under each row, the sample of the mesh's boundary farthest from
 *   the input and the sample of the input farthest from the boundary)
 *   --auto (a row "auto": bs_mesh_read with the library's defaults, the
 *   mesher auto and the gate, as `bigstep mesh info FILE --size H`)
 * A geometry input (.step, .stp, .brep, .iges, .igs, .geo) gets the "auto" row only
 * (bs_mesh_read at h = diagonal / N with the gate, Gmsh's path), measured
 * against the boundary of a reference mesh of the same file at diagonal /
 * --reference N (200; no gate): its sag is about (h_ref / h)^2 of the row's,
 * so the volume and the distance are the row's to within that.
 * Every surface input is read and repaired as bs_mesh_read does it
 * (bs_surface_prepare: self-intersections removed, duplicates merged); the
 * volume and the Hausdorff distance are measured against the repaired
 * surface.
 * Seconds are wall-clock of one run: on a busy machine, say so beside them.
 * Never run by the test suite. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"
#include "bs_shim.h"

enum { RUN_CGAL = 1, RUN_GMSH = 2, RUN_REMESH = 4, RUN_AUTO = 8 };

typedef struct row {
  double h, seconds, dmin, refined, rmin, vol_err, haus, local_min, local_frac;
  double far_mesh[3], far_input[3]; /* the farthest samples of each direction */
  int64_t tets, features;
} row;

static double soup_volume(const double *p, const int32_t *t, int64_t nt) {
  double v = 0;
  for (int64_t f = 0; f < nt; f++) {
    const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return fabs(v / 6.0);
}

/* Quality, volume error and Hausdorff distance (spacing h / 4) of m against the soup. */
static void measure(const bs_mesh *m, const double *p, int64_t np, const int32_t *t, int64_t nt, row *r) {
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  r->tets = m->n_tets;
  r->dmin = q.dihedral_min;
  r->rmin = q.radius_ratio_min;
  double v0 = soup_volume(p, t, nt);
  r->vol_err = (bs_mesh_volume(m) - v0) / v0;
  double d1 = NAN, d2 = NAN;
  bs_error err;
  bs_error_clear(&err);
  if (!bs_shim_surface_distance(m->x, m->n_vertices, m->faces, m->n_faces, p, np, t, nt, r->h / 4, &d1, r->far_mesh, &err) &&
      !bs_shim_surface_distance(p, np, t, nt, m->x, m->n_vertices, m->faces, m->n_faces, r->h / 4, &d2, r->far_input, &err))
    r->haus = fmax(d1, d2);
  else
    r->haus = NAN;
}

static int print_where = 0; /* --where */
static int ref_n = 200;     /* --reference N */

static void print_row(const char *input, const char *mesher, const row *r) {
  printf("%-28s %-6s %10.4g %9lld %8.2f %9.0f %8.2f %8.3f %8.4f %9.2e %7.3f %5lld %6.3f %5.3f\n", input, mesher, r->h,
         (long long)r->tets, r->seconds, r->tets / r->seconds, r->refined, r->dmin, r->rmin, r->vol_err, r->haus / r->h,
         (long long)r->features, r->local_min, r->local_frac);
  if (print_where)
    printf("  farthest: mesh sample (%.5g, %.5g, %.5g) from the input, input sample (%.5g, %.5g, %.5g) from the mesh\n",
           r->far_mesh[0], r->far_mesh[1], r->far_mesh[2], r->far_input[0], r->far_input[1], r->far_input[2]);
}

static int run_cgal(const char *path, const double *p, int64_t np, const int32_t *t, int64_t nt,
                    const bs_shim_mesh3_opts *o, row *r) {
  bs_error err;
  bs_error_clear(&err);
  bs_shim_mesh3_out out;
  double t0 = bs_seconds();
  int rc = bs_shim_mesh_surface(path, p, np, t, nt, o, &out, &err);
  bs_mesh *m = NULL;
  if (!rc) rc = bs_mesh_create((int32_t)out.n_vertices, out.x, (int32_t)out.n_tets, out.tets, 0, NULL, &m, &err);
  r->seconds = bs_seconds() - t0;
  r->refined = out.refined_dihedral;
  r->features = out.n_features;
  r->local_min = out.local_size_min / r->h;
  r->local_frac = out.local_fraction;
  bs_shim_free(out.x);
  bs_shim_free(out.tets);
  if (rc) {
    printf("%-28s cgal   failed: %s\n", path, err.msg);
    return rc;
  }
  measure(m, p, np, t, nt, r);
  bs_mesh_destroy(&m);
  return 0;
}

/* One bs_mesh_read of path at r->h through mesher (BS_SURFACE_*, named
 * label in the table) with the given gate (-1: none), timed and measured;
 * a refusal is printed with its message. Gmsh's row: its reparametrised
 * surface, no gate (raw Gmsh); remesh: CGAL isotropic remeshing, Gmsh HXT
 * and Gmsh's optimisers to the default gate. */
static void run_read(const char *path, const double *p, int64_t np, const int32_t *t, int64_t nt, int mesher,
                     double gate, int close_holes, const char *label, row *r) {
  bs_error err;
  bs_error_clear(&err);
  bs_mesh_read_opts o = {.size = r->h, .min_dihedral = gate, .surface_mesher = mesher, .close_holes = close_holes};
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  int rc = bs_mesh_read(path, &o, &m, &err);
  r->seconds = bs_seconds() - t0;
  r->refined = NAN;
  r->features = 0;
  r->local_min = r->local_frac = NAN;
  if (rc) {
    printf("%-28s %-6s failed after %.1f s: %.300s\n", path, label, r->seconds, err.msg);
    return;
  }
  measure(m, p, np, t, nt, r);
  print_row(path, label, r);
  bs_mesh_destroy(&m);
}

static int parse_opts(int argc, char **argv, bs_shim_mesh3_opts *o, int *which, double *dist_frac, double *facet_frac,
                      double *floor_frac, double *scan_frac, int *close_holes, int *first) {
  *o = (bs_shim_mesh3_opts){.feature_angle = 60, .smoother = BS_SHIM_SMOOTH_ODT, .smooth_iterations = 10,
                            .perturb = 1, .exude = 1, .target_dihedral = 10, .max_rounds = 3,
                            .scan_facet_angle = 30, .scan_radius_edge = 2, .thickness_elements = 2,
                            .size_gradation = 0.5};
  *which = RUN_CGAL | RUN_GMSH | RUN_REMESH;
  *dist_frac = 10;
  *facet_frac = 1;
  *floor_frac = 8;
  *scan_frac = 25;
  *close_holes = 0;
  int i = 1;
  for (; i < argc && !strncmp(argv[i], "--", 2); i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : "";
    if (!strcmp(a, "--no-gmsh")) *which &= ~RUN_GMSH;
    else if (!strcmp(a, "--no-cgal")) *which &= ~RUN_CGAL;
    else if (!strcmp(a, "--no-remesh")) *which &= ~RUN_REMESH;
    else if (!strcmp(a, "--no-perturb")) o->perturb = 0;
    else if (!strcmp(a, "--no-exude")) o->exude = 0;
    else if (!strcmp(a, "--close-holes")) *close_holes = 1;
    else if (!strcmp(a, "--auto")) *which |= RUN_AUTO;
    else if (!strcmp(a, "--where")) print_where = 1;
    else if (!strcmp(a, "--reference") && ++i) ref_n = atoi(v);
    else if (!strcmp(a, "--smoother") && ++i)
      o->smoother = !strcmp(v, "lloyd") ? BS_SHIM_SMOOTH_LLOYD : !strcmp(v, "none") ? BS_SHIM_SMOOTH_NONE : BS_SHIM_SMOOTH_ODT;
    else if (!strcmp(a, "--iters") && ++i) o->smooth_iterations = atoi(v);
    else if (!strcmp(a, "--rounds") && ++i) o->max_rounds = atoi(v);
    else if (!strcmp(a, "--target") && ++i) o->target_dihedral = atof(v);
    else if (!strcmp(a, "--feature") && ++i) o->feature_angle = atof(v);
    else if (!strcmp(a, "--distance") && ++i) *dist_frac = atof(v);
    else if (!strcmp(a, "--facet") && ++i) *facet_frac = atof(v);
    else if (!strcmp(a, "--sizing") && ++i) o->thickness_elements = atof(v);
    else if (!strcmp(a, "--angle") && ++i) o->scan_facet_angle = atof(v);
    else if (!strcmp(a, "--radius-edge") && ++i) o->scan_radius_edge = atof(v);
    else if (!strcmp(a, "--scan-distance") && ++i) *scan_frac = atof(v);
    else if (!strcmp(a, "--grad") && ++i) o->size_gradation = atof(v);
    else if (!strcmp(a, "--floor") && ++i) *floor_frac = atof(v);
    else {
      fprintf(stderr, "bench_mesh_surface: unknown option %s\n", a);
      return 2;
    }
  }
  *first = i;
  return i < argc ? 0 : 2;
}

static int is_geometry(const char *path) {
  const char *dot = strrchr(path, '.');
  static const char *ext[] = {".step", ".stp", ".brep", ".iges", ".igs", ".geo", ".STEP", ".STP"};
  for (size_t i = 0; dot && i < sizeof ext / sizeof *ext; i++)
    if (!strcmp(dot, ext[i])) return 1;
  return 0;
}

/* The boundary of path's mesh at diagonal / ref_n (no gate) into the soup
 * (p, np, t, nt), its bounding box into lo, hi; the diagonal from Gmsh's
 * own mesh of the file. */
static int geometry_reference(const char *path, double **p, int64_t *np, int32_t **t, int64_t *nt, double lo[3],
                              double hi[3]) {
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  bs_mesh_read_opts o = {.min_dihedral = -1};
  if (bs_mesh_read(path, &o, &m, &err)) return printf("%-28s        failed: %s\n", path, err.msg), 1;
  bs_bbox(m->n_vertices, m->x, lo, hi);
  bs_mesh_destroy(&m);
  o.size = bs_bbox_diagonal(lo, hi) / ref_n;
  if (bs_mesh_read(path, &o, &m, &err)) return printf("%-28s        reference failed: %s\n", path, err.msg), 1;
  *np = m->n_vertices, *nt = m->n_faces;
  *p = malloc(3 * (size_t)*np * sizeof **p);
  *t = malloc(3 * (size_t)*nt * sizeof **t);
  if (*p && *t) memcpy(*p, m->x, 3 * (size_t)*np * sizeof **p), memcpy(*t, m->faces, 3 * (size_t)*nt * sizeof **t);
  printf("%-28s        reference: h %.4g, %d tets, %d boundary triangles\n", path, o.size, m->n_tets, m->n_faces);
  bs_mesh_destroy(&m);
  return !*p || !*t;
}

/* Geometry input: the auto row against geometry_reference's boundary. */
static void run_geometry(const char *path, double n, int close_holes) {
  double *p = NULL, lo[3], hi[3];
  int32_t *t = NULL;
  int64_t np = 0, nt = 0;
  if (!geometry_reference(path, &p, &np, &t, &nt, lo, hi)) {
    row r = {.h = bs_bbox_diagonal(lo, hi) / n};
    run_read(path, p, np, t, nt, BS_SURFACE_AUTO, 0, close_holes, "auto", &r);
  }
  free(p);
  free(t);
}

int main(int argc, char **argv) {
  bs_shim_mesh3_opts o;
  int which, first, close_holes;
  double dist_frac, facet_frac, floor_frac, scan_frac;
  if (parse_opts(argc, argv, &o, &which, &dist_frac, &facet_frac, &floor_frac, &scan_frac, &close_holes, &first)) {
    fprintf(stderr, "usage: bench_mesh_surface [options] FILE:N ... (see the file's comment)\n");
    return 2;
  }
  printf("%-28s %-6s %10s %9s %8s %9s %8s %8s %8s %9s %7s %5s %6s %5s\n", "input", "mesher", "h", "tets", "seconds", "tets/s",
         "refined", "dih.min", "rr.min", "vol.err", "haus/h", "feat", "lmin/h", "lfrac");
  for (int a = first; a < argc; a++) {
    char path[1024];
    snprintf(path, sizeof path, "%s", argv[a]);
    char *colon = strrchr(path, ':');
    double n = colon ? atof(colon + 1) : 30;
    if (colon) *colon = '\0';
    if (is_geometry(path)) {
      run_geometry(path, n, close_holes);
      fflush(stdout);
      continue;
    }
    double *p = NULL, lo[3], hi[3];
    int32_t *t = NULL;
    int64_t np = 0, nt = 0;
    bs_error err;
    bs_error_clear(&err);
    bs_mesh_read_opts ro = {.close_holes = close_holes};
    if (bs_surface_prepare(path, &p, &np, &t, &nt, &ro, NULL, &err)) {
      printf("%-28s        failed: %s\n", path, err.msg);
      continue;
    }
    bs_bbox(np, p, lo, hi);
    row r = {.h = bs_bbox_diagonal(lo, hi) / n};
    o.size = r.h;
    o.facet_distance = r.h / dist_frac;
    o.facet_size = r.h / facet_frac;
    o.min_size = r.h / floor_frac;
    o.scan_facet_distance = r.h / scan_frac;
    if ((which & RUN_CGAL) && !run_cgal(path, p, np, t, nt, &o, &r)) print_row(path, "cgal", &r);
    if (which & RUN_AUTO) run_read(path, p, np, t, nt, BS_SURFACE_AUTO, 0, close_holes, "auto", &r);
    if (which & RUN_REMESH) run_read(path, p, np, t, nt, BS_SURFACE_REMESH, 0, close_holes, "remesh", &r);
    if (which & RUN_GMSH) run_read(path, p, np, t, nt, BS_SURFACE_GMSH, -1, close_holes, "gmsh", &r);
    bs_shim_free(p);
    bs_shim_free(t);
    fflush(stdout);
  }
  return 0;
}
