/* The study's paths: a study folder, reference or scene path too long for
 * BS_MAX_PATH, a run folder OUT/NAME too long, and a file path in a folder
 * (bs_study_file_path) are refused as input errors naming them, never cut. */
#include <criterion/criterion.h>
#include <string.h>

#include "bs_study.h"

static const char *scene = "data/scenes/cube_pulse.json";

static bs_study_knob knob(const char *spec) {
  bs_study_knob k;
  bs_error err;
  cr_assert_eq(bs_study_knob_parse(spec, &k, &err), 0, "%s", err.msg);
  return k;
}

/* A path of n bytes: "/tmp/" then 'a's. */
static char *long_path(size_t n) {
  char *p = malloc(n + 1);
  memset(p, 'a', n);
  memcpy(p, "/tmp/", 5);
  p[n] = 0;
  return p;
}

Test(study_paths, file_path_fits_or_is_named) {
  char p[BS_STUDY_FILE_PATH];
  bs_error err;
  cr_assert_eq(bs_study_file_path("out/study/x", "study.csv", p, &err), 0);
  cr_assert_str_eq(p, "out/study/x/study.csv");
  char *dir = long_path(BS_MAX_PATH - 1); /* the longest folder */
  char name[BS_STUDY_FILE_NAME_MAX];
  memset(name, 'n', sizeof name - 1);
  name[sizeof name - 1] = 0; /* the longest name */
  cr_assert_eq(bs_study_file_path(dir, name, p, &err), 0);
  cr_assert_eq(strlen(p), BS_MAX_PATH - 1 + 1 + BS_STUDY_FILE_NAME_MAX - 1);
  free(dir);
  dir = long_path(BS_MAX_PATH);
  cr_assert_eq(bs_study_file_path(dir, "done", p, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "/tmp/aaaa"), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "too long (a folder of 1024 bytes, at most 1023"), "%s", err.msg);
  free(dir);
}

Test(study_paths, long_folders_are_input_errors) {
  bs_study_knob k = knob("steps_per_frame=1,2");
  bs_study *S = NULL;
  bs_error err;
  char *out = long_path(BS_MAX_PATH);
  bs_study_opts o = {.scene = scene, .n_knobs = 1, .knobs = &k, .out = out};
  cr_assert_eq(bs_study_create(&o, &S, &err), BS_EINPUT);
  cr_assert_null(S);
  cr_assert_not_null(strstr(err.msg, "study folder '/tmp/aaa"), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "longer than 1023 bytes"), "%s", err.msg);
  o.out = NULL;
  o.reference = out;
  cr_assert_eq(bs_study_create(&o, &S, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "reference folder"), "%s", err.msg);
  free(out);

  /* a study folder that fits, but not with a run's name after it */
  out = long_path(BS_MAX_PATH - 10);
  o.reference = NULL;
  o.out = out;
  cr_assert_eq(bs_study_create(&o, &S, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_study_plan(S, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "steps_per_frame=1"), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "longer than 1023 bytes"), "%s", err.msg);
  bs_study_destroy(&S);
  free(out);

  /* the same study in a short folder plans */
  o.out = "/tmp/bs_test_study_paths";
  cr_assert_eq(bs_study_create(&o, &S, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_study_plan(S, &err), 0, "%s", err.msg);
  cr_assert_eq(S->n_runs, 2);
  cr_assert_str_eq(S->runs[1].dir, "/tmp/bs_test_study_paths/steps_per_frame=2");
  bs_study_destroy(&S);
  bs_study_knob_free(&k);
}
