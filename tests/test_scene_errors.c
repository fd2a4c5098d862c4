/* What the scene loader says about bad input: an unknown key names the
 * nearest allowed one when it is a likely typo (and only then) besides the
 * allowed list; a wrong type says what it got; a string outside its choices
 * lists them and guesses; malformed JSON gives the file, line and column. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_scene.h"
#include "scene_fixture.h"
#include "scene_schema.h"

/* The good scene with one override is refused with a message holding each
 * of the needles (NULL-terminated) and, if `absent`, not holding it. */
static void expect_msg(const char *set, const char *absent, const char *const *needles) {
  bs_scene *s = NULL;
  bs_error err;
  int st = bs_scene_parse(bs_test_good_scene, "good.json", 1, &set, &s, &err);
  bs_scene_destroy(&s);
  cr_expect_eq(st, BS_EINPUT, "--set %s: status %d (%s)", set, st, st ? err.msg : "loaded");
  if (!st) return;
  for (int i = 0; needles[i]; i++)
    cr_expect(strstr(err.msg, needles[i]) != NULL, "--set %s: should hold '%s': %s", set, needles[i], err.msg);
  if (absent) cr_expect(strstr(err.msg, absent) == NULL, "--set %s: should not hold '%s': %s", set, absent, err.msg);
}

#define EXPECT(set, ...) expect_msg(set, NULL, (const char *const[]){__VA_ARGS__, NULL})
#define EXPECT_NOT(set, absent, ...) expect_msg(set, absent, (const char *const[]){__VA_ARGS__, NULL})

Test(scene_errors, unknown_key_gets_the_nearest) {
  EXPECT("gravty=[0, -9.8, 0]", "good.json: gravty: unknown key; did you mean 'gravity'?", "allowed here: $schema");
  EXPECT("bodies.0.material.young=1e5", "bodies.0.material.young: unknown key; did you mean 'youngs'?");
  EXPECT("time.FPS=24", "time.FPS: unknown key; did you mean 'fps'?");             /* case */
  EXPECT("time.fsp=24", "time.fsp: unknown key; did you mean 'fps'?");             /* transposition */
  EXPECT("solver.tolerence=1e-3", "did you mean 'tolerance'?");                   /* substitution */
  EXPECT("bodies.0.scripted.0.grup=\"x\"", "did you mean 'group'?");             /* deletion */
  EXPECT("solver.max_iteration=5", "did you mean 'max_iterations'?");
  EXPECT("output.vtuevery=2", "did you mean 'vtu_every'?");
  EXPECT("bodies.0.materail={}", "did you mean 'material'?");
}

Test(scene_errors, far_key_gets_no_guess) {
  EXPECT_NOT("solver.colour=\"blue\"", "did you mean", "solver.colour: unknown key (allowed here: method, integrator, linear, ");
  EXPECT_NOT("time.x=1", "did you mean", "time.x: unknown key (allowed here: fps, frames, steps_per_frame, dt)");
  EXPECT_NOT("bodies.0.mass=1", "did you mean", "bodies.0.mass: unknown key");
}

Test(scene_errors, nearest_is_close_enough_only) {
  const char *const keys[] = {"fps", "frames", "steps_per_frame", "dt", NULL};
  cr_expect_str_eq(bs__schema_nearest("frame", keys, -1), "frames");
  cr_expect_str_eq(bs__schema_nearest("steps_per_fram", keys, -1), "steps_per_frame");
  cr_expect_str_eq(bs__schema_nearest("step_per_fram", keys, -1), "steps_per_frame"); /* 6+ letters: 2 edits */
  cr_expect_null(bs__schema_nearest("stp_per_fram", keys, -1));                      /* 3 edits */
  cr_expect_null(bs__schema_nearest("fram", keys, -1));                              /* 2 edits, 4 letters */
  cr_expect_null(bs__schema_nearest("t", keys, -1));                /* as long as the distance */
  cr_expect_str_eq(bs__schema_nearest("td", keys + 3, 1), "dt");    /* counted list; a transposition */
  cr_expect_null(bs__schema_nearest("speed", keys, -1));
}

