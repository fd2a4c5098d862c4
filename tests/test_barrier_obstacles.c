/* test_barrier_obstacles.c — scenes with obstacles[].collision "barrier": a
 * box thrown at a barrier plane at one step per frame never has a vertex
 * inside; a block on an incline (a tilted barrier plane) sticks below
 * tan(theta) = mu and slides above it with the acceleration
 * g (sin theta - mu cos theta) within 1%; a slab faster than a box's gap
 * per step sweeps the box along; bad input named. */
#include <criterion/criterion.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bs_ipc_obstacle.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "sim_util.h"

static int parse_fails(const char *text, bs_error *err) {
  bs_scene *sc = NULL;
  int st = bs_scene_parse(text, "test", 0, NULL, &sc, err);
  if (!st) {
    bs_sim *s = NULL;
    st = bs_sim_create(sc, &s, err);
    bs_sim_destroy(&s);
  }
  bs_scene_destroy(&sc);
  return st;
}

/* The smallest phi over every vertex of s against the scene's obstacle 0. */
static double min_phi(const bs_sim *s) {
  const bs_levelset *ls = bs_obstacles_levelset(s->obstacles, 0);
  double m = INFINITY;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) m = fmin(m, bs_levelset_eval(ls, s->time, s->x + 3 * v, NULL, NULL));
  return m;
}

Test(barrier_obstacles, box_thrown_at_a_plane_never_has_a_vertex_inside, .timeout = 600) {
  const char *text =
      "{\"time\": {\"fps\": 24, \"frames\": 16, \"steps_per_frame\": 1},\n"
      " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-5},\n"
      " \"gravity\": [0, 0, -9.8],\n"
      " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [0.3, 0.3, 0.3]},\n"
      "   \"translate\": [0, 0, 0.3], \"velocity\": [1, 0, -6],\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000}}],\n"
      " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 0, 1], \"offset\": 0, \"collision\": \"barrier\",\n"
      "   \"friction\": 0.3}]}\n";
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "test", &sc);
  bs_error err = {0};
  cr_assert_not_null(s->obstacle_barrier);
  long limited = 0;
  for (int f = 1; f <= sc->frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    for (int k = 0; k < fs.n_steps; k++) limited += fs.steps[k].st.min.ccd_limited;
    bs_sim_measures m;
    bs_sim_measure(s, 0, &m);
    const double mp = min_phi(s);
    fprintf(stderr, "frame %d: failed %ld, iterations %ld, min phi %.4e, kappa %.3e\n", f, fs.failed, fs.iterations,
            mp, m.kappa);
    cr_assert_gt(mp, 0, "frame %d: a vertex at phi = %g", f, mp);
    cr_assert_eq(m.penetrating, 0, "frame %d", f);
    cr_assert_eq(m.obstacle_min_distance, mp, "frame %d: %g vs %g", f, m.obstacle_min_distance, mp);
  }
  cr_assert_gt(limited, 0, "no line search was bounded by the CCD");
  bs_sim_measures m;
  bs_sim_measure(s, 0, &m);
  bs_frame_stats fs = {0};
  char row[512];
  bs_frames_csv_row(row, sizeof row, s->time, &fs, &m);
  int commas = 0, hdr = 0;
  for (const char *c = row; *c; c++) commas += *c == ',';
  for (const char *c = BS_FRAMES_CSV_HEADER; *c; c++) hdr += *c == ',';
  cr_assert_eq(commas, hdr, "%s", row);
  cr_assert(strstr(BS_FRAMES_CSV_HEADER, ",obstacle_min_distance"));
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* A 0.2 x 0.2 x 0.1 block on a plane tilted by theta about y (normal
 * (sin, 0, cos)), the block rotated alike and lifted 0.5 mm off it (dhat
 * 1 mm), gravity -z. Returns the mean velocity along the downhill direction
 * (cos, 0, -sin) at frames f1 and f2 (1 s = 50 frames). */
