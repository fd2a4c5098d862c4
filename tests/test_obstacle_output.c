/* Obstacles in the output: the triangle surface of every analytic shape
 * (plane, sphere, box, cylinder, torus; inside-out; static and moving) lies
 * on the zero level set of the obstacle at that time, its triangles face
 * grad phi (out of the obstacle), the closed ones are closed and consistently
 * oriented with the enclosed volume of the shape; a run folder writes a file
 * per moving obstacle per frame, one per static obstacle, a PVD each, and a
 * grid obstacle's .vti read back gives phi at its nodes where they are. */
#define _GNU_SOURCE /* mkdtemp */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_levelset.h"
#include "bs_ls_surface.h"
#include "bs_obstacles.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_vtu_read.h"

static const double PI = 3.14159265358979323846;

static bs_levelset *shape(int kind) {
  bs_levelset *ls = NULL;
  bs_error err;
  const double c[3] = {0.3, -0.2, 0.5}, axis[3] = {1, 2, -0.5}, half[3] = {0.4, 0.25, 0.6}, n[3] = {0.2, 1, 0.1};
  int st = kind == 0   ? bs_levelset_create_halfspace(n, 0.3, &ls, &err)
           : kind == 1 ? bs_levelset_create_sphere(c, 0.7, &ls, &err)
           : kind == 2 ? bs_levelset_create_box(c, half, &ls, &err)
           : kind == 3 ? bs_levelset_create_cylinder(c, axis, 0.4, 0.9, &ls, &err)
                       : bs_levelset_create_torus(c, axis, 1.0, 0.3, &ls, &err);
  cr_assert_eq(st, 0, "%s", err.msg);
  return ls;
}

/* The volume the shape encloses, and that of its tessellation (polygons). */
static double volume(int kind, double *tess) {
  const int S = 64;
  const double poly = 0.5 * S * sin(2 * PI / S); /* polygon area over r^2 */
  switch (kind) {
    case 1: *tess = 0.0; return 4.0 / 3.0 * PI * 0.343;
    case 2: *tess = 8 * 0.4 * 0.25 * 0.6; return *tess;
    case 3: *tess = poly * 0.16 * 1.8; return PI * 0.16 * 1.8;
    case 4: *tess = 0.0; return 2 * PI * PI * 1.0 * 0.09;
  }
  return 0;
}

static void sub(const double *a, const double *b, double *d) {
  for (int k = 0; k < 3; k++) d[k] = a[k] - b[k];
}
static void cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1], c[1] = a[2] * b[0] - a[0] * b[2], c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Every directed edge (a, b) appears once and (b, a) once: closed and
 * consistently oriented. */
static void check_closed(const bs_ls_surface *s, const char *what) {
  int32_t n = s->n_points;
  int *count = calloc((size_t)n * n, sizeof(int));
  for (int32_t t = 0; t < s->n_tris; t++)
    for (int e = 0; e < 3; e++) count[(size_t)s->tris[3 * t + e] * n + s->tris[3 * t + (e + 1) % 3]]++;
  for (int32_t a = 0; a < n; a++)
    for (int32_t b = 0; b < n; b++) {
      int ab = count[(size_t)a * n + b], ba = count[(size_t)b * n + a];
      cr_assert(ab <= 1, "%s: edge %d-%d used twice in one direction", what, a, b);
      cr_assert_eq(ab, ba, "%s: edge %d-%d: %d one way, %d the other", what, a, b, ab, ba);
    }
  free(count);
}