Test(scene_errors, wrong_type_says_what_it_got) {
  EXPECT("time.fps=\"abc\"", "good.json: time.fps: must be a number, got string \"abc\"");
  EXPECT("time.fps=[24]", "time.fps: must be a number, got array of 1");
  EXPECT("time.fps=true", "time.fps: must be a number, got true");
  EXPECT("time.fps=null", "time.fps: must be a number, got null");
  EXPECT("time.fps={}", "time.fps: must be a number, got object");
  EXPECT("time.frames=2.5", "time.frames: must be an integer in [0, 10000000], got 2.5");
  EXPECT("bodies.0.mesh=5", "bodies.0.mesh: must be a string, got 5");
  EXPECT("output.stats=\"yes\"", "output.stats: must be true or false, got string \"yes\"");
  EXPECT("gravity={\"y\": -9.8}", "gravity: must be an array of 3 numbers, got object");
  EXPECT("gravity=[0, \"a\", 0]", "gravity: element 1 must be a finite number, got string \"a\"");
  EXPECT("gravity=[0,NaN,0]", "gravity: must be an array of 3 numbers, got string \"[0,NaN,0]\"");
  EXPECT("time=24", "time: must be an object, got 24");
  EXPECT("bodies={}", "bodies: must be an array, got object");
  EXPECT("bodies=[]", "bodies: must be a non-empty array, got array of 0");
  EXPECT("bodies.0.scripted=true", "bodies.0.scripted: must be an array, got true");
  EXPECT("bodies.0.materials=[]", "bodies.0.materials: must be an object {name: object}, got array of 0");
  EXPECT("solver.cg_sigma=[1]", "solver.cg_sigma: must be a number > 0 or \"auto\", got array of 1");
  EXPECT("bodies.0.scale=\"big\"", "bodies.0.scale: must be a number or an array of 3 numbers, got string \"big\"");
  EXPECT("description=1", "description: must be a string, got 1");
  /* a long string is cut after 40 characters */
  EXPECT("time.fps=\"0123456789012345678901234567890123456789abcdef\"",
         "got string \"0123456789012345678901234567890123456789...\"");
  bs_scene *s = NULL;
  bs_error err;
  const char *sets[1] = {"bodies.0.mesh=5"};
  cr_expect_eq(bs_scene_parse(bs_test_good_scene, NULL, 1, sets, &s, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "<scene>: bodies.0.mesh: must be a string") == err.msg, "%s", err.msg);
}

Test(scene_errors, bad_choice_lists_and_guesses) {
  EXPECT("solver.linear=\"amgg\"", "solver.linear: must be \"cg\", \"pcg\", \"amg\" or \"cholmod\", got \"amgg\"; "
                                  "did you mean \"amg\"?");
  EXPECT("solver.linear=\"minres\"", "solver.linear: must be \"cg\", \"pcg\", \"amg\" or \"cholmod\", got \"minres\"");
  EXPECT("solver.mode=\"Static\"", "did you mean \"static\"?");
  EXPECT("bodies.0.material.model=\"neohookean\"", "did you mean \"neo_hookean\"?");
  EXPECT_NOT("solver.method=\"magic\"", "did you mean",
             "solver.method: must be \"optimization\", \"newton\" or \"newton_k\", got \"magic\"");
  EXPECT("bodies.0.initial_state={\"type\": \"randm\"}", "bodies.0.initial_state.type: ", "did you mean \"random\"?");
}

Test(scene_errors, duplicate_key) {
  bs_scene *s = NULL;
  bs_error err;
  int st = bs_scene_parse("{\"time\": {\"fps\": 24, \"fps\": 30}, \"bodies\": []}", "dup.json", 0, NULL, &s, &err);
  cr_expect_eq(st, BS_EINPUT);
  cr_expect_str_eq(err.msg, "dup.json: time.fps: given twice");
}

/* The message for malformed text. */
static const char *malformed(const char *text) {
  static bs_error err;
  bs_scene *s = NULL;
  int st = bs_scene_parse(text, "bad.json", 0, NULL, &s, &err);
  cr_expect_eq(st, BS_EINPUT, "%s: status %d", text, st);
  bs_scene_destroy(&s);
  return err.msg;
}

