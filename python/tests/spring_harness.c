/* spring_harness.c — examples/02_spring's term, in C, on a scene file, for
 * test_terms.py: the example's own source is included (its main renamed),
 * so the callbacks are the example's. Usage:
 *     spring_harness SCENE.json OUT.bin
 * loads the scene, adds the example's spring term (group xmax, k 1e4,
 * d (0.2, -0.1, 0.05)) and writes x after the static solve (mode static) or
 * after every frame (dynamic), 3n doubles per record. */
#define main spring_example_main
#include "../../examples/02_spring/main.c"
#undef main

int main(int argc, char **argv) {
  bs_error err;
  if (argc != 3) return 2;
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  CHECK(bs_scene_load(argv[1], 0, NULL, &sc, &err));
  CHECK(bs_sim_create(sc, &s, &err));
  const bs_group *face = bs_mesh_group(s->mesh, "xmax");
  spring *sp = malloc(sizeof *sp);
  *sp = (spring){.n = face->n_vertices, .v = face->vertices, .rest = s->x0, .k = 1e4, .d = {0.2, -0.1, 0.05}};
  bs_term *t = NULL;
  CHECK(bs_term_create("spring", &spring_ops, s->fem, &s->step, sp, &t, &err));
  CHECK(bs_sim_add_term(s, t, &err));
  FILE *f = fopen(argv[2], "wb");
  if (!f) return 1;
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  bs_frame_stats fs;
  if (sc->mode == BS_MODE_STATIC) {
    CHECK(bs_sim_statics(s, &fs, &err));
    fwrite(s->x, sizeof(double), n3, f);
  } else {
    for (int k = 0; k < sc->frames; k++) {
      CHECK(bs_sim_advance_frame(s, &fs, &err));
      fwrite(s->x, sizeof(double), n3, f);
    }
  }
  fclose(f);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return 0;
}