static void incline(double theta_deg, double mu, int f1, int f2, double *v1, double *v2) {
  const double th = theta_deg * M_PI / 180, n[3] = {sin(th), 0, cos(th)}, t[3] = {cos(th), 0, -sin(th)};
  char text[2048];
  snprintf(text, sizeof text,
           "{\"time\": {\"fps\": 50, \"frames\": %d, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-7},\n"
           " \"gravity\": [0, 0, -9.8],\n"
           " \"contact\": {\"dhat\": 0.001},\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 1], \"size\": [0.2, 0.2, 0.1]},\n"
           "   \"rotate\": [0, %.17g, 0], \"translate\": [%.17g, 0, %.17g],\n"
           "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}}],\n"
           " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [%.17g, 0, %.17g], \"offset\": 0,\n"
           "   \"collision\": \"barrier\", \"friction\": %g}]}\n",
           f2, theta_deg, 5e-4 * n[0], 5e-4 * n[2], n[0], n[2], mu);
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "test", &sc);
  bs_error err = {0};
  cr_assert_gt(min_phi(s), 4e-4);
  for (int f = 1; f <= f2; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    cr_assert_eq(fs.failed, 0, "frame %d", f);
    cr_assert_gt(min_phi(s), 0, "frame %d", f);
    double v = 0, mass = 0;
    for (int32_t i = 0; i < s->mesh->n_vertices; i++) {
      const double *vi = s->v + 3 * i, m = s->fem->mass[i];
      v += m * (vi[0] * t[0] + vi[1] * t[1] + vi[2] * t[2]);
      mass += m;
    }
    v /= mass;
    if (f == f1) *v1 = v;
    if (f == f2) *v2 = v;
  }
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(barrier_obstacles, block_on_incline_sticks_below_the_friction_angle, .timeout = 900) {
  double v1 = 0, v2 = 0; /* tan 20 deg = 0.364 < mu = 0.5 */
  incline(20, 0.5, 25, 50, &v1, &v2);
  fprintf(stderr, "stick: v(0.5 s) = %.3e, v(1 s) = %.3e m/s (eps_v 1e-3)\n", v1, v2);
  cr_assert_lt(fabs(v1), 1e-3);
  cr_assert_lt(fabs(v2), 1e-3);
}

Test(barrier_obstacles, block_on_incline_slides_with_the_coulomb_acceleration, .timeout = 900) {
  double v1 = 0, v2 = 0; /* tan 20 deg = 0.364 > mu = 0.2 */
  incline(20, 0.2, 20, 50, &v1, &v2);
  const double th = 20 * M_PI / 180, a = (v2 - v1) / 0.6, want = 9.8 * (sin(th) - 0.2 * cos(th));
  fprintf(stderr, "slide: v(0.4 s) = %.6f, v(1 s) = %.6f, a = %.6f, analytic %.6f (%.3f%%)\n", v1, v2, a, want,
          100 * (a - want) / want);
  cr_assert_lt(fabs(a - want), 0.01 * want, "a = %g, want %g", a, want);
}

#define PLANE_SCENE(extra, obstacle)                                                                     \
  "{\"time\": {\"fps\": 24, \"frames\": 1},\n"                                                           \
  " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1], \"size\": [1, 1, 1]},\n"            \
  "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"                        \
  " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 0, 1], " obstacle "}]" extra "}\n"

