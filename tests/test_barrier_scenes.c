/* test_barrier_scenes.c — scenes with self_collision.model "barrier": a
 * stiff box thrown at a thin (flattened) torus tube at one step per frame
 * never intersects it; a box resting on a fixed box keeps a gap in
 * (0, dhat]; bad input named. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bs_ipc_term.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"

static bs_scene *parse(const char *text) {
  bs_scene *sc = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_scene_parse(text, "test", 0, NULL, &sc, &err), 0, "%s", err.msg);
  return sc;
}

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

/* The box (body 1) falls at 6 m/s on the tube of a torus (body 0, major
 * radius 0.5, tube flattened to 0.1 m thick, every vertex fixed): 0.25 m
 * per step, more than twice the tube's thickness. */
Test(barrier_scenes, box_thrown_at_a_thin_tube_never_intersects_it, .timeout = 600) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"time\": {\"fps\": 24, \"frames\": 8, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-4},\n"
           " \"gravity\": [0, 0, -9.8],\n"
           " \"bodies\": [{\"mesh\": \"%s/data/geo/torus.geo\", \"mesh_size\": 0.12, \"scale\": [1, 1, 0.25],\n"
           "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000},\n"
           "   \"scripted\": [{\"group\": \"body\", \"fixed\": true}]},\n"
           "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [0.3, 0.3, 0.3]},\n"
           "   \"translate\": [0.35, -0.15, 0.3], \"velocity\": [0, 0, -6],\n"
           "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}}],\n"
           " \"self_collision\": {\"model\": \"barrier\"}}\n",
           BS_SOURCE_DIR);
  bs_scene *sc = parse(text);
  bs_sim *s = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_not_null(s->barrier);
  long limited = 0;
  double zmin_box = INFINITY;
  for (int f = 1; f <= sc->frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    for (int k = 0; k < fs.n_steps; k++) limited += fs.steps[k].st.min.ccd_limited;
    bs_sim_measures m;
    bs_sim_measure(s, 1, &m);
    cr_assert_eq(m.self_intersections, 0, "frame %d: %lld intersecting triangle pairs", f,
                 (long long)m.self_intersections);
    bs_ipc_stats st;
    cr_assert_eq(bs_term_ipc_stats(s->barrier, &st, &err), 0);
    zmin_box = INFINITY;
    for (int32_t v = s->vertex_offset[1]; v < s->vertex_offset[2]; v++) zmin_box = fmin(zmin_box, s->x[3 * v + 2]);
    fprintf(stderr, "frame %d: failed %ld, iterations %ld, box z min %.4f, kappa %.3e, pairs %lld, min dist %.3e\n", f,
            fs.failed, fs.iterations, zmin_box, st.kappa, (long long)(st.pairs_pt + st.pairs_ee), st.min_distance);
  }
  cr_assert_gt(limited, 0, "no line search was bounded by the CCD");
  /* it did not pass through the tube: the box's bottom stays above the tube's */
  cr_assert_gt(zmin_box, -0.05, "box bottom at z = %g", zmin_box);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* A 0.2 m box on a fixed 0.4 m box, starting 1 mm above it (dhat 2 mm),
 * at rest under gravity: the surfaces never meet and the gap ends in
 * (0, dhat]. */
