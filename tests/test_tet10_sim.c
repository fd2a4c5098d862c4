/* test_tet10_sim.c — quadratic tetrahedra (bodies[].element tet10) through
 * the whole pipeline: the quadratic mesh and its groups, the fem over tet10
 * (mass, load, gradient and Hessian against differences), the cantilever of
 * data/scenes/beam_sag.json against beam theory and against tet4, a patch
 * test, the VTU output, and the inputs refused by name. */
#define _GNU_SOURCE /* mkdtemp */
#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_audit.h"
#include "bs_fem.h"
#include "bs_mesh.h"
#include "bs_qoi.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_tet10.h"
#include "bs_terms.h"
#include "sim_util.h"

#define BEAM BS_SOURCE_DIR "/data/scenes/beam_sag.json"

/* ---- the quadratic mesh ---- */

Test(tet10_mesh, box_nodes_and_groups) {
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 0.1, 0.1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 20, 2, 2, &m, &err), 0, "%s", err.msg);
  const int32_t nc = m->n_vertices;
  cr_assert_eq(bs_tet10_mesh(m, &err), 0, "%s", err.msg);
  cr_expect_eq(m->n_corners, nc);
  /* a 20x2x2 Kuhn box: the quadratic nodes are the vertices of the 40x4x4 grid plus the face diagonals' and
     cell diagonals' midpoints; count them through the edges instead: n_vertices = corners + unique edges */
  cr_expect_gt(m->n_vertices, nc);
  for (int32_t t = 0; t < m->n_tets; t++)
    for (int k = 0; k < 6; k++) {
      const int32_t a = m->tets10[10 * t + bs_tet10_edges[k][0]], b = m->tets10[10 * t + bs_tet10_edges[k][1]];
      const int32_t n = m->tets10[10 * t + 4 + k];
      cr_assert(n >= nc && n < m->n_vertices);
      cr_assert_eq(bs_mesh_edge_node(m, a, b), n);
      for (int i = 0; i < 3; i++) cr_assert_eq(m->x[3 * n + i], 0.5 * (m->x[3 * a + i] + m->x[3 * b + i]));
    }
  /* the face group xmin: its 3x3 vertices and the 5x5 - 9 = 16 midside nodes of its triangles */
  const bs_group *g = bs_mesh_group(m, "xmin");
  cr_assert(g);
  cr_expect_eq(g->n_vertices, 25, "xmin holds %d nodes", g->n_vertices);
  for (int32_t k = 0; k < g->n_vertices; k++) {
    cr_expect_eq(m->x[3 * g->vertices[k]], 0.0, "node %d of xmin is off the face", g->vertices[k]);
    if (k) cr_expect_gt(g->vertices[k], g->vertices[k - 1], "xmin not sorted");
  }
  /* quadratic meshes are refused by the linear-mesh operations, by name */
  bs_mesh *f = NULL;
  cr_expect_eq(bs_mesh_refine(m, &f, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "quadratic"), "%s", err.msg);
  cr_expect_eq(bs_tet10_mesh(m, &err), BS_EINPUT);
  bs_mesh *c = NULL;
  cr_assert_eq(bs_mesh_copy(m, &c, &err), 0, "%s", err.msg);
  cr_expect_eq(memcmp(c->tets10, m->tets10, sizeof(int32_t) * 10 * (size_t)m->n_tets), 0);
  bs_mesh_destroy(&c);
  bs_mesh_destroy(&m);
}

/* A geometry input meshed at order 2: the midside nodes of its boundary
 * edges lie on the sphere (Gmsh places them on the geometry), so the curved
 * tet10 mesh encloses the ball's volume far better than its flat corners. */
Test(tet10_mesh, geometry_at_order_two_has_curved_boundary_nodes) {
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  bs_mesh_read_opts o = {.element_order = 2};
  cr_assert_eq(bs_mesh_read(BS_SOURCE_DIR "/data/geo/sphere.geo", &o, &m, &err), 0, "%s", err.msg);
  const int32_t nc = m->n_vertices;
  double v1 = 0, v2 = 0;
  for (int32_t t = 0; t < m->n_tets; t++) v1 += bs_mesh_tet_volume(m, m->x, t);
  cr_assert_eq(bs_tet10_mesh(m, &err), 0, "%s", err.msg);
  int32_t on = 0, boundary_edges = 0;
  for (int32_t f = 0; f < m->n_faces; f++)
    for (int k = 0; k < 3; k++) {
      const int32_t a = m->faces[3 * f + k], b = m->faces[3 * f + (k + 1) % 3];
      if (a > b) continue; /* each boundary edge once (its two faces run it both ways) */
      boundary_edges++;
      const int32_t n = bs_mesh_edge_node(m, a, b);
      cr_assert(n >= nc, "boundary edge (%d, %d) has no midside node", a, b);
      const double *p = m->x + 3 * (size_t)n;
      on += fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 0.5) < 1e-9;
    }
  cr_expect_eq(on, boundary_edges, "%d of %d boundary midside nodes on the sphere", on, boundary_edges);
  for (int32_t t = 0; t < m->n_tets; t++) {
    double X[30];
    bs_tet10_rest r;
    for (int a = 0; a < 10; a++) memcpy(X + 3 * a, m->x + 3 * (size_t)m->tets10[10 * t + a], 3 * sizeof(double));
    cr_assert_eq(bs_tet10_rest_init(X, BS_TET10_RULE_14PT_DEG5, &r, &err), 0, "%s", err.msg);
    v2 += r.volume;
  }
  const double ball = 4.0 / 3.0 * M_PI * 0.125, e1 = fabs(v1 - ball) / ball, e2 = fabs(v2 - ball) / ball;
  cr_log_info("sphere.geo: %d tets; volume flat %.6f (%.3f%% off), curved %.6f (%.4f%% off), ball %.6f", m->n_tets, v1,
              100 * e1, v2, 100 * e2, ball);
  cr_expect_lt(e2, 0.05 * e1, "curved volume %.6g is %.3g off, flat %.3g", v2, e2, e1);
  bs_mesh_destroy(&m);
}