static void check_surface(int kind, int complement, double t) {
  bs_levelset *ls = shape(kind);
  bs_error err;
  char what[64];
  snprintf(what, sizeof what, "%s%s at t = %g", bs_levelset_kind_name(ls->kind), complement ? " (inside out)" : "", t);
  if (complement) bs_levelset_set_complement(ls, 1);
  if (t > 0) {
    const double v[3] = {0.5, -1, 2}, w[3] = {1, 0.5, -2};
    cr_assert_eq(bs_levelset_set_velocity(ls, v, w, &err), 0, "%s", err.msg);
  }
  const double lo[3] = {-1, 0, -1}, hi[3] = {1, 2, 3};
  bs_ls_surface s;
  cr_assert_eq(bs_ls_surface_make(ls, t, lo, hi, &s, &err), 0, "%s", err.msg);
  cr_assert_gt(s.n_tris, 0);
  for (int32_t i = 0; i < s.n_points; i++) {
    double phi = bs_levelset_eval(ls, t, s.x + 3 * i, NULL, NULL);
    cr_assert_lt(fabs(phi), 1e-13, "%s: point %d off the surface, phi = %g", what, i, phi);
  }
  double vol = 0;
  for (int32_t k = 0; k < s.n_tris; k++) {
    const double *a = s.x + 3 * s.tris[3 * k], *b = s.x + 3 * s.tris[3 * k + 1], *c = s.x + 3 * s.tris[3 * k + 2];
    double ab[3], ac[3], nrm[3], ctr[3], g[3], bc[3];
    sub(b, a, ab), sub(c, a, ac), cross(ab, ac, nrm);
    for (int q = 0; q < 3; q++) ctr[q] = (a[q] + b[q] + c[q]) / 3;
    bs_levelset_eval(ls, t, ctr, g, NULL);
    double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    cr_assert_gt((nrm[0] * g[0] + nrm[1] * g[1] + nrm[2] * g[2]) / len, 0.9, "%s: triangle %d does not face grad phi", what, k);
    cross(b, c, bc);
    vol += (a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]) / 6;
  }
  if (kind > 0) {
    check_closed(&s, what);
    double tess = 0, exact = volume(kind, &tess), want = tess > 0 ? tess : exact, sign = complement ? -1 : 1;
    cr_assert_lt(fabs(vol - sign * want), (tess > 0 ? 1e-12 : 0.03) * want, "%s: encloses %g, the shape %g", what, vol,
                 sign * want);
  }
  bs_ls_surface_free(&s);
  bs_levelset_destroy(&ls);
}

Test(obstacle_output, surfaces_lie_on_the_level_set_facing_out) {
  for (int kind = 0; kind < 5; kind++)
    for (int comp = 0; comp < 2; comp++) {
      check_surface(kind, comp, 0.0);
      check_surface(kind, comp, 0.7);
    }
}

Test(obstacle_output, a_grid_has_no_surface) {
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1}, c[3] = {0, 0, 0};
  bs_levelset *sp = NULL, *g = NULL;
  bs_error err;
  cr_assert_eq(bs_levelset_create_sphere(c, 0.5, &sp, &err), 0);
  cr_assert_eq(bs_levelset_grid_sample(sp, 0, lo, hi, 0.25, &g, &err), 0, "%s", err.msg);
  bs_ls_surface s;
  cr_assert_eq(bs_ls_surface_make(g, 0, NULL, NULL, &s, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "image data"), "%s", err.msg);
  bs_levelset_destroy(&sp);
  bs_levelset_destroy(&g);
}

/* ---- a run folder ---------------------------------------------------------- */

static char *slurp(const char *path) {
  FILE *fp = fopen(path, "rb");
  cr_assert_not_null(fp, "cannot read %s", path);
  fseek(fp, 0, SEEK_END);
  long n = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  cr_assert_eq(fread(s, 1, (size_t)n, fp), (size_t)n);
  s[n] = 0;
  fclose(fp);
  return s;
}

static void numbers(const char *s, const char *attr, double *out, int n) {
  char key[64];
  snprintf(key, sizeof key, " %s=\"", attr);
  const char *p = strstr(s, key);
  cr_assert_not_null(p, "no %s", attr);
  p += strlen(key);
  for (int i = 0; i < n; i++) out[i] = strtod(p, (char **)&p);
}

/* Every node of the written grid, placed by Origin, Spacing and Direction,
 * holds phi of the obstacle there at time t. */
