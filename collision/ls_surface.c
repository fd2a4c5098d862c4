/* ls_surface.c — analytic obstacles as triangle surfaces at a time t (see
 * bs_ls_surface.h). Each shape is tessellated in its local frame as a
 * parametric surface p(u, v) whose triangles follow p_u x p_v, the outward
 * normal; the complement reverses them; the frame at t places the points. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_ls_surface.h"

static const double PI = 3.14159265358979323846;

enum { PLANE_N = 8, SPHERE_RINGS = 16, SPHERE_SEGS = 32, CYL_SEGS = 64, TORUS_U = 64, TORUS_V = 32 };

static int reserve(bs_ls_surface *s, int32_t np, int32_t nt, bs_error *err) {
  s->x = malloc(sizeof(double) * 3 * (size_t)np);
  s->tris = malloc(sizeof(int32_t) * 3 * (size_t)nt);
  if (!s->x || !s->tris) {
    bs_ls_surface_free(s);
    return bs_error_set(err, BS_ENOMEM, "out of memory for an obstacle surface (%d points)", np);
  }
  return 0;
}

static int32_t point(bs_ls_surface *s, double a, double b, double c) {
  double *p = s->x + 3 * (size_t)s->n_points;
  p[0] = a, p[1] = b, p[2] = c;
  return s->n_points++;
}

static void tri(bs_ls_surface *s, int32_t a, int32_t b, int32_t c) {
  int32_t *t = s->tris + 3 * (size_t)s->n_tris++;
  t[0] = a, t[1] = b, t[2] = c;
}

/* The quad (a, b, c, d), counter-clockwise seen from its outer side. */
static void quad(bs_ls_surface *s, int32_t a, int32_t b, int32_t c, int32_t d) {
  tri(s, a, b, c);
  tri(s, a, c, d);
}

/* Half-space: the square patch of z = 0 around (cx, cy), half side L. */
static int plane(bs_ls_surface *s, double cx, double cy, double L, bs_error *err) {
  const int n = PLANE_N;
  int st = reserve(s, (n + 1) * (n + 1), 2 * n * n, err);
  if (st) return st;
  for (int j = 0; j <= n; j++)
    for (int i = 0; i <= n; i++) point(s, cx + L * (2.0 * i / n - 1), cy + L * (2.0 * j / n - 1), 0);
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) {
      int32_t a = j * (n + 1) + i;
      quad(s, a, a + 1, a + n + 2, a + n + 1);
    }
  return 0;
}

/* Sphere: poles and rings of constant polar angle (u), segments in azimuth (v). */
static int sphere(bs_ls_surface *s, double r, bs_error *err) {
  const int R = SPHERE_RINGS, S = SPHERE_SEGS;
  int st = reserve(s, 2 + (R - 1) * S, 2 * S * (R - 1), err);
  if (st) return st;
  int32_t north = point(s, 0, 0, r);
  for (int k = 1; k < R; k++)
    for (int j = 0; j < S; j++) {
      double th = PI * k / R, ph = 2 * PI * j / S;
      point(s, r * sin(th) * cos(ph), r * sin(th) * sin(ph), r * cos(th));
    }
  int32_t south = point(s, 0, 0, -r);
#define RING(k, j) (1 + ((k) - 1) * S + ((j) % S))
  for (int j = 0; j < S; j++) {
    tri(s, north, RING(1, j), RING(1, j + 1));
    for (int k = 1; k + 1 < R; k++) quad(s, RING(k, j), RING(k + 1, j), RING(k + 1, j + 1), RING(k, j + 1));
    tri(s, RING(R - 1, j), south, RING(R - 1, j + 1));
  }
#undef RING
  return 0;
}

/* Box of half-extents h: face (axis a, side sg) spanned by the next two axes. */
static int box(bs_ls_surface *s, const double h[3], bs_error *err) {
  int st = reserve(s, 8, 12, err);
  if (st) return st;
  for (int i = 0; i < 8; i++) point(s, i & 1 ? h[0] : -h[0], i & 2 ? h[1] : -h[1], i & 4 ? h[2] : -h[2]);
  for (int a = 0; a < 3; a++)
    for (int sg = 0; sg < 2; sg++) {
      const int b = (a + 1) % 3, c = (a + 2) % 3, base = sg << a;
      int32_t q[4] = {base, base | 1 << b, base | 1 << b | 1 << c, base | 1 << c}; /* ccw about +e_a */
      if (sg) quad(s, q[0], q[1], q[2], q[3]);
      else quad(s, q[0], q[3], q[2], q[1]);
    }
  return 0;
}