Test(scene_errors, malformed_json_gives_line_and_column) {
  cr_expect_str_eq(malformed("{\"time\": {\"fps\": 24,,}"),
                   "bad.json: line 1, column 21: malformed JSON: expected a key in double quotes, found ',}'");
  cr_expect_str_eq(malformed("{\n  \"time\": {\"fps\": 24}\n  \"bodies\": []\n}"),
                   "bad.json: line 3, column 3: malformed JSON: expected ',' or '}', found '\"bodies\": []'");
  cr_expect_str_eq(malformed("{\"description\": \"caf\xc3\xa9\", \"time\": 2x}"), /* columns count characters */
                   "bad.json: line 1, column 34: malformed JSON: expected ',' or '}', found 'x}'");
  cr_expect_str_eq(malformed("{\"time\": {\"fps\": 24}"),
                   "bad.json: line 1, column 21: malformed JSON: expected ',' or '}' at the end of the text");
  cr_expect(strstr(malformed(""), "bad.json: line 1, column 1: malformed JSON: expected a value") != NULL);
  cr_expect_str_eq(malformed("{\"time\": 1} x"),
                   "bad.json: line 1, column 13: malformed JSON: expected the end of the text (one value only), found 'x'");
  cr_expect_str_eq(malformed("{\"a\": \"unterminated\n}"),
                   "bad.json: line 1, column 7: malformed JSON: expected a closing quote for this string, found "
                   "'\"unterminated'");
  cr_expect_str_eq(malformed("[1, 2,]"), "bad.json: line 1, column 7: malformed JSON: expected a value (an object, "
                                         "array, string, number, true, false or null), found ']'");
  cr_expect_str_eq(malformed("{\"a\" 1}"), "bad.json: line 1, column 6: malformed JSON: expected ':' after the key, "
                                          "found '1}'");
  cr_expect_str_eq(malformed("{\"a\": -}"), "bad.json: line 1, column 8: malformed JSON: expected a digit, found '}'");
  cr_expect_str_eq(malformed("{\"a\": \"\\q\"}"), "bad.json: line 1, column 9: malformed JSON: expected an escape "
                                               "(\\\" \\\\ \\/ \\b \\f \\n \\r \\t \\uXXXX), found 'q\"}'");
  cr_expect_str_eq(malformed("{'a': 1}"), "bad.json: line 1, column 2: malformed JSON: expected a key in double quotes, "
                                          "found ''a': 1}'");
}

/* A file's message names the file. */
Test(scene_errors, malformed_file_is_named) {
  char path[] = "/tmp/bs_scene_errors_XXXXXX";
  bs_test_write_scene(path, "{\n\n   ]");
  bs_scene *s = NULL;
  bs_error err;
  cr_expect_eq(bs_scene_load(path, 0, NULL, &s, &err), BS_EINPUT);
  char want[128];
  snprintf(want, sizeof want, "%s: line 3, column 4: malformed JSON: expected a key in double quotes, found ']'", path);
  cr_expect_str_eq(err.msg, want);
  unlink(path);
}

/* Values that would make the run impossible (a step count beyond the integer
 * range, a run of more steps than the limit, a rotation whose angle is not a
 * number any more) are refused with the key and the limit. */
Test(scene_errors, impossible_time_and_rotation_are_refused) {
  EXPECT("time.fps=1e-300", "good.json: time.fps: must be in [1e-09, 1e+09], got 1e-300");
  EXPECT("time.steps_per_frame=1000001", "time.steps_per_frame: must be an integer in [1, 1000000]");
  EXPECT("bodies.0.rotate=[1e300, 0, 0]", "bodies.0.rotate: a rotation of 1e+300 degrees, above the limit of 1e+09");
  EXPECT("bodies.0.rotate=[1e154, 1e154, 0]", "bodies.0.rotate: a rotation of 1.41421e+154 degrees");
  const char *dt_scenes[] = {"1e-20", "3e-10"};
  for (int i = 0; i < 2; i++) {
    char json[1024];
    snprintf(json, sizeof json,
             "{\"time\": {\"fps\": 24, \"frames\": 2, \"dt\": %s},\n"
             " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
             "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}]}\n",
             dt_scenes[i]);
    bs_scene *s = NULL;
    bs_error err;
    cr_expect_eq(bs_scene_parse(json, "dt.json", 0, NULL, &s, &err), BS_EINPUT, "dt %s loaded", dt_scenes[i]);
    cr_expect(strstr(err.msg, "dt.json: time.dt: ") && strstr(err.msg, "steps per frame at 24 fps, above the limit"),
              "%s", err.msg);
    bs_scene_destroy(&s);
  }
}

Test(scene_errors, limits_apply_to_scenes_built_in_c) {
  bs_scene *sc = bs_test_box_scene(2, 24, 1);
  bs_error err;
  sc->frames = 2000000;
  sc->steps_per_frame = 1000;
  cr_expect_eq(bs_scene_validate(sc, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "2000000 frames x 1000 steps per frame = 2000000000 time steps"), "%s", err.msg);
  sc->frames = 2;
  sc->steps_per_frame = 1;
  sc->bodies[0].rotate[2] = INFINITY;
  cr_expect_eq(bs_scene_validate(sc, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "bodies.0.rotate: a rotation of inf degrees"), "%s", err.msg);
  bs_scene_destroy(&sc);
}
