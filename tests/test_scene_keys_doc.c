/* test_scene_keys_doc.c — docs/scene-keys.md is the scene-key reference the
 * schema table generates (bs_scene_schema_markdown), byte for byte; every
 * key of the table has its row; every design note it links to exists; and
 * `bigstep schema --markdown` prints the same text. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_scene.h"
#include "cli_util.h"
#include "scene_schema.h"

#define REGENERATE "regenerate it with `build/app/bigstep schema --markdown -o docs/scene-keys.md`"

static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  cr_assert_not_null(f, "cannot open %s: " REGENERATE, path);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *t = malloc((size_t)n + 1);
  cr_assert_not_null(t);
  cr_assert_eq(fread(t, 1, (size_t)n, f), (size_t)n);
  t[n] = '\0';
  fclose(f);
  return t;
}

/* The first line where a and b differ (1-based), for the message. */
static int first_differing_line(const char *a, const char *b) {
  int line = 1;
  for (; *a && *a == *b; a++, b++)
    if (*a == '\n') line++;
  return line;
}

Test(scene_keys_doc, committed_reference_is_generated_from_the_table) {
  char *text = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_schema_markdown(&text, &err), 0, "%s", err.msg);
  char *file = read_text(BS_SOURCE_DIR "/docs/scene-keys.md");
  cr_expect(strcmp(text, file) == 0,
            "docs/scene-keys.md is not the schema table's reference (first difference at line %d): " REGENERATE,
            first_differing_line(text, file));
  free(file);
  free(text);
}

Test(scene_keys_doc, every_key_has_its_row) {
  char *text = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_schema_markdown(&text, &err), 0, "%s", err.msg);
  for (int i = 0; i < bs__schema_n_keys; i++) {
    const bs_schema_key *k = &bs__schema_keys[i];
    char row[200];
    if (k->section[0]) snprintf(row, sizeof row, "\n| `%s.%s` | ", k->section, k->key);
    else snprintf(row, sizeof row, "\n| `%s` | ", k->key);
    cr_expect(strstr(text, row) != NULL, "no row for %s", row + 1);
  }
  free(text);
}

Test(scene_keys_doc, design_notes_exist_and_name_keys) {
  const char *const *paths, *const *notes;
  int n = bs__schema_design_notes(&paths, &notes);
  cr_assert_gt(n, 0);
  for (int i = 0; i < n; i++) {
    char file[512];
    snprintf(file, sizeof file, "%s/docs/%s", BS_SOURCE_DIR, notes[i]);
    cr_expect(access(file, R_OK) == 0, "%s links to %s, which does not exist", paths[i], file);
    /* the path is a key of the table, or a section of it */
    int found = 0;
    for (int j = 0; j < bs__schema_n_keys && !found; j++) {
      const bs_schema_key *k = &bs__schema_keys[j];
      char p[200];
      if (k->section[0]) snprintf(p, sizeof p, "%s.%s", k->section, k->key);
      else snprintf(p, sizeof p, "%s", k->key);
      found = !strcmp(p, paths[i]);
    }
    cr_expect(found, "the design-note table names %s, which is not a key", paths[i]);
  }
}

Test(scene_keys_doc, command_prints_the_committed_file) {
  char *out, *file = read_text(BS_SOURCE_DIR "/docs/scene-keys.md");
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " schema --markdown", &out), 0, "%s", out);
  cr_expect(strcmp(out, file) == 0, "`bigstep schema --markdown` differs from docs/scene-keys.md: " REGENERATE);
  free(out);
  free(file);
}