/* The body's placement (scale, rotate, translate) moves the file's curved
 * midside nodes with the corners: every boundary midside node of the
 * scaled, moved sphere lies on it (they were left at the file's place). */
Test(tet10_mesh, placed_body_keeps_its_curved_nodes_on_the_geometry) {
  static const char *const scene =
      "{\"time\": {\"fps\": 24, \"frames\": 1},\n"
      " \"bodies\": [{\"mesh\": \"" BS_SOURCE_DIR "/data/geo/sphere.geo\", \"element\": \"tet10\",\n"
      "   \"scale\": [2, 2, 2], \"rotate\": [0.3, 0.5, 0.1], \"translate\": [0.3, 1, -0.2],\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}]}\n";
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(scene, "placed", &sc);
  const bs_mesh *m = s->mesh;
  int32_t on = 0, n = 0;
  for (int32_t f = 0; f < m->n_faces; f++)
    for (int k = 0; k < 3; k++) {
      const int32_t a = m->faces[3 * f + k], b = m->faces[3 * f + (k + 1) % 3];
      if (a > b) continue;
      const int32_t v = bs_mesh_edge_node(m, a, b);
      cr_assert(v >= 0);
      const double *p = s->x0 + 3 * (size_t)v, d[3] = {p[0] - 0.3, p[1] - 1, p[2] + 0.2};
      on += fabs(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - 1.0) < 1e-9;
      n++;
    }
  cr_expect_eq(on, n, "%d of %d boundary midside nodes on the placed sphere", on, n);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* ---- the fem over tet10 ---- */

typedef struct fem_fixture {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_material mat;
} fem_fixture;

static void fem_make(fem_fixture *f, int model) {
  bs_error err;
  bs_error_clear(&err);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.2, 0.1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 2, 1, &f->mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_tet10_mesh(f->mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(model, 1e6, 0.3, 1000, &f->mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(f->mesh, 1, &f->mat, NULL, &f->fem, &err), 0, "%s", err.msg);
}

static void fem_free(fem_fixture *f) {
  bs_fem_destroy(&f->fem);
  bs_mesh_destroy(&f->mesh);
}

Test(tet10_fem, mass_load_pattern) {
  fem_fixture f;
  fem_make(&f, BS_MODEL_FIXED_COROTATED);
  const bs_fem *fem = f.fem;
  const double V = 0.3 * 0.2 * 0.1, rho = 1000;
  cr_expect_eq(fem->order, 2);
  double M = 0, L = 0, vol = 0;
  for (int32_t v = 0; v < fem->n_vertices; v++) {
    cr_expect_gt(fem->mass[v], 0, "HRZ mass of node %d is %g", v, fem->mass[v]);
    M += fem->mass[v];
    L += fem->load[v];
  }
  for (int32_t t = 0; t < fem->n_tets; t++) vol += fem->volume[t];
  cr_expect_float_eq(M, rho * V, 1e-12 * rho * V);
  cr_expect_float_eq(L, rho * V, 1e-12 * rho * V);
  cr_expect_float_eq(vol, V, 1e-12 * V);
  cr_expect_float_eq(fem->total_mass, rho * V, 1e-12 * rho * V);
  /* every node pair of a tet has its block; straight tets: the 4-point rule */
  for (int32_t t = 0; t < fem->n_tets; t++) {
    cr_expect_eq(fem->q_ptr[t + 1] - fem->q_ptr[t], 4);
    for (int a = 0; a < 10; a++)
      for (int b = 0; b < 10; b++)
        cr_assert_eq(bs_bsr_slot(fem->pattern, f.mesh->tets10[10 * t + a], f.mesh->tets10[10 * t + b]),
                     fem->slots[100 * t + 10 * a + b]);
  }
  fem_free(&f);
}

/* A smooth non-affine configuration of the rest nodes. */
static void deform(const bs_mesh *m, double *x) {
  for (int32_t v = 0; v < m->n_vertices; v++) {
    const double *X = m->x + 3 * v;
    x[3 * v] = X[0] + 0.05 * X[1] * X[1] + 0.02 * sin(7 * X[2]);
    x[3 * v + 1] = X[1] - 0.1 * X[0] * X[2] + 0.01;
    x[3 * v + 2] = 1.05 * X[2] + 0.03 * X[0] * X[1];
  }
}

Test(tet10_fem, gradient_and_hessian_against_differences) {
  fem_fixture f;
  fem_make(&f, BS_MODEL_NEO_HOOKEAN);
  const int32_t n = f.fem->n_vertices;
  const size_t n3 = 3 * (size_t)n;
  double *x = malloc(sizeof(double) * n3), *g = calloc(n3, sizeof(double)), *gp = calloc(n3, sizeof(double)),
         *gm = calloc(n3, sizeof(double)), *d = malloc(sizeof(double) * n3), *Hd = malloc(sizeof(double) * n3);
  deform(f.mesh, x);
  const double E = bs_fem_elastic_gradient(f.fem, x, g);
  cr_expect_float_eq(E, bs_fem_elastic_energy(f.fem, x), 1e-12 * fabs(E));
  srand(7);
  for (size_t i = 0; i < n3; i++) d[i] = (double)rand() / RAND_MAX - 0.5;
  const double h = 1e-6;
  for (size_t i = 0; i < n3; i++) x[i] += h * d[i];
  const double Ep = bs_fem_elastic_gradient(f.fem, x, gp);
  for (size_t i = 0; i < n3; i++) x[i] -= 2 * h * d[i];
  const double Em = bs_fem_elastic_gradient(f.fem, x, gm);
  for (size_t i = 0; i < n3; i++) x[i] += h * d[i];
  double gd = 0;
  for (size_t i = 0; i < n3; i++) gd += g[i] * d[i];
  cr_expect_float_eq((Ep - Em) / (2 * h), gd, 1e-6 * fabs(gd) + 1e-9, "dE.d %g vs %g", (Ep - Em) / (2 * h), gd);
  bs_bsr *H = NULL;
  bs_error err;
  cr_assert_eq(bs_fem_matrix(f.fem, &H, &err), 0, "%s", err.msg);
  bs_fem_elastic_hessian(f.fem, x, BS_PSD_NONE, 1.0, H);
  bs_bsr_mul(H, NULL, d, Hd);
  double num = 0, den = 0;
  for (size_t i = 0; i < n3; i++) {
    const double fd = (gp[i] - gm[i]) / (2 * h);
    num += (fd - Hd[i]) * (fd - Hd[i]);
    den += Hd[i] * Hd[i];
  }
  cr_expect_lt(sqrt(num / den), 1e-6, "|H d - dg| / |H d| = %g", sqrt(num / den));
  /* a rigid motion has no energy and no force */
  for (int32_t v = 0; v < n; v++) {
    const double *X = f.mesh->x + 3 * v;
    x[3 * v] = 0.8 * X[0] - 0.6 * X[1] + 1;
    x[3 * v + 1] = 0.6 * X[0] + 0.8 * X[1] - 2;
    x[3 * v + 2] = X[2] + 0.5;
  }
  memset(g, 0, sizeof(double) * n3);
  cr_expect_lt(fabs(bs_fem_elastic_gradient(f.fem, x, g)), 1e-12);
  for (size_t i = 0; i < n3; i++) cr_expect_lt(fabs(g[i]), 1e-7, "rigid motion: g[%zu] = %g", i, g[i]);
  double mn = 0;
  cr_expect_eq(bs_fem_count_inverted(f.fem, x, &mn), 0);
  cr_expect_float_eq(mn, 1.0, 1e-12);
  bs_bsr_destroy(&H);
  free(x), free(g), free(gp), free(gm), free(d), free(Hd);
  fem_free(&f);
}

/* Energy, gradient, Hessian and inverted count on n threads (16^3 cells:
 * 24,576 tets, 48 chunks, so that colours run in parallel). */
static void assemble_on(int n, const fem_fixture *f, const double *x, double *E, double *g, bs_bsr *H, int32_t *inv) {
  omp_set_num_threads(n);
  memset(g, 0, sizeof(double) * 3 * (size_t)f->fem->n_vertices);
  memset(H->val, 0, sizeof(double) * 9 * (size_t)H->nnzb);
  E[0] = bs_fem_elastic_energy(f->fem, x);
  E[1] = bs_fem_elastic_gradient(f->fem, x, g);
  bs_fem_elastic_hessian(f->fem, x, BS_PSD_ALL, 1.0, H);
  double mn;
  *inv = bs_fem_count_inverted(f->fem, x, &mn);
}

Test(tet10_fem, one_and_two_threads_give_the_same_bits) {
  fem_fixture f;
  bs_error err;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.4, 0.3, 0.2};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 16, 16, 16, &f.mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_tet10_mesh(f.mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e6, 0.3, 1000, &f.mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(f.mesh, 1, &f.mat, NULL, &f.fem, &err), 0, "%s", err.msg);
  const size_t n3 = 3 * (size_t)f.fem->n_vertices;
  double *x = malloc(n3 * sizeof(double)), *g1 = malloc(n3 * sizeof(double)), *g2 = malloc(n3 * sizeof(double));
  deform(f.mesh, x);
  bs_bsr *H1 = NULL, *H2 = NULL;
  cr_assert_eq(bs_fem_matrix(f.fem, &H1, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_matrix(f.fem, &H2, &err), 0, "%s", err.msg);
  double E1[2], E2[2];
  int32_t i1, i2;
  const int saved = omp_get_max_threads();
  assemble_on(1, &f, x, E1, g1, H1, &i1);
  assemble_on(2, &f, x, E2, g2, H2, &i2);
  omp_set_num_threads(saved);
  cr_expect_eq(memcmp(E1, E2, sizeof E1), 0, "energy %.17g / %.17g on 1 thread, %.17g / %.17g on 2", E1[0], E1[1], E2[0], E2[1]);
  cr_expect_float_eq(E1[0], E1[1], 1e-12 * fabs(E1[0]));
  cr_expect_eq(memcmp(g1, g2, n3 * sizeof(double)), 0, "the gradient differs between 1 and 2 threads");
  cr_expect_eq(memcmp(H1->val, H2->val, 9 * (size_t)H1->nnzb * sizeof(double)), 0, "the Hessian differs");
  cr_expect_eq(i1, i2);
  bs_bsr_destroy(&H1);
  bs_bsr_destroy(&H2);
  free(x), free(g1), free(g2);
  fem_free(&f);
}

/* ---- the cantilever of beam_sag.json ---- */

/* Tip deflection of the scene's cantilever by beam theory: Euler-Bernoulli
 * q L^4 / (8 E I), and Timoshenko's shear part q L^2 / (2 k G A) with
 * Cowper's k = 10 (1 + nu) / (12 + 11 nu) for a rectangle; q = rho |g| A. */
static void beam_theory(const bs_scene *sc, double *eb, double *timo) {
  const bs_scene_body *b = &sc->bodies[0];
  const double L = b->box_size[0], h = b->box_size[1], w = b->box_size[2];
  const double E = b->materials[0].youngs, nu = b->materials[0].poisson, rho = b->materials[0].density;
  const double A = h * w, I = w * h * h * h / 12, q = rho * fabs(sc->gravity[1]) * A;
  const double G = E / (2 * (1 + nu)), k = 10 * (1 + nu) / (12 + 11 * nu);
  *eb = q * L * L * L * L / (8 * E * I);
  *timo = *eb + q * L * L / (2 * k * G * A);
}

/* The static tip deflection (-tip_y, the scene's first QoI) with the overrides. */
static double beam_tip_of(const char *scene, const char *sets, bs_scene **keep_scene, int32_t *n_nodes) {
  sim_rec rec;
  bs_run_totals T;
  bs_scene *sc = NULL;
  bs_sim *s = sim_run_scene(scene, sets, NULL, &rec, &T, 1, &sc);
  cr_assert_eq(rec.failed, 0, "%s: %s", sets, rec.reason);
  bs_qoi *q = NULL;
  bs_error err;
  double v[4];
  cr_assert_eq(bs_qoi_create(s, &q, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_qoi_eval(q, s, v, &err), 0, "%s", err.msg);
  cr_expect_float_eq(v[1], 98.0, 1e-6, "clamp reaction %g, the beam's weight 98 N", v[1]);
  if (n_nodes) *n_nodes = s->mesh->n_vertices;
  bs_qoi_destroy(&q);
  bs_sim_destroy(&s);
  if (keep_scene) *keep_scene = sc;
  else bs_scene_destroy(&sc);
  return -v[0];
}

static double beam_tip(const char *sets, bs_scene **keep_scene, int32_t *n_nodes) {
  return beam_tip_of(BEAM, sets, keep_scene, n_nodes);
}

Test(tet10_sim, beam_sag_matches_beam_theory_and_beats_tet4) {
  bs_scene *sc = NULL;
  int32_t n10 = 0;
  const double d10 = beam_tip("bodies.0.element=tet10 output.vtu_every=0", &sc, &n10);
  const double d4 = beam_tip("output.vtu_every=0", NULL, NULL);
  double eb, timo;
  beam_theory(sc, &eb, &timo);
  bs_scene_destroy(&sc);
  const double e10 = (d10 - eb) / eb, e4 = (d4 - eb) / eb;
  cr_log_info("beam_sag tip: tet10 %.6g m (%d nodes), tet4 %.6g m; Euler-Bernoulli %.6g, Timoshenko %.6g: "
              "tet10 %+.2f%% / %+.2f%%, tet4 %+.1f%% / %+.1f%%",
              d10, n10, d4, eb, timo, 100 * e10, 100 * (d10 - timo) / timo, 100 * e4, 100 * (d4 - timo) / timo);
  cr_expect_lt(fabs(e10), 0.01, "tet10 tip %g vs Euler-Bernoulli %g: %+.2f%%", d10, eb, 100 * e10);
  cr_expect_lt(fabs(d10 - timo) / timo, 0.02, "tet10 tip %g vs Timoshenko %g", d10, timo);
  cr_expect_gt(fabs(e4), 20 * fabs(e10), "tet4 error %g not far above tet10's %g", e4, e10);
}

/* ---- patch test ---- */

static const char *const patch_scene =
    "{\"time\": {\"fps\": 1, \"frames\": 1, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"newton\", \"linear\": \"cholmod\", \"tolerance\": 1e-12, \"mode\": \"static\"},\n"
    " \"gravity\": [0, 0, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [3, 2, 2], \"size\": [0.3, 0.2, 0.2]}, \"element\": \"tet10\",\n"
    "   \"rotate\": [0, 0, 0],\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e6, \"poisson\": 0, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true},\n"
    "                {\"group\": \"xmax\", \"keyframes\": [{\"t\": 0, \"offset\": [0.03, 0, 0]}]}]}]}\n";

Test(tet10_sim, patch_test_affine_stretch) {
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(patch_scene, "patch", &sc);
  bs_error err;
  bs_error_clear(&err);
  bs_frame_stats fs;
  cr_assert_eq(bs_sim_statics(s, &fs, &err), 0, "%s", err.msg);
  /* nu = 0: the uniaxial stretch x -> (1 + 0.1) x is the exact solution (no lateral traction) */
  double worst = 0;
  int32_t at = -1;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) {
    const double *X = s->x0 + 3 * v, *x = s->x + 3 * v;
    const double d = fabs(x[0] - 1.1 * X[0]) + fabs(x[1] - X[1]) + fabs(x[2] - X[2]);
    if (d > worst) worst = d, at = v;
  }
  cr_expect_lt(worst, 1e-9, "node %d (of %d, %d corners) is %g off the affine field", at, s->mesh->n_vertices,
               s->mesh->n_corners, worst);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* ---- refused input ---- */

static void expect_refused(const char *sets, const char *needle) {
  char buf[1024];
  const char *v[16];
  int n = sim_split_sets(sets, buf, sizeof buf, v, 16);
  bs_error err;
  int st = sim_load_error(BEAM, v, n, &err);
  cr_expect_neq(st, 0, "[%s] was accepted", sets);
  cr_expect(strstr(err.msg, needle), "[%s]: '%s' does not say '%s'", sets, err.msg, needle);
}

Test(tet10_sim, refused_by_name) {
  expect_refused("bodies.0.element=tet10 self_collision.stiffness=1e5",
                 "self_collision is not supported with bodies[].element tet10");
  expect_refused("bodies.0.element=tet10 self_collision.model=barrier",
                 "self_collision is not supported with bodies[].element tet10");
  expect_refused("bodies.0.element=tet10 solver.backend=petsc", "tet10 is not supported with solver.backend petsc");
  expect_refused("bodies.0.element=tet20", "bodies.0.element");
  expect_refused("bodies.0.element=tet20", "tet20");
}

/* ---- output ---- */

/* The raw appended array `name` of a VTU file (uncompressed): its bytes into
 * *data (malloc'ed), its byte count returned; -1 when absent. */
static long vtu_array(const char *text, size_t len, const char *name, unsigned char **data) {
  char key[128];
  snprintf(key, sizeof key, "Name=\"%s\"", name);
  const char *a = strstr(text, key), *app = strstr(text, "<AppendedData");
  if (!a || !app) return -1;
  const char *o = strstr(a, "offset=\"");
  const char *u = strchr(app, '_');
  if (!o || !u) return -1;
  const size_t off = strtoul(o + 8, NULL, 10), base = (size_t)(u + 1 - text);
  uint64_t n;
  if (base + off + 8 > len) return -1;
  memcpy(&n, text + base + off, 8);
  if (base + off + 8 + n > len) return -1;
  *data = malloc(n ? n : 1);
  memcpy(*data, text + base + off + 8, n);
  return (long)n;
}

Test(tet10_sim, vtu_quadratic_cells_and_stress) {
  char dir[] = "/tmp/bs_test_tet10_XXXXXX";
  cr_assert_not_null(mkdtemp(dir));
  sim_rec rec;
  bs_run_totals T;
  bs_scene *sc = NULL;
  bs_sim *s = sim_run_scene(BEAM, "bodies.0.element=tet10 output.vtu_every=1", dir, &rec, &T, 1, &sc);
  char path[1200];
  snprintf(path, sizeof path, "%s/frame_00001.vtu", dir);
  FILE *fp = fopen(path, "rb");
  cr_assert(fp, "no %s", path);
  fseek(fp, 0, SEEK_END);
  const long len = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *text = malloc((size_t)len + 1);
  cr_assert_eq(fread(text, 1, (size_t)len, fp), (size_t)len);
  text[len] = 0;
  fclose(fp);
  const bs_mesh *m = s->mesh;
  char np[64];
  snprintf(np, sizeof np, "NumberOfPoints=\"%d\" NumberOfCells=\"%d\"", m->n_vertices, m->n_tets);
  cr_expect(strstr(text, np), "the VTU lacks %s", np);
  unsigned char *types = NULL, *conn = NULL, *vm = NULL;
  cr_assert_eq(vtu_array(text, (size_t)len, "types", &types), m->n_tets);
  for (int32_t t = 0; t < m->n_tets; t++) cr_assert_eq(types[t], 24, "cell %d has type %d", t, types[t]);
  cr_assert_eq(vtu_array(text, (size_t)len, "connectivity", &conn), 8L * 10 * m->n_tets);
  for (int64_t i = 0; i < 10 * (int64_t)m->n_tets; i++) {
    int64_t c;
    memcpy(&c, conn + 8 * i, 8);
    cr_assert_eq(c, m->tets10[i]);
  }
  /* von Mises: the bending stress at the root, M c / I = (q L^2 / 2)(h / 2) / I; a root cell's average lies below it */
  cr_assert_eq(vtu_array(text, (size_t)len, "von_mises", &vm), 8L * m->n_tets);
  const double q = 1000 * 9.8 * 0.01, I = 0.1 * 1e-3 / 12, smax = q * 0.5 * 0.05 / I;
  double top = 0;
  for (int32_t t = 0; t < m->n_tets; t++) {
    double v;
    memcpy(&v, vm + 8 * t, 8);
    cr_assert(isfinite(v) && v >= 0, "cell %d: von Mises %g", t, v);
    if (v > top) top = v;
  }
  cr_log_info("largest cell von Mises %g Pa; beam theory's root bending stress %g Pa", top, smax);
  cr_expect(top > 0.4 * smax && top < 1.3 * smax, "largest von Mises %g against %g", top, smax);
  free(types), free(conn), free(vm), free(text);
  /* `bigstep check` reads the quadratic frames (with the scene's simulation: every node is a vertex of it) */
  bs_audit_list L;
  bs_audit_totals AT;
  bs_error err;
  cr_assert_eq(bs_audit_list_frames(dir, &L, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_audit_run(&L, s, NULL, NULL, &AT, &err), 0, "%s", err.msg);
  cr_expect_eq(AT.n_frames, 2);
  cr_expect_eq(AT.unreadable, 0, "%d quadratic frames could not be audited", AT.unreadable);
  cr_expect_eq(AT.inverted, 0);
  cr_expect_eq(AT.self_pairs, 0);
  bs_audit_list_free(&L);
  char cmd[256];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* The audit of a quadratic VTU: a clean box, then one midside node pushed
 * along its edge to 0.9 of it, which folds the curved map of every tet around
 * that edge while their corners stay positive. */
Test(tet10_sim, audit_sees_a_folded_quadratic_element) {
  char dir[] = "/tmp/bs_test_tet10_audit_XXXXXX";
  cr_assert_not_null(mkdtemp(dir));
  bs_mesh *m = NULL;
  bs_error err;
  bs_error_clear(&err);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.2, 0.1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 3, 2, 1, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_tet10_mesh(m, &err), 0, "%s", err.msg);
  const size_t n3 = 3 * (size_t)m->n_vertices;
  double *x = malloc(n3 * sizeof(double));
  memcpy(x, m->x, n3 * sizeof(double));
  char path[1200];
  snprintf(path, sizeof path, "%s/clean.vtu", dir);
  bs_vtu_fields f = {.x = x};
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), 0, "%s", err.msg);
  bs_auditor *a = NULL;
  bs_audit_counts c;
  cr_assert_eq(bs_auditor_create(NULL, &a, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_auditor_frame(a, path, 0, &c, &err), 0, "%s", err.msg);
  cr_expect_eq(c.n_tets, m->n_tets);
  cr_expect_eq(c.inverted, 0);
  cr_expect_eq(c.self_pairs, 0);
  /* tet 0's edge (0, 1): its midside node to 0.9 of the way from node 0 to node 1 */
  const int32_t va = m->tets10[0], vb = m->tets10[1], mid = m->tets10[4];
  for (int k = 0; k < 3; k++) x[3 * mid + k] = m->x[3 * va + k] + 0.9 * (m->x[3 * vb + k] - m->x[3 * va + k]);
  int32_t around = 0;
  for (int32_t t = 0; t < m->n_tets; t++) {
    int has = 0;
    for (int j = 0; j < 4; j++) has += m->tets[4 * t + j] == va || m->tets[4 * t + j] == vb;
    around += has == 2;
  }
  snprintf(path, sizeof path, "%s/folded.vtu", dir);
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_auditor_frame(a, path, 0, &c, &err), 0, "%s", err.msg);
  cr_expect_eq(c.inverted, around, "%d folded tets seen, %d share the edge", c.inverted, around);
  cr_expect_gt(around, 0);
  bs_auditor_destroy(&a);
  bs_mesh_destroy(&m);
  free(x);
  char cmd[1300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
}

/* ---- dynamics and obstacles ---- */

static const char *const drop_scene =
    "{\"time\": {\"fps\": 24, \"frames\": 12, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"optimization\", \"linear\": \"cg\", \"tolerance\": 1e-4},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [0.2, 0.2, 0.2]}, \"element\": \"tet10\",\n"
    "   \"translate\": [0, 0.05, 0], \"velocity\": [0, -1, 0],\n"
    "   \"material\": {\"model\": \"stable_neo_hookean\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": 0, \"collision\": \"%s\"%s}]}\n";

/* A tet10 cube thrown on the ground: every node (corners and midside nodes)
 * stays above it (constraint: to rounding; penalty: within a small depth). */
static void drop(const char *collision, const char *extra, double depth) {
  char text[2048];
  snprintf(text, sizeof text, drop_scene, collision, extra);
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "drop", &sc);
  bs_error err;
  bs_error_clear(&err);
  sim_rec rec;
  memset(&rec, 0, sizeof rec);
  rec.first_clean = -1;
  bs_run_totals T;
  cr_assert_eq(bs_sim_run(s, sim_rec_frame, &rec, &T, &err), 0, "%s", err.msg);
  cr_expect_eq(rec.nonfinite, 0, "%s", rec.nonfinite_msg);
  cr_expect_eq(rec.max_inverted, 0);
  double lo = INFINITY, vy = 0, M = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) {
    lo = fmin(lo, s->x[3 * v + 1]);
    vy += s->fem->mass[v] * s->v[3 * v + 1], M += s->fem->mass[v];
  }
  cr_log_info("tet10 drop (%s): lowest node y = %g, mean vy %g m/s after %d frames", collision, lo, vy / M, rec.frames);
  cr_expect_geq(lo, -depth, "%s: a node is %g below the ground", collision, -lo);
  cr_expect_lt(fabs(vy / M), 0.5, "%s: the cube did not stop on the ground (vy %g)", collision, vy / M);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(tet10_sim, dynamic_drop_on_obstacles) {
  drop("constraint", "", 1e-9);
  drop("penalty", ", \"stiffness\": 1e7", 5e-3);
}

/* ---- bigstep mesh --order 2 ---- */

Test(tet10_cli, mesh_convert_order_2_passes_gmsh_check) {
  char dir[] = "/tmp/bs_test_tet10_msh_XXXXXX", cmd[2048], path[1024];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/box2.msh", dir);
  snprintf(cmd, sizeof cmd, "'%s' mesh convert box:4x2x2:1x0.5x0.5 '%s' --order 2 > '%s/out.txt' 2>&1", BS_BIGSTEP_EXE,
           path, dir);
  cr_assert_eq(system(cmd), 0, "%s failed", cmd);
  FILE *fp = fopen(path, "rb");
  cr_assert(fp);
  static char text[1 << 20];
  const size_t n = fread(text, 1, sizeof text - 1, fp);
  text[n] = 0;
  fclose(fp);
  /* 4x2x2 Kuhn cells: 96 tets on the volume entity, 10 nodes each (Gmsh type 11); 225 nodes; 6-node triangles */
  cr_expect(strstr(text, "\n3 1 11 96\n"), "no block of 96 10-node tets");
  cr_expect(strstr(text, "\n7 225 1 225\n"), "not 225 nodes");
  cr_expect(strstr(text, " 9 8\n") || strstr(text, " 9 16\n"), "no 6-node triangle block");
  cr_expect_eq(system("'" BS_BIGSTEP_EXE "' mesh convert box:2 /dev/null/x.msh --order 3 > /dev/null 2>&1") == 0, 0,
               "--order 3 accepted");
  if (system("command -v gmsh > /dev/null 2>&1") == 0) {
    snprintf(cmd, sizeof cmd, "gmsh - '%s' -check > '%s/check.txt' 2>&1", path, dir);
    cr_expect_eq(system(cmd), 0, "gmsh -check failed");
    snprintf(path, sizeof path, "%s/check.txt", dir);
    fp = fopen(path, "rb");
    cr_assert(fp);
    const size_t k = fread(text, 1, sizeof text - 1, fp);
    text[k] = 0;
    fclose(fp);
    cr_expect(strstr(text, "Done checking mesh coherence"), "gmsh -check: %s", text);
    cr_expect(!strstr(text, "Error") && !strstr(text, "Warning"), "gmsh -check: %s", text);
  } else {
    cr_log_warn("gmsh not on PATH: the file's check by gmsh -check skipped");
  }
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
}

/* ---- reading a .msh of 10-node tets ---- */

Test(tet10_mesh, msh_of_10_node_tets_round_trip_and_curved_edge) {
  char dir[] = "/tmp/bs_test_tet10_read_XXXXXX", path[512];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/q.msh", dir);
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL, *r = NULL;
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 0.5, 0.5};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 4, 2, 2, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_tet10_mesh(m, &err), 0, "%s", err.msg);
  /* bulge the midside node of one boundary edge of the face ymax outward (y up by 0.02) */
  const int32_t a = m->edges[0], b = m->edges[1];
  int32_t bulged = -1;
  for (int32_t e = 0; e < m->n_edges && bulged < 0; e++) {
    const int32_t p = m->edges[2 * e], q = m->edges[2 * e + 1];
    if (m->x[3 * p + 1] == 0.5 && m->x[3 * q + 1] == 0.5) bulged = bs_mesh_edge_node(m, p, q);
  }
  (void)a, (void)b;
  cr_assert_geq(bulged, 0);
  const size_t n3 = 3 * (size_t)m->n_vertices;
  double *x = malloc(sizeof(double) * n3);
  memcpy(x, m->x, sizeof(double) * n3);
  x[3 * bulged + 1] += 0.02;
  cr_assert_eq(bs_mesh_write_msh(m, x, path, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_mesh_read(path, NULL, &r, &err), 0, "%s", err.msg);
  cr_expect_eq(r->n_vertices, m->n_corners, "the linear mesh of the corners");
  cr_expect_eq(r->n_dropped, 0, "midside nodes counted as dropped: %d", r->n_dropped);
  cr_expect_eq(r->n_midside, 6 * r->n_tets);
  cr_assert_eq(bs_tet10_mesh(r, &err), 0, "%s", err.msg);
  cr_expect_eq(r->n_vertices, m->n_vertices);
  cr_expect_eq(r->n_midside, 0);
  /* every node where the file put it: the bulged one off its edge, the others at their edges' midpoints */
  int moved = 0;
  for (int32_t v = 0; v < r->n_vertices; v++) {
    double best = INFINITY;
    for (int32_t u = 0; u < m->n_vertices; u++) {
      const double d = fabs(r->x[3 * v] - x[3 * u]) + fabs(r->x[3 * v + 1] - x[3 * u + 1]) + fabs(r->x[3 * v + 2] - x[3 * u + 2]);
      if (d < best) best = d;
    }
    cr_expect_lt(best, 1e-15, "node %d is at no node of the written file", v);
    moved += r->x[3 * v + 1] > 0.5;
  }
  cr_expect_eq(moved, 1, "%d nodes above y = 0.5, the bulged one only expected", moved);
  /* the fem: the 14-point rule on the curved tets (those with the bulged node), 4 points elsewhere */
  bs_material mat;
  bs_fem *fem = NULL;
  cr_assert_eq(bs_material_init(BS_MODEL_NEO_HOOKEAN, 1e6, 0.3, 1000, &mat, &err), 0);
  cr_assert_eq(bs_fem_create(r, 1, &mat, NULL, &fem, &err), 0, "%s", err.msg);
  int curved = 0;
  for (int32_t t = 0; t < r->n_tets; t++) {
    int has = 0;
    for (int k = 0; k < 10; k++) has |= r->x[3 * r->tets10[10 * t + k] + 1] > 0.5;
    cr_expect_eq(fem->q_ptr[t + 1] - fem->q_ptr[t], has ? 14 : 4, "tet %d", t);
    curved += has;
  }
  cr_expect_gt(curved, 0);
  double vol = 0;
  for (int32_t t = 0; t < r->n_tets; t++) vol += fem->volume[t];
  cr_expect_gt(vol, 0.25, "the bulge adds volume: %g", vol);
  bs_fem_destroy(&fem);
  /* a bulge past the edge folds the element: refused, named */
  x[3 * bulged + 1] = 0.5 - 10.0;
  cr_assert_eq(bs_mesh_write_msh(m, x, path, &err), 0, "%s", err.msg);
  bs_mesh_destroy(&r);
  cr_assert_eq(bs_mesh_read(path, NULL, &r, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_tet10_mesh(r, &err), 0, "%s", err.msg);
  cr_expect_neq(bs_fem_create(r, 1, &mat, NULL, &fem, &err), 0);
  cr_expect(strstr(err.msg, "folded") || strstr(err.msg, "det J"), "%s", err.msg);
  bs_fem_destroy(&fem);
  bs_mesh_destroy(&r);
  bs_mesh_destroy(&m);
  free(x);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
}

Test(tet10_sim, scene_with_a_msh_of_10_node_tets) {
  char dir[] = "/tmp/bs_test_tet10_scene_XXXXXX", path[512], set[700];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/beam.msh", dir);
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "'%s' mesh convert box:20x2x2:1x0.1x0.1 '%s' --order 2 > /dev/null 2>&1", BS_BIGSTEP_EXE, path);
  cr_assert_eq(system(cmd), 0, "%s", cmd);
  /* beam_sag.json with the mesh file in place of its box */
  char scene[600];
  snprintf(scene, sizeof scene, "%s/beam.json", dir);
  FILE *fp = fopen(scene, "w");
  cr_assert(fp);
  fprintf(fp, "{\"time\": {\"fps\": 24, \"frames\": 48, \"steps_per_frame\": 1},\n"
              " \"solver\": {\"method\": \"optimization\", \"linear\": \"cg\", \"tolerance\": 1e-6, \"mode\": \"static\"},\n"
              " \"gravity\": [0, -9.8, 0],\n"
              " \"bodies\": [{\"mesh\": \"beam.msh\", \"element\": \"tet10\",\n"
              "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e8, \"poisson\": 0.3, \"density\": 1000},\n"
              "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}],\n"
              " \"qoi\": [{\"name\": \"tip_y\", \"quantity\": \"displacement\", \"group\": \"xmax\", \"component\": \"y\"},\n"
              "         {\"name\": \"clamp_y\", \"quantity\": \"reaction\", \"group\": \"xmin\", \"component\": \"y\"}]}\n");
  fclose(fp);
  snprintf(set, sizeof set, "output.vtu_every=0");
  int32_t n = 0;
  const double d = beam_tip_of(scene, set, NULL, &n);
  const double d_box = beam_tip("bodies.0.element=tet10 output.vtu_every=0", NULL, NULL);
  cr_expect_eq(n, 1025);
  cr_expect_float_eq(d, d_box, 1e-6 * d_box, "the .msh of 10-node tets: tip %g, the box's %g", d, d_box);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
}
