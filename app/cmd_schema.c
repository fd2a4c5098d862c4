/* bigstep schema [--markdown] [-o FILE] — the scene schema as a JSON Schema
 * (draft-07), generated from the table the scene loader checks with
 * (bs_scene_schema_json), or with --markdown as the scene-key reference
 * (bs_scene_schema_markdown). data/scene.schema.json and docs/scene-keys.md
 * are these outputs; editors read the first through a scene's "$schema" key
 * or their own settings (docs/scenes.md). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "bs_scene.h"

static const char *schema_help =
    "usage: bigstep schema [--markdown] [-o FILE]\n"
    "\n"
    "Prints the scene schema as a JSON Schema (draft-07) on stdout, or writes\n"
    "it to FILE. Editors complete and check scenes with it: put\n"
    "  \"$schema\": \"PATH/TO/scene.schema.json\"\n"
    "at the top of a scene (data/scene.schema.json is this output).\n"
    "  --markdown  print the scene-key reference as Markdown instead (one row per\n"
    "              key: path, type, default, range or choices, description;\n"
    "              docs/scene-keys.md is this output)\n"
    "  -o FILE     write to FILE instead of stdout\n";

int bs_cmd_schema(int argc, char **argv) {
  const char *out = NULL;
  int markdown = 0;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      fputs(schema_help, stdout);
      return 0;
    }
    if (!strcmp(argv[i], "--markdown")) markdown = 1;
    else if ((!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) && i + 1 < argc) out = argv[++i];
    else return bs_app_usage_error("schema", "unexpected argument '%s'", argv[i]);
  }
  char *text;
  bs_error err;
  if ((markdown ? bs_scene_schema_markdown : bs_scene_schema_json)(&text, &err)) {
    fprintf(stderr, "bigstep schema: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  FILE *f = out ? fopen(out, "wb") : stdout;
  if (!f) {
    free(text);
    fprintf(stderr, "bigstep schema: cannot write '%s'\n", out);
    return BS_EXIT_FAIL;
  }
  size_t n = strlen(text);
  int bad = fwrite(text, 1, n, f) != n;
  free(text);
  bad |= out ? fclose(f) != 0 : fflush(f) != 0;
  if (bad) {
    fprintf(stderr, "bigstep schema: cannot write '%s'\n", out ? out : "stdout");
    return BS_EXIT_FAIL;
  }
  return 0;
}
