/* The resolved scene (bs_scene_write_json): every shipped scene
 * (data/scenes/, data/scenes/paper/) loads, and load -> write -> parse ->
 * write gives the same text and the same struct; a scene built in C comes
 * back field for field; a minimal scene resolves to the schema table's
 * defaults, key by key; mesh paths come out absolute. */
#define _GNU_SOURCE /* realpath */
#include <cJSON.h>
#include <criterion/criterion.h>
#include <glob.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_scene.h"
#include "scene_fixture.h"
#include "scene_full.h"
#include "scene_schema.h"

#define EQ(f) cr_expect(a->f == b->f, "%s: " #f " differs", where)
#define EQ3(f) cr_expect(!memcmp(a->f, b->f, 3 * sizeof a->f[0]), "%s: " #f " differs", where)
#define EQN(f, n) cr_expect((n) == 0 || !memcmp(a->f, b->f, (size_t)(n) * sizeof a->f[0]), "%s: " #f " differs", where)

static void expect_same_solver(const bs_scene *a, const bs_scene *b, const char *where) {
  EQ(solver.method); EQ(solver.newton_k); EQ(solver.amg_at_rest); EQ(mode); EQ(load_steps); EQ(project_hessian);
  EQ(solver.min.tol); EQ(solver.min.max_iter); EQ(solver.min.sigma); EQ(solver.min.sigma_auto);
  EQ(solver.min.linear); EQ(solver.min.cg_max_iter); EQ(solver.min.cg_single); EQ(solver.min.forcing_ew);
  EQ(solver.min.cg_downhill); EQ(solver.min.amg_rebuild_factor); EQ(solver.min.amg_rebuild_every);
  EQ(solver.min.convexify);
}

/* The same file, whether the path is relative or absolute. */
static void expect_same_file(const char *p, const char *q, const char *where) {
  char rp[PATH_MAX], rq[PATH_MAX];
  if (!strcmp(p, q)) return;
  cr_expect(realpath(p, rp) && realpath(q, rq) && !strcmp(rp, rq), "%s: '%s' and '%s' differ", where, p, q);
}

static void expect_same_body(const bs_scene_body *a, const bs_scene_body *b, const char *where) {
  expect_same_file(a->mesh, b->mesh, where);
  EQ3(box_cells); EQ3(box_size); EQ(mesh_size); EQ(refine); EQ(close_holes); EQ(mesher); EQ(reorder); EQ3(translate); EQ3(rotate); EQ3(scale);
  EQ3(velocity); EQ3(angular_velocity); EQ(init); EQ(init_seed); EQ(n_materials); EQ(n_scripts);
  if (a->init != BS_INIT_REST) EQ3(init_lo);
  if (a->init == BS_INIT_RANDOM) EQ3(init_hi);
  for (int m = 0; m < a->n_materials && m < b->n_materials; m++) {
    const bs_scene_material *x = &a->materials[m], *y = &b->materials[m];
    cr_expect(!strcmp(x->group, y->group) && x->model == y->model && x->youngs == y->youngs &&
                  x->poisson == y->poisson && x->density == y->density && x->rayleigh == y->rayleigh,
              "%s: material %d differs", where, m);
  }
  for (int k = 0; k < a->n_scripts && k < b->n_scripts; k++) {
    const bs_scene_script *x = &a->scripts[k], *y = &b->scripts[k];
    int same = !strcmp(x->group, y->group) && x->kind == y->kind && x->n_keys == y->n_keys;
    if (same && x->kind == BS_SCRIPT_VELOCITY) same = !memcmp(x->velocity, y->velocity, sizeof x->velocity);
    if (same && x->kind == BS_SCRIPT_KEYFRAMES)
      same = !memcmp(x->key_t, y->key_t, sizeof(double) * (size_t)x->n_keys) &&
             !memcmp(x->key_offset, y->key_offset, 3 * sizeof(double) * (size_t)x->n_keys);
    cr_expect(same, "%s: script %d differs", where, k);
  }
}

static void expect_same_obstacle(const bs_scene_obstacle *a, const bs_scene_obstacle *b, const char *where) {
  EQ(shape); EQ3(normal); EQ(offset); EQ3(center); EQ(radius); EQ3(half_extents); EQ3(axis); EQ(half_height);
  EQ(major); EQ(minor); EQ(inside_out); EQ(grid_h); EQ(collision); EQ(stiffness); EQ(friction); EQ3(velocity);
  EQ3(angular_velocity); EQ(n_keys);
  if (a->grid_file[0] || b->grid_file[0]) expect_same_file(a->grid_file, b->grid_file, where);
  if (a->n_keys == b->n_keys) {
    EQN(key_t, a->n_keys);
    EQN(key_translate, 3 * a->n_keys);
    EQN(key_rotate, 3 * a->n_keys);
  }
}

