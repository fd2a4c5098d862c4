/* scene_fixture.h — the small scene the scene and command-line tests share
 * (a 2^3-cell box clamped at ymin, two frames), and writing a scene text to
 * a fresh temporary file. */
#ifndef BS_TEST_SCENE_FIXTURE_H
#define BS_TEST_SCENE_FIXTURE_H

#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>

#include "bs_scene.h"

static const char *const bs_test_good_scene =
    "{\"time\": {\"fps\": 24, \"frames\": 2, \"steps_per_frame\": 1},\n"
    " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-3},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"ymin\", \"fixed\": true}]}]}\n";

/* Writes text to a fresh file from the template path ("...XXXXXX", changed in
 * place); the caller unlinks it. */
static inline void bs_test_write_scene(char *path, const char *text) {
  int fd = mkstemp(path);
  cr_assert(fd >= 0, "cannot create %s", path);
  FILE *f = fdopen(fd, "w");
  cr_assert_not_null(f);
  fputs(text, f);
  fclose(f);
}

/* A scene built in C: one 2^3-cell unit box (fixed corotated, E 1e5 Pa,
 * nu 0.3, rho 1000 kg/m^3) falling freely for `frames` frames at `fps`,
 * `steps` steps each; validated. The caller edits it (and validates again). */
static inline bs_scene *bs_test_box_scene(int frames, double fps, int steps) {
  bs_scene *sc = NULL;
  bs_scene_body *b = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_create(&sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_scene_add_body(sc, "box", &b, &err), 0, "%s", err.msg);
  b->box_cells[0] = b->box_cells[1] = b->box_cells[2] = 2;
  b->materials[0].youngs = 1e5;
  b->materials[0].poisson = 0.3;
  b->materials[0].density = 1000;
  sc->frames = frames;
  sc->fps = fps;
  sc->steps_per_frame = steps;
  cr_assert_eq(bs_scene_validate(sc, &err), 0, "%s", err.msg);
  return sc;
}

#endif