static void check_vti(const char *path, const bs_levelset *ls, double t) {
  char *s = slurp(path);
  double ext[6], o[3], h[3], D[9];
  numbers(s, "WholeExtent", ext, 6);
  numbers(s, "Origin", o, 3);
  numbers(s, "Spacing", h, 3);
  numbers(s, "Direction", D, 9);
  const char *u = strchr(strstr(s, "<AppendedData"), '_');
  const double *phi = (const double *)(u + 1 + 8);
  int n[3] = {(int)ext[1] + 1, (int)ext[3] + 1, (int)ext[5] + 1}, checked = 0;
  for (int k = 0; k < n[2]; k += 3)
    for (int j = 0; j < n[1]; j += 3)
      for (int i = 0; i < n[0]; i += 3) {
        double q[3] = {h[0] * i, h[1] * j, h[2] * k}, x[3];
        for (int r = 0; r < 3; r++) x[r] = o[r] + D[3 * r] * q[0] + D[3 * r + 1] * q[1] + D[3 * r + 2] * q[2];
        double want = bs_levelset_eval(ls, t, x, NULL, NULL), got = phi[i + n[0] * (j + n[1] * (size_t)k)];
        cr_assert_lt(fabs(got - want), 1e-9, "%s node (%d, %d, %d): %g, phi there %g", path, i, j, k, got, want);
        checked++;
      }
  cr_assert_gt(checked, 100);
  free(s);
}

static int exists(const char *dir, const char *name) {
  char p[512];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  return access(p, F_OK) == 0;
}

static const char *scene_text =
    "{\"time\": {\"fps\": 24, \"frames\": 2},\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1]},\n"
    "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": -2},\n"
    "   {\"shape\": \"torus\", \"center\": [4, 0, 0], \"major\": 1, \"minor\": 0.2, \"velocity\": [0, 1, 0]},\n"
    "   {\"shape\": \"grid\", \"file\": \"%s/data/levelsets/bowl.bsls\", \"collision\": \"penalty\",\n"
    "    \"inside_out\": true, \"velocity\": [1, 0, 5], \"angular_velocity\": [0, 0, 2]}],\n"
    " \"output\": {\"dir\": \"%s\", \"compress\": true}}\n";

Test(obstacle_output, a_run_folder_writes_the_obstacles) {
  char dir[] = "/tmp/bs_test_obst_XXXXXX", text[2048], p[512];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(text, sizeof text, scene_text, BS_SOURCE_DIR, dir);
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_parse(text, "obst.json", 0, NULL, &sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_create(dir, s, &rf, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_run(s, bs_runfolder_frame, rf, NULL, &err), 0, "%s", err.msg);
  bs_runfolder_destroy(&rf);
  cr_assert(exists(dir, "obstacle_0.vtu") && !exists(dir, "obstacle_0_00001.vtu"), "a static obstacle: one file");
  for (int f = 0; f <= 2; f++) {
    char a[64], b[64];
    snprintf(a, sizeof a, "obstacle_1_%05d.vtu", f);
    snprintf(b, sizeof b, "obstacle_2_%05d.vti", f);
    cr_assert(exists(dir, a) && exists(dir, b), "frame %d of the moving obstacles", f);
  }
  for (int k = 0; k < 3; k++) {
    snprintf(p, sizeof p, "%s/obstacles_%d.pvd", dir, k);
    bs_pvd *pvd = NULL;
    cr_assert_eq(bs_pvd_read(p, &pvd, &err), 0, "%s", err.msg);
    cr_assert_eq(pvd->n, 3, "frames 0, 1, 2");
    cr_assert_float_eq(pvd->times[2], 2.0 / 24, 1e-15);
    bs_pvd_destroy(&pvd);
  }
  const bs_levelset *grid = bs_obstacles_levelset(s->obstacles, 2);
  cr_assert(!bs_levelset_is_analytic(grid) && bs_levelset_is_complement(grid));
  snprintf(p, sizeof p, "%s/obstacle_2_00002.vti", dir);
  check_vti(p, grid, 2.0 / 24);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  snprintf(p, sizeof p, "rm -rf '%s'", dir);
  cr_assert_eq(system(p), 0);
}