static void expect_same_scene(const bs_scene *a, const bs_scene *b, const char *where) {
  EQ(fps); EQ(frames); EQ(steps_per_frame); EQ(dt); EQ3(gravity); EQ(drag); EQ(n_bodies); EQ(n_obstacles);
  EQ(self_collision); EQ(vtu_every); EQ(stats_csv); EQ(states);
  if (a->self_collision) {
    EQ(self_stiffness);
    EQ(self_friction);
  }
  cr_expect_str_eq(a->out_dir, b->out_dir, "%s: output.dir", where);
  cr_expect(!a->description == !b->description && (!a->description || !strcmp(a->description, b->description)),
            "%s: description", where);
  expect_same_solver(a, b, where);
  for (int i = 0; i < a->n_bodies && i < b->n_bodies; i++) expect_same_body(&a->bodies[i], &b->bodies[i], where);
  for (int i = 0; i < a->n_obstacles && i < b->n_obstacles; i++)
    expect_same_obstacle(&a->obstacles[i], &b->obstacles[i], where);
}

/* a -> text -> parse -> text again: the same text and the same scene. */
static void round_trip(const bs_scene *a, const char *where) {
  char *t1 = NULL, *t2 = NULL;
  bs_error err;
  bs_scene *b = NULL;
  cr_assert_eq(bs_scene_write_json(a, &t1, &err), 0, "%s: %s", where, err.msg);
  cr_assert_eq(bs_scene_parse(t1, "resolved.json", 0, NULL, &b, &err), 0, "%s: the resolved scene: %s\n%s", where,
               err.msg, t1);
  cr_assert_eq(bs_scene_write_json(b, &t2, &err), 0, "%s: %s", where, err.msg);
  cr_expect_str_eq(t1, t2, "%s: the second write differs", where);
  expect_same_scene(a, b, where);
  bs_scene_destroy(&b);
  free(t1);
  free(t2);
}

Test(scene_write, shipped_scenes_load_and_round_trip) {
  glob_t g;
  cr_assert_eq(glob(BS_SOURCE_DIR "/data/scenes/*.json", 0, NULL, &g), 0);
  cr_assert_eq(glob(BS_SOURCE_DIR "/data/scenes/paper/*.json", GLOB_APPEND, NULL, &g), 0);
  cr_expect_geq(g.gl_pathc, 20, "%zu scenes", g.gl_pathc);
  for (size_t i = 0; i < g.gl_pathc; i++) {
    bs_scene *s = NULL;
    bs_error err;
    int st = bs_scene_load(g.gl_pathv[i], 0, NULL, &s, &err);
    if (st == BS_EIO && strstr(err.msg, "armadillo.off")) { /* setup.sh extracts it from libcgal-demo */
      cr_log_info("skipped: %s", err.msg);
      continue;
    }
    cr_expect_eq(st, 0, "%s", err.msg);
    if (st) continue;
    round_trip(s, g.gl_pathv[i]);
    for (int b = 0; b < s->n_bodies; b++) {
      char *t;
      cr_assert_eq(bs_scene_write_json(s, &t, &err), 0);
      cr_expect(!strcmp(s->bodies[b].mesh, "box") || strstr(t, "\"mesh\": \"/"), "%s: mesh path not absolute",
                g.gl_pathv[i]);
      free(t);
    }
    bs_scene_destroy(&s);
  }
  globfree(&g);
}

Test(scene_write, full_scene_round_trips) {
  bs_scene *s = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_parse(bs_test_full_scene, "full.json", 0, NULL, &s, &err), 0, "%s", err.msg);
  round_trip(s, "full scene");
  cr_expect_str_eq(s->description, "every section");
  bs_scene_destroy(&s);
}

