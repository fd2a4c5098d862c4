/* Grid level sets sampled from closed surfaces through the library
 * (collision/bs_ls_sample.h): a sphere's grid against the analytic distance
 * within the stated bound (the Hausdorff distance of its triangulation);
 * closedness; the grid's plan and its defaults; errors naming what is wrong;
 * the files written. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_levelset.h"
#include "bs_ls_sample.h"
#include "bs_mesh.h"

/* An icosphere: the icosahedron subdivided `levels` times, every point on
 * the sphere of radius r at c (points shared, triangles outward). */
typedef struct ico {
  int np, nt, cap_p;
  double *x;
  int32_t *t;
} ico;

static int ico_point(ico *s, const double p[3], const double c[3], double r) {
  double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
  double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  double q[3] = {c[0] + r * d[0] / n, c[1] + r * d[1] / n, c[2] + r * d[2] / n};
  for (int i = 0; i < s->np; i++)
    if (fabs(s->x[3 * i] - q[0]) + fabs(s->x[3 * i + 1] - q[1]) + fabs(s->x[3 * i + 2] - q[2]) < 1e-12 * r) return i;
  cr_assert_lt(s->np, s->cap_p);
  memcpy(s->x + 3 * s->np, q, sizeof q);
  return s->np++;
}

static ico icosphere(const double c[3], double r, int levels) {
  const double g = (1 + sqrt(5.0)) / 2;
  const double v[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                           {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  const int f[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                        {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                        {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  int nt = 20;
  for (int l = 0; l < levels; l++) nt *= 4;
  ico s = {0, 0, nt / 2 + 2, NULL, NULL};
  s.x = malloc(sizeof(double) * 3 * (size_t)s.cap_p);
  s.t = malloc(sizeof(int32_t) * 3 * (size_t)nt);
  /* the triangles of level 0 as corner positions, split in four per level */
  double *tri = malloc(sizeof(double) * 9 * (size_t)nt), *next = malloc(sizeof(double) * 9 * (size_t)nt);
  for (int i = 0; i < 20; i++)
    for (int k = 0; k < 3; k++) memcpy(tri + 9 * i + 3 * k, v[f[i][k]], 3 * sizeof(double));
  int n = 20;
  for (int l = 0; l < levels; l++, n *= 4) {
    for (int i = 0; i < n; i++) {
      const double *a = tri + 9 * i, *b = a + 3, *cc = a + 6;
      double ab[3], bc[3], ca[3];
      for (int k = 0; k < 3; k++) {
        ab[k] = (a[k] + b[k]) / 2;
        bc[k] = (b[k] + cc[k]) / 2;
        ca[k] = (cc[k] + a[k]) / 2;
      }
      const double *q[4][3] = {{a, ab, ca}, {ab, b, bc}, {ca, bc, cc}, {ab, bc, ca}};
      for (int j = 0; j < 4; j++)
        for (int k = 0; k < 3; k++) memcpy(next + 9 * (4 * i + j) + 3 * k, q[j][k], 3 * sizeof(double));
    }
    double *tmp = tri;
    tri = next;
    next = tmp;
  }
  for (int i = 0; i < nt; i++)
    for (int k = 0; k < 3; k++) s.t[3 * i + k] = ico_point(&s, tri + 9 * i + 3 * k, (const double[3]){0, 0, 0}, 1);
  s.nt = nt;
  for (int i = 0; i < s.np; i++)
    for (int k = 0; k < 3; k++) s.x[3 * i + k] = c[k] + r * s.x[3 * i + k];
  free(tri);
  free(next);
  return s;
}

static bs_ls_soup ico_soup(const ico *s) {
  bs_ls_soup o = {s->np, s->x, s->nt, s->t};
  return o;
}

/* The Hausdorff distance of an inscribed triangulation to its sphere: r -
 * the smallest distance from the centre to a triangle's plane, sqrt(r^2 -
 * rho^2) with rho the triangle's circumradius. */
static double sphere_gap(const ico *s, double r) {
  double worst = 0;
  for (int i = 0; i < s->nt; i++) {
    const double *a = s->x + 3 * s->t[3 * i], *b = s->x + 3 * s->t[3 * i + 1], *c = s->x + 3 * s->t[3 * i + 2];
    double la = 0, lb = 0, lc = 0, u[3], w[3];
    for (int k = 0; k < 3; k++) {
      la += (b[k] - c[k]) * (b[k] - c[k]);
      lb += (c[k] - a[k]) * (c[k] - a[k]);
      lc += (a[k] - b[k]) * (a[k] - b[k]);
      u[k] = b[k] - a[k];
      w[k] = c[k] - a[k];
    }
    double cr[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    double area2 = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]); /* twice the area */
    double rho = sqrt(la * lb * lc) / (2 * area2);
    worst = fmax(worst, r - sqrt(fmax(0, r * r - rho * rho)));
  }
  return worst;
}

Test(ls_sample, sphere_grid_matches_the_distance_within_the_bound) {
  const double c[3] = {0.1, -0.2, 0.3}, r = 0.5;
  ico s = icosphere(c, r, 3); /* 1280 triangles, 642 points */
  cr_assert_eq(s.nt, 1280);
  cr_assert_eq(s.np, 642);
  bs_ls_soup soup = ico_soup(&s);
  bs_error err;
  cr_assert_eq(bs_ls_soup_check_closed(&soup, "icosphere", &err), 0, "%s", err.msg);
  const double delta = sphere_gap(&s, r);
  cr_assert(delta > 1e-3 && delta < 1e-2, "gap %g", delta);
  bs_ls_grid_plan g;
  cr_assert_eq(bs_ls_grid_plan_make(&soup, "icosphere", 0.05, 0.2, &g, &err), 0, "%s", err.msg);
  double *v = malloc(sizeof(double) * (size_t)g.total);
  bs_ls_sample_info info;
  cr_assert_eq(bs_ls_sample_grid(&soup, &g, v, &info, &err), 0, "%s", err.msg);
  double worst = 0, below = 0;
  int64_t inside = 0;
  for (int32_t k = 0; k < g.n[2]; k++)
    for (int32_t j = 0; j < g.n[1]; j++)
      for (int32_t i = 0; i < g.n[0]; i++) {
        double p[3] = {g.origin[0] + g.h * i - c[0], g.origin[1] + g.h * j - c[1], g.origin[2] + g.h * k - c[2]};
        double exact = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - r;
        double got = v[i + (int64_t)g.n[0] * (j + (int64_t)g.n[1] * k)];
        worst = fmax(worst, fabs(got - exact));
        below = fmax(below, exact - got); /* the polyhedron lies inside the ball: got >= exact */
        inside += got < 0;
      }
  cr_assert_leq(worst, delta + 1e-12, "largest error %g, bound %g", worst, delta);
  cr_assert_leq(below, 1e-12, "a node below the sphere's distance by %g", below);
  cr_assert_gt(worst, 0.1 * delta, "the error %g should be of the order of the gap %g", worst, delta);
  cr_assert_eq(info.n_inside, inside);
  cr_assert_geq(info.phi_min, -r - 1e-12);
  cr_assert_lt(info.phi_min, -r + delta + g.h);
  cr_assert_geq(info.threads, 1);
  free(v);

  /* the whole job: the grid level set; at the centre about -r */
  bs_levelset *ls = NULL;
  cr_assert_eq(bs_ls_from_surface(&soup, "icosphere", 0.05, 0.2, &g, &info, &ls, &err), 0, "%s", err.msg);
  double phi_c = bs_levelset_eval(ls, 0.0, c, NULL, NULL);
  cr_assert(phi_c > -r - 1e-6 && phi_c < -r + delta + 1e-6, "phi at the centre %g", phi_c);
  bs_levelset_destroy(&ls);
  free(s.x);
  free(s.t);
}

/* The unit cube as 8 points and 12 outward triangles; without its top. */
static const double cube_x[8 * 3] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
static int32_t cube_t[12 * 3] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3, 3, 7, 6, 3, 6, 2};

Test(ls_sample, closedness_plan_and_errors) {
  bs_ls_soup s = {8, (double *)cube_x, 12, cube_t};
  bs_error err;
  cr_assert_eq(bs_ls_soup_check_closed(&s, "cube.off", &err), 0, "%s", err.msg);
  s.n_tris = 10; /* the last two: the face y = 1 */
  cr_assert_eq(bs_ls_soup_check_closed(&s, "open.off", &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "'open.off'"), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "not closed: 4 edges"), "%s", err.msg);
  bs_levelset *ls = NULL;
  cr_assert_eq(bs_ls_from_surface(&s, "open.off", 0.1, 0.1, NULL, NULL, &ls, &err), BS_EINPUT);
  cr_assert_null(ls);
  s.n_tris = 0;
  cr_assert_eq(bs_ls_from_surface(&s, "none.off", 0.1, 0.1, NULL, NULL, &ls, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "'none.off': no triangles"), "%s", err.msg);
  s.n_tris = 12;

  /* defaults: h = edge / 40, margin = max(0.1 edge, 2 h) */
  bs_ls_grid_plan g;
  cr_assert_eq(bs_ls_grid_plan_make(&s, "cube.off", 0, -1, &g, &err), 0, "%s", err.msg);
  cr_assert_float_eq(g.h, 1.0 / 40, 1e-15);
  cr_assert_float_eq(g.margin, 0.1, 1e-15);
  cr_assert_float_eq(g.origin[1], -0.1, 1e-15);
  cr_assert_eq(g.n[0], 49);
  cr_assert_eq(g.total, 49LL * 49 * 49);
  cr_assert_eq(g.hi[2], 1.0);
  /* given: ceil((1 + 2 * 0.5) / 0.25) + 1 = 9 nodes */
  cr_assert_eq(bs_ls_grid_plan_make(&s, "cube.off", 0.25, 0.5, &g, &err), 0, "%s", err.msg);
  cr_assert_eq(g.n[2], 9);
  cr_assert_eq(g.origin[0], -0.5);
  cr_assert_eq(bs_ls_grid_plan_make(&s, "cube.off", 1e-9, 0.5, &g, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "h = 1e-09"), "%s", err.msg);
  cr_assert_eq(bs_ls_grid_plan_make(&s, "cube.off", 1e-3, 0.5, &g, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "2^31"), "%s", err.msg);
  const double flat[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  int32_t one[3] = {0, 1, 2};
  bs_ls_soup point = {3, (double *)flat, 1, one};
  cr_assert_eq(bs_ls_grid_plan_make(&point, "dot.off", 0.1, 0.1, &g, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "'dot.off': the surface has no extent"), "%s", err.msg);

  cr_assert(bs_ls_soup_is_file("a/b.off") && bs_ls_soup_is_file("B.STL") && bs_ls_soup_is_file("x.ply"));
  cr_assert(!bs_ls_soup_is_file("a.msh") && !bs_ls_soup_is_file("a.off/b") && !bs_ls_soup_is_file("box:2"));
}

/* The boundary of a box mesh, sampled and written both ways; the .bsls file
 * loads back bit for bit; a missing surface file is named. */
Test(ls_sample, mesh_boundary_and_files) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 1};
  bs_mesh *m = NULL;
  bs_error err;
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 2, 2, &m, &err), 0, "%s", err.msg);
  bs_ls_soup s;
  cr_assert_eq(bs_ls_soup_from_mesh(m, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(s.n_tris, m->n_faces);
  bs_levelset *ls = NULL;
  bs_ls_grid_plan g;
  bs_ls_sample_info info;
  cr_assert_eq(bs_ls_from_surface(&s, "box", 0.25, 0.25, &g, &info, &ls, &err), 0, "%s", err.msg);
  /* the exact distance to the box at the grid's nodes (the faces are flat) */
  int32_t n[3];
  double origin[3], h;
  const double *v = bs_levelset_grid_values(ls, n, origin, &h);
  cr_assert_eq(n[1], (int32_t)ceil(2.5 / 0.25) + 1);
  const double q[3] = {origin[0], origin[1], origin[2]}; /* (-0.25, -0.25, -0.25): sqrt(3) 0.25 out */
  cr_assert_float_eq(v[0], sqrt(3.0) * 0.25, 1e-12);
  cr_assert_float_eq(bs_levelset_eval(ls, 0.0, q, NULL, NULL), sqrt(3.0) * 0.25, 1e-9);
  cr_assert_float_eq(info.phi_min, -0.5, 1e-12);

  char dir[] = "/tmp/bs_test_ls_sample_XXXXXX", path[96];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/box.bsls", dir);
  cr_assert_eq(bs_ls_sample_write(ls, path, &err), 0, "%s", err.msg);
  bs_levelset *back = NULL;
  cr_assert_eq(bs_levelset_grid_load(path, &back, &err), 0, "%s", err.msg);
  int32_t nb[3];
  const double *vb = bs_levelset_grid_values(back, nb, NULL, NULL);
  cr_assert_eq(memcmp(nb, n, sizeof n), 0);
  cr_assert_eq(memcmp(vb, v, sizeof(double) * (size_t)g.total), 0);
  unlink(path);
  snprintf(path, sizeof path, "%s/box.vti", dir);
  cr_assert_eq(bs_ls_sample_write(ls, path, &err), 0, "%s", err.msg);
  cr_assert_eq(access(path, F_OK), 0);
  unlink(path);
  snprintf(path, sizeof path, "%s/no/such/box.bsls", dir);
  cr_assert_neq(bs_ls_sample_write(ls, path, &err), 0);
  cr_assert_not_null(strstr(err.msg, "no/such/box.bsls"), "%s", err.msg);
  snprintf(path, sizeof path, "%s/missing.off", dir);
  bs_ls_soup none;
  cr_assert_neq(bs_ls_soup_read(path, &none, &err), 0);
  cr_assert_not_null(strstr(err.msg, "missing.off"), "%s", err.msg);
  cr_assert_null(none.x);
  rmdir(dir);
  bs_levelset_destroy(&back);
  bs_levelset_destroy(&ls);
  bs_ls_soup_free(&s);
  cr_assert_null(s.x);
  bs_mesh_destroy(&m);
}