Test(barrier_obstacles, bad_input_is_named) {
  bs_error err = {0};
  cr_assert_eq(parse_fails(PLANE_SCENE("", "\"offset\": -0.5, \"collision\": \"barrier\""), &err), 0, "%s", err.msg);
  /* the box on the plane z = 0: its bottom vertices touch */
  cr_assert_eq(parse_fails(PLANE_SCENE("", "\"offset\": 0, \"collision\": \"barrier\""), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacles[].collision \"barrier\"") && strstr(err.msg, "inside or on"), "%s", err.msg);
  cr_assert_eq(parse_fails(PLANE_SCENE(", \"contact\": {\"eps_v\": 0}", "\"offset\": -0.5, \"collision\": \"barrier\""),
                           &err),
               BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.eps_v"), "%s", err.msg);
  cr_assert_eq(parse_fails(PLANE_SCENE("", "\"offset\": -0.5, \"collision\": \"ipc\""), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "obstacles") && strstr(err.msg, "barrier"), "%s", err.msg);
  cr_assert_eq(parse_fails(PLANE_SCENE(", \"contact\": {\"dhat\": -1}", "\"offset\": -0.5, \"collision\": \"barrier\""),
                           &err),
               BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.dhat"), "%s", err.msg);
}

/* A barrier obstacle that passes over the box within one step (a slab at
 * 40 m/s, 1.67 m per step, starting 1 m above the box's top, no gravity)
 * is swept through the step (bs_step.h, "Moving obstacles"): no vertex is
 * ever inside it, the first step sweeps, and the box ends moving with the
 * slab: its mean velocity is -40 m/s along z within 2%, since the slab is
 * prescribed (infinitely massive) and the backward Euler contact is
 * inelastic. */
/* Runs the frames of a stack struck by a barrier slab (obstacle 0),
 * asserting at each that its step converged, that no vertex is inside the
 * slab, no surface pair crosses (CGAL's exact audit) and no tet is
 * inverted; returns the sweep's stages over the frames. */
static int stack_frames(bs_sim *s, int frames) {
  bs_error err = {0};
  int stages = 0;
  for (int f = 1; f <= frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    stages += fs.steps[0].st.sweep_stages;
    cr_log_info("frame %d: %d stages, %d newton\n", f, fs.steps[0].st.sweep_stages, fs.steps[0].st.min.iterations);
    cr_expect_eq(fs.steps[0].st.failed, 0, "frame %d: the step did not converge", f);
    cr_assert_gt(min_phi(s), 0, "frame %d: a vertex is inside the slab", f);
    bs_sim_measures m;
    bs_sim_measure(s, 1, &m);
    cr_assert_eq(m.inverted, 0, "frame %d", f);
    cr_assert_eq(m.self_intersections, 0, "frame %d: the boxes' surfaces cross", f);
  }
  return stages;
}

/* The slab at 40 m/s onto two boxes stacked 5 mm apart (dhat 1 cm): the
 * sweep carries the box it meets, and the box under it with it (their
 * contact's pairs, bs_step.h "Moving obstacles"), each as a rigid body, so
 * the stack is swept in few stages; no vertex is ever inside the slab, no
 * surface pair ever crosses (CGAL's exact audit), and both boxes leave at
 * least as fast as the slab. */
Test(barrier_obstacles, a_fast_slab_sweeps_a_stack_of_boxes_as_rigid_bodies, .timeout = 300) {
  const char *text =
      "{\"time\": {\"fps\": 24, \"frames\": 6},\n"
      " \"gravity\": [0, 0, 0],\n"
      " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}},\n"
      "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]}, \"translate\": [0, 0, 1.005],\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}}],\n"
      " \"self_collision\": {\"model\": \"barrier\"}, \"contact\": {\"dhat\": 0.01},\n"
      " \"obstacles\": [{\"shape\": \"box\", \"center\": [0, 0, 3.505], \"half_extents\": [5, 5, 0.5],\n"
      "   \"velocity\": [0, 0, -40], \"collision\": \"barrier\"}]}\n";
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "test", &sc);
  const int stages = stack_frames(s, sc->frames);
  cr_log_info("%d stages over %d steps\n", stages, sc->frames);
  /* 13 (4, 1, 1, 1, 3, 3); carrying only the vertices within dhat of the
     slab, and the rest by the linear response, took 55 (13, 14, 20, 2, 3, 3) */
  cr_expect_leq(stages, 3 * sc->frames, "%d stages in %d steps", stages, sc->frames);
  const int32_t half = s->mesh->n_vertices / 2;
  double vz[2] = {0, 0};
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) vz[v >= half] += s->v[3 * v + 2] / half;
  /* pushed, neither is slower than the slab; the one below, struck through
     the other, leaves faster (-42.1 and -40.9 m/s at frame 6) */
  for (int b = 0; b < 2; b++)
    cr_expect(vz[b] < -40 * 0.99 && vz[b] > -40 * 1.1, "box %d's mean velocity is %g m/s, the slab's -40", b, vz[b]);
  cr_expect_lt(vz[0], vz[1], "the box below is not the faster one");
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* The slab at 2 m/s onto a box resting 5 mm above a box whose bottom is
 * fixed: the struck box cannot be carried whole into the fixed one (the
 * CCD between them stops it at once), and the fixed box is not a rigid
 * body, so the predictor without rigid bodies takes over where it goes
 * further. Over 3 steps the slab presses the stack: every step converges;
 * no vertex inside the slab, no surface pair crossing, no inverted tet, the
 * fixed vertices where they were. */
Test(barrier_obstacles, a_slab_pressing_a_box_onto_a_fixed_one_is_swept, .timeout = 300) {
  const char *text =
      "{\"time\": {\"fps\": 24, \"frames\": 3},\n"
      " \"gravity\": [0, 0, 0],\n"
      " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000},\n"
      "   \"scripted\": [{\"group\": \"zmin\", \"fixed\": true}]},\n"
      "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]}, \"translate\": [0, 0, 1.005],\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}}],\n"
      " \"self_collision\": {\"model\": \"barrier\"}, \"contact\": {\"dhat\": 0.01},\n"
      " \"obstacles\": [{\"shape\": \"box\", \"center\": [0, 0, 2.51], \"half_extents\": [5, 5, 0.5],\n"
      "   \"velocity\": [0, 0, -2], \"collision\": \"barrier\"}]}\n";
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "test", &sc);
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  double *x0 = malloc(sizeof(double) * n3);
  memcpy(x0, s->x, sizeof(double) * n3);
  const int stages = stack_frames(s, sc->frames);
  cr_expect_gt(stages, 0, "the slab was never swept");
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    if (x0[3 * v + 2] == 0.0)
      cr_expect_arr_eq(s->x + 3 * v, x0 + 3 * v, 3 * sizeof(double), "fixed vertex %d moved", v);
  double ztop = -INFINITY;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) ztop = fmax(ztop, s->x[3 * v + 2]);
  cr_expect_lt(ztop, 2.005 - 0.1, "the stack's top is at %g: the slab did not press it", ztop);
  free(x0);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(barrier_obstacles, a_fast_slab_sweeps_the_box_along_and_never_has_it_inside, .timeout = 300) {
  const char *text =
      "{\"time\": {\"fps\": 24, \"frames\": 6},\n"
      " \"gravity\": [0, 0, 0],\n"
      " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}}],\n"
      " \"obstacles\": [{\"shape\": \"box\", \"center\": [0, 0, 2.5], \"half_extents\": [5, 5, 0.5],\n"
      "   \"velocity\": [0, 0, -40], \"collision\": \"barrier\"}]}\n";
  bs_scene *sc = NULL;
  bs_sim *s = sim_from_text(text, "test", &sc);
  bs_error err = {0};
  for (int f = 1; f <= sc->frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    if (f == 1) cr_assert_gt(fs.steps[0].st.sweep_stages, 0, "the first step was not swept");
    cr_assert_gt(min_phi(s), 0, "frame %d: a vertex is inside the slab", f);
    bs_sim_measures m;
    bs_sim_measure(s, 0, &m);
    cr_assert_eq(m.inverted, 0, "frame %d", f);
  }
  double vz = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) vz += s->v[3 * v + 2] / s->mesh->n_vertices;
  cr_assert(vz < -40 * 0.98 && vz > -40 * 1.02, "the box's mean velocity is %g m/s, the slab's -40", vz);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}
