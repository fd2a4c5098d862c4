/* Output fields (sim/bs_fields.h): output.fields and output.compress parsed
 * strictly (an unknown name is an error naming the key and listing the
 * allowed names), the default set, bodies told apart by "body" with the
 * material indexed within its body, and a run folder writing the chosen
 * arrays (and only those) into its frames. */
#define _GNU_SOURCE /* mkdtemp */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_fields.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_vtu_read.h"

/* Two 2^3-cell boxes side by side; body 0 gives its 3-D group "body" a
 * second material. `output` is the text of the output section. */
static char *two_boxes(const char *output) {
  static char buf[4096];
  snprintf(buf, sizeof buf,
           "{\"time\": {\"fps\": 24, \"frames\": 1},\n"
           " \"bodies\": [\n"
           "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2]},\n"
           "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
           "   \"materials\": {\"body\": {\"youngs\": 2e5, \"poisson\": 0.3, \"density\": 1000}},\n"
           "   \"scripted\": [{\"group\": \"ymin\", \"fixed\": true}]},\n"
           "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2]}, \"translate\": [2, 0, 0],\n"
           "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"
           " \"output\": %s}\n",
           output);
  return buf;
}

static int parse(const char *output, bs_scene **sc, bs_error *err) {
  return bs_scene_parse(two_boxes(output), "fields.json", 0, NULL, sc, err);
}

Test(fields, names_parse_into_a_set) {
  bs_scene *sc = NULL;
  bs_error err;
  cr_assert_eq(parse("{\"fields\": [\"von_mises\", \"body\", \"von_mises\"], \"compress\": true}", &sc, &err), 0,
               "%s", err.msg);
  cr_assert_eq(sc->out_fields, BS_FIELD_BIT(BS_FIELD_VON_MISES) | BS_FIELD_BIT(BS_FIELD_BODY));
  cr_assert_eq(sc->out_compress, 1);
  bs_scene_destroy(&sc);
  cr_assert_eq(parse("{}", &sc, &err), 0, "%s", err.msg);
  cr_assert_eq(sc->out_fields, BS_FIELDS_DEFAULT);
  cr_assert_eq(sc->out_compress, 0);
  cr_assert(!(BS_FIELDS_DEFAULT & BS_FIELD_BIT(BS_FIELD_FIRST_PIOLA)) && (BS_FIELDS_DEFAULT & BS_FIELD_BIT(BS_FIELD_CAUCHY)));
  bs_scene_destroy(&sc);
  for (int f = 0; f < BS_FIELD_COUNT; f++) {
    bs_field g;
    cr_assert_eq(bs_field_parse(bs_field_name((bs_field)f), &g, &err), 0);
    cr_assert_eq((int)g, f);
  }
}

Test(fields, bad_values_name_the_key) {
  bs_scene *sc = NULL;
  bs_error err;
  cr_assert_eq(parse("{\"fields\": [\"cauchy\", \"stress\"]}", &sc, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "fields.json") && strstr(err.msg, "output.fields.1") && strstr(err.msg, "\"stress\"") &&
                strstr(err.msg, "\"displacement\", \"velocity\"") && strstr(err.msg, "\"energy_density\""),
            "%s", err.msg);
  cr_assert_eq(parse("{\"fields\": [\"von_misses\"]}", &sc, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "output.fields.0") && strstr(err.msg, "did you mean \"von_mises\""), "%s", err.msg);
  cr_assert_eq(parse("{\"fields\": \"cauchy\"}", &sc, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "output.fields: must be an array of strings"), "%s", err.msg);
  cr_assert_eq(parse("{\"fields\": [3]}", &sc, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "output.fields: must be an array of strings"), "%s", err.msg);
  uint32_t set;
  const char *names[2] = {"cauchy", "stress"};
  cr_assert_eq(bs_fields_parse_names(2, names, &set, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "output.fields.1: unknown field \"stress\" (allowed: displacement, velocity") &&
                strstr(err.msg, "energy_density, elastic_force, contact_force, friction_impulse)"),
            "%s", err.msg);
  cr_assert_eq(parse("{\"compress\": 1}", &sc, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "output.compress"), "%s", err.msg);
  cr_assert_null(sc);
}

Test(fields, bodies_and_materials_are_told_apart) {
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_fields *fl = NULL;
  bs_error err;
  cr_assert_eq(parse("{}", &sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fields_create(s, BS_FIELDS_DEFAULT, &fl, &err), 0, "%s", err.msg);
  const int32_t nv0 = s->vertex_offset[1];
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) {
    cr_assert_eq(fl->point_body[v], v < nv0 ? 0 : 1, "vertex %d", v);
    cr_assert_eq(fl->scripted[v], !s->mask[v]);
  }
  int32_t per_body[2] = {0, 0};
  for (int32_t t = 0; t < s->mesh->n_tets; t++) {
    int b = fl->cell_body[t];
    per_body[b]++;
    cr_assert_eq(fl->material[t], b == 0 ? 1 : 0, "tet %d of body %d: material %d", t, b, fl->material[t]);
  }
  cr_assert_eq(per_body[0], 48);
  cr_assert_eq(per_body[1], 48);
  cr_assert_null(fl->P, "first_piola is not in the default set");
  bs_fields_destroy(&fl);
  cr_assert_null(fl);
  cr_assert_eq(bs_fields_create(s, 1u << BS_FIELD_COUNT, &fl, &err), BS_EINPUT);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* A run folder's frame holds displacement (always) and the chosen fields only. */
Test(fields, a_run_folder_writes_the_chosen_fields) {
  char dir[] = "/tmp/bs_test_fields_XXXXXX", text[256], path[512];
  cr_assert_not_null(mkdtemp(dir));
  snprintf(text, sizeof text, "{\"dir\": \"%s\", \"fields\": [\"von_mises\", \"body\", \"stretches\"]}", dir);
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  bs_error err;
  cr_assert_eq(parse(text, &sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_create(dir, s, &rf, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_run(s, bs_runfolder_frame, rf, NULL, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_runfolder_finish(rf, NULL, &err), 0, "%s", err.msg);
  bs_runfolder_destroy(&rf);
  snprintf(path, sizeof path, "%s/frame_00001.vtu", dir);
  bs_vtu *v = NULL;
  cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
  cr_assert_eq(v->n_point_data, 2, "displacement and body");
  cr_assert_not_null(bs_vtu_point_array(v, "displacement"));
  cr_assert_not_null(bs_vtu_point_array(v, "body"));
  cr_assert_eq(v->n_cell_data, 3, "body, von_mises and stretches");
  const bs_vtu_array *st = bs_vtu_cell_array(v, "stretches"), *vm = bs_vtu_cell_array(v, "von_mises");
  cr_assert(st && st->ncomp == 3 && vm && bs_vtu_cell_array(v, "body"));
  const bs_vtu_array *body = bs_vtu_cell_array(v, "body");
  for (int32_t t = 0; t < v->n_cells; t++) /* body 0 hangs from its clamp, body 1 falls freely */
    if (body->data[t] == 0) cr_assert(vm->data[t] > 0, "the clamped box sags: tet %d is stressed", t);
    else cr_assert_lt(vm->data[t], 1e-6, "the falling box is unstressed: tet %d", t);
  bs_vtu_destroy(&v);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_assert_eq(system(cmd), 0);
}