/* A scene built in C with a value off the default in every section. */
Test(scene_write, scene_built_in_c_comes_back) {
  bs_scene *sc = bs_test_box_scene(3, 30, 2);
  bs_scene_body *b = &sc->bodies[0];
  bs_scene_material *m;
  bs_scene_script *scr;
  bs_scene_obstacle *o;
  bs_error err;
  b->box_size[1] = 0.25, b->refine = 1, b->close_holes = 1, b->reorder = BS_ORDER_RCM, b->scale[2] = 2, b->rotate[0] = 30;
  b->translate[1] = 0.5, b->velocity[0] = -1, b->angular_velocity[2] = 0.5;
  b->init = BS_INIT_POINT, b->init_lo[1] = 2, b->init_seed = 7;
  b->materials[0].model = BS_MODEL_NEO_HOOKEAN, b->materials[0].rayleigh = 0.01;
  cr_assert_eq(bs_scene_body_add_material(b, "body", &m, &err), 0, "%s", err.msg);
  m->youngs = 3.25e6;
  cr_assert_eq(bs_scene_body_add_script(b, "ymin", BS_SCRIPT_FIXED, &scr, &err), 0);
  cr_assert_eq(bs_scene_body_add_script(b, "ymax", BS_SCRIPT_VELOCITY, &scr, &err), 0);
  scr->velocity[1] = 0.1;
  double kt[2] = {0, 0.5}, ko[6] = {0, 0, 0, 0.1, 0.2, 1.0 / 3};
  cr_assert_eq(bs_scene_body_add_script(b, "xmax", BS_SCRIPT_KEYFRAMES, &scr, &err), 0);
  cr_assert_eq(bs_scene_script_set_keyframes(scr, 2, kt, ko, &err), 0);
  cr_assert_eq(bs_scene_add_obstacle(sc, BS_SHAPE_TORUS, &o, &err), 0);
  o->major = 0.7, o->collision = BS_COLLIDE_PENALTY, o->friction = 0.3, o->inside_out = 1, o->grid_h = 0.05;
  sc->solver.method = BS_METHOD_NEWTON_K, sc->solver.newton_k = 3, sc->solver.min.linear = BS_LIN_AMG;
  sc->solver.min.sigma_auto = 0, sc->solver.min.sigma = 0.5, sc->solver.min.cg_single = 1;
  sc->solver.amg_at_rest = 0, sc->mode = BS_MODE_STATIC, sc->load_steps = 4, sc->drag = 0.1;
  sc->self_collision = 1, sc->self_stiffness = 2e5, sc->self_friction = 0.2;
  snprintf(sc->out_dir, sizeof sc->out_dir, "out/c");
  sc->vtu_every = 0, sc->states = 1;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  round_trip(sc, "scene built in C");
  bs_scene_destroy(&sc);
}

/* Scenes with only the required keys, every section present. */
static const char *const minimal_scene =
    "{\"time\": {}, \"solver\": {}, \"self_collision\": {}, \"output\": {},\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2]},\n"
    "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"initial_state\": {\"type\": \"rest\"}, \"scripted\": [{\"group\": \"ymin\", \"fixed\": true}]}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"keyframes\": [{\"t\": 0}]}],\n"
    " \"qoi\": [{\"name\": \"q\", \"quantity\": \"energy\"}]}\n";

/* Every default of the table is the value a minimal scene resolves to. */
Test(scene_write, defaults_agree_with_the_table) {
  /* written only when they matter: the point for type point; the contact
   * section when it holds a value other than its defaults (so that scenes
   * without contact keep their identity, and their checkpoints resume) */
  static const char *const conditional[] = {"bodies.0.initial_state.point", "contact.eps_v", NULL};
  bs_scene *s = NULL;
  bs_error err;
  char *text;
  cr_assert_eq(bs_scene_parse(minimal_scene, "minimal.json", 0, NULL, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_write_json(s, &text, &err), 0, "%s", err.msg);
  cJSON *root = cJSON_Parse(text);
  cr_assert_not_null(root);
  int n = 0;
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    if (!k->def) continue;
    char path[256], buf[256];
    bs_test_key_path(k->section, k->key, path, sizeof path);
    snprintf(buf, sizeof buf, "%s", path);
    cJSON *node = root;
    for (char *save = NULL, *tok = strtok_r(buf, ".", &save); tok && node; tok = strtok_r(NULL, ".", &save))
      node = cJSON_IsArray(node) ? cJSON_GetArrayItem(node, atoi(tok)) : cJSON_GetObjectItemCaseSensitive(node, tok);
    int skip = 0;
    for (int c = 0; conditional[c]; c++) skip |= !strcmp(conditional[c], path);
    if (skip) continue;
    cJSON *def = cJSON_Parse(k->def);
    char *got = node ? cJSON_PrintUnformatted(node) : NULL;
    cr_expect(node && cJSON_Compare(node, def, 1), "%s: the table's default is %s, a minimal scene gives %s", path,
              k->def, got ? got : "nothing");
    free(got);
    cJSON_Delete(def);
    n++;
  }
  cr_expect_geq(n, 50, "only %d defaults checked", n);
  cJSON_Delete(root);
  free(text);
  bs_scene_destroy(&s);
}

/* The file writer: the same text, in a file that loads. */
Test(scene_write, write_json_file) {
  bs_scene *s = bs_test_box_scene(2, 24, 1), *t = NULL;
  bs_error err;
  char path[] = "/tmp/bs_scene_write_XXXXXX";
  int fd = mkstemp(path);
  cr_assert(fd >= 0);
  close(fd);
  cr_assert_eq(bs_scene_write_json_file(s, path, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_load(path, 0, NULL, &t, &err), 0, "%s", err.msg);
  expect_same_scene(s, t, path);
  unlink(path);
  cr_expect_eq(bs_scene_write_json_file(s, "/no/such/dir/scene.json", &err), BS_EIO);
  cr_expect(strstr(err.msg, "/no/such/dir/scene.json") != NULL, "%s", err.msg);
  bs_scene_destroy(&s);
  bs_scene_destroy(&t);
}