/* Capped cylinder: bottom and top rings (azimuth u, height v), two fans. */
static int cylinder(bs_ls_surface *s, double r, double hh, bs_error *err) {
  const int S = CYL_SEGS;
  int st = reserve(s, 2 * S + 2, 4 * S, err);
  if (st) return st;
  for (int side = 0; side < 2; side++)
    for (int j = 0; j < S; j++) point(s, r * cos(2 * PI * j / S), r * sin(2 * PI * j / S), side ? hh : -hh);
  int32_t cb = point(s, 0, 0, -hh), ct = point(s, 0, 0, hh);
  for (int j = 0; j < S; j++) {
    int32_t b0 = j, b1 = (j + 1) % S, t0 = S + j, t1 = S + (j + 1) % S;
    quad(s, b0, b1, t1, t0);
    tri(s, ct, t0, t1);
    tri(s, cb, b1, b0);
  }
  return 0;
}

/* Torus: major angle u around the axis, minor angle v around the tube. */
static int torus(bs_ls_surface *s, double R, double r, bs_error *err) {
  const int U = TORUS_U, V = TORUS_V;
  int st = reserve(s, U * V, 2 * U * V, err);
  if (st) return st;
  for (int i = 0; i < U; i++)
    for (int j = 0; j < V; j++) {
      double u = 2 * PI * i / U, v = 2 * PI * j / V, a = R + r * cos(v);
      point(s, a * cos(u), a * sin(u), r * sin(v));
    }
#define TP(i, j) (((i) % U) * V + ((j) % V))
  for (int i = 0; i < U; i++)
    for (int j = 0; j < V; j++) quad(s, TP(i, j), TP(i + 1, j), TP(i + 1, j + 1), TP(i, j + 1));
#undef TP
  return 0;
}

/* The local surface of ls (f: its frame at t, for the plane's patch). */
static int local_surface(const bs_levelset *ls, const bs_levelset_frame *f, const double lo[3], const double hi[3],
                         bs_ls_surface *s, bs_error *err) {
  const double *p = ls->param;
  switch (ls->kind) {
    case BS_LS_HALFSPACE: {
      double ctr[3] = {0, 0, 0}, L = 1e-3, y[2]; /* ctr: the patch's centre relative to c */
      if (lo && hi) {
        for (int k = 0; k < 3; k++) ctr[k] = 0.5 * (lo[k] + hi[k]) - f->c[k];
        L = fmax(L, sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                         (hi[2] - lo[2]) * (hi[2] - lo[2])));
      }
      for (int a = 0; a < 2; a++) y[a] = f->M[a] * ctr[0] + f->M[3 + a] * ctr[1] + f->M[6 + a] * ctr[2]; /* M^T */
      return plane(s, y[0], y[1], L, err);
    }
    case BS_LS_SPHERE: return sphere(s, p[0], err);
    case BS_LS_BOX: return box(s, p, err);
    case BS_LS_CYLINDER: return cylinder(s, p[0], p[1], err);
    case BS_LS_TORUS: return torus(s, p[0], p[1], err);
    case BS_LS_GRID: break;
  }
  return bs_error_set(err, BS_EINPUT, "a %s level set has no analytic surface (write it as image data)",
                      bs_levelset_kind_name(ls->kind));
}

int bs_ls_surface_make(const bs_levelset *ls, double t, const double lo[3], const double hi[3], bs_ls_surface *out,
                       bs_error *err) {
  memset(out, 0, sizeof *out);
  bs_levelset_frame f;
  bs_levelset_frame_at(ls, t, &f);
  int st = local_surface(ls, &f, lo, hi, out, err);
  if (st) return st;
  for (int32_t i = 0; i < out->n_points; i++) { /* x = M y + c */
    double *x = out->x + 3 * (size_t)i, y[3] = {x[0], x[1], x[2]};
    for (int k = 0; k < 3; k++) x[k] = f.M[3 * k] * y[0] + f.M[3 * k + 1] * y[1] + f.M[3 * k + 2] * y[2] + f.c[k];
  }
  if (ls->complement)
    for (int32_t i = 0; i < out->n_tris; i++) {
      int32_t *tr = out->tris + 3 * (size_t)i, b = tr[1];
      tr[1] = tr[2], tr[2] = b;
    }
  return 0;
}

void bs_ls_surface_free(bs_ls_surface *s) {
  if (!s) return;
  free(s->x);
  free(s->tris);
  memset(s, 0, sizeof *s);
}