Test(barrier_scenes, resting_box_keeps_a_gap_within_dhat, .timeout = 600) {
  const char *text =
      "{\"time\": {\"fps\": 24, \"frames\": 12, \"steps_per_frame\": 1},\n"
      " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-5},\n"
      " \"gravity\": [0, 0, -9.8],\n"
      " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [0.4, 0.4, 0.2]},\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000},\n"
      "   \"scripted\": [{\"group\": \"zmin\", \"fixed\": true}]},\n"
      "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [0.2, 0.2, 0.2]},\n"
      "   \"translate\": [0.1, 0.1, 0.201],\n"
      "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000}}],\n"
      " \"self_collision\": {\"model\": \"barrier\"}, \"contact\": {\"dhat\": 0.002}}\n";
  bs_scene *sc = parse(text);
  bs_sim *s = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  bs_ipc_stats st;
  for (int f = 1; f <= sc->frames; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    cr_assert_eq(fs.failed, 0, "frame %d: %s", f, fs.steps[0].reason);
    cr_assert_eq(bs_term_ipc_detect(s->barrier, s->x, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.intersecting, 0, "frame %d", f);
  }
  cr_assert_gt(st.min_distance, 0);
  cr_assert_leq(st.min_distance, 0.002, "gap %g", st.min_distance);
  cr_assert_gt(st.pairs_pt + st.pairs_ee, 0, "not in contact at the end");
  /* frames.csv's contact columns: min distance, pairs, CCD-limited searches, kappa */
  bs_sim_measures m;
  bs_sim_measure(s, 0, &m);
  cr_assert_eq(m.contact_min_distance, st.min_distance);
  cr_assert_eq(m.contact_pairs, st.pairs_pt + st.pairs_ee);
  cr_assert_gt(m.kappa, 0);
  bs_frame_stats fs = {0};
  char row[512];
  bs_frames_csv_row(row, sizeof row, s->time, &fs, &m);
  int commas = 0, hdr = 0;
  for (const char *c = row; *c; c++) commas += *c == ',';
  for (const char *c = BS_FRAMES_CSV_HEADER; *c; c++) hdr += *c == ',';
  cr_assert_eq(commas, hdr, "%s", row);
  cr_assert(strstr(BS_FRAMES_CSV_HEADER, ",contact_min_distance,contact_pairs,ccd_limited,kappa"));
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

#define TWO_BOXES(extra, z)                                                                                           \
  "{\"time\": {\"fps\": 24, \"frames\": 1},\n"                                                                       \
  " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1], \"size\": [1, 1, 1]},\n"                         \
  "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}},\n"                                      \
  "  {\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1], \"size\": [1, 1, 1]}, \"translate\": [0.25, 0.25, " z "],\n" \
  "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"                                     \
  " \"self_collision\": {\"model\": \"barrier\"}" extra "}\n"

Test(barrier_scenes, bad_input_is_named) {
  bs_error err = {0};
  cr_assert_eq(parse_fails(TWO_BOXES(", \"contact\": {\"dhat\": 0}", "2"), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.dhat"), "%s", err.msg);
  cr_assert_eq(parse_fails(TWO_BOXES(", \"contact\": {\"dhat\": -1}", "2"), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.dhat"), "%s", err.msg);
  cr_assert_eq(parse_fails(TWO_BOXES(", \"contact\": {\"kappa\": 0}", "2"), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.kappa"), "%s", err.msg);
  cr_assert_eq(parse_fails(TWO_BOXES(", \"contact\": {\"dhat\": \"auto\"}", "2"), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.dhat"), "%s", err.msg);
  /* the second box sunk half into the first: intersecting at t = 0 */
  cr_assert_eq(parse_fails(TWO_BOXES("", "0.5"), &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "bodies 0 and 1") && strstr(err.msg, "intersect"), "%s", err.msg);
  /* a NaN dhat set in C */
  bs_scene *sc = parse(TWO_BOXES("", "2"));
  sc->contact_dhat = NAN;
  bs_sim *s = NULL;
  cr_assert_eq(bs_sim_create(sc, &s, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "contact.dhat"), "%s", err.msg);
  bs_scene_destroy(&sc);
  /* the model's name */
  cr_assert_eq(parse_fails(TWO_BOXES("", "2") , &err), 0, "%s", err.msg);
  const char *bad_model = "{\"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [1, 1, 1]},"
                          " \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],"
                          " \"self_collision\": {\"model\": \"ipc\"}}";
  cr_assert_eq(parse_fails(bad_model, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "self_collision.model"), "%s", err.msg);
}
