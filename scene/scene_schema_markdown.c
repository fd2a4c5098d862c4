/* scene_schema_markdown.c — the scene-key reference (docs/scene-keys.md)
 * generated from the schema table (scene_schema.h): one table per section,
 * one row per key with its path, type, default, range or choices, the row's
 * one-line description and, where one exists, a link to the design note that
 * explains the choice (the table design_notes below). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_scene.h"
#include "scene_schema.h"

/* Key paths (section.key) with a design note, relative to docs/. */
static const struct {
  const char *path;
  const char *note;
} design_notes[] = {
    {"solver.tolerance", "design/convergence.md"},
    {"solver.rtol", "design/convergence.md"},
    {"solver.load_rtol", "design/convergence.md"},
    {"solver.newton_max_iterations", "design/convergence.md"},
    {"solver.linear", "design/linear-solvers.md"},
    {"solver.cg_downhill", "design/linear-solvers.md"},
    {"solver.cg_precision", "design/linear-solvers.md"},
    {"solver.amg_matrix", "design/linear-solvers.md"},
    {"solver.amg_rebuild_factor", "design/linear-solvers.md"},
    {"solver.amg_rebuild_every", "design/linear-solvers.md"},
    {"solver.cg_sigma", "design/cg-forcing.md"},
    {"solver.cg_sigma_scale", "design/cg-forcing.md"},
    {"solver.cg_forcing", "design/cg-forcing.md"},
    {"solver.project_hessian", "design/project-hessian.md"},
    {"solver.globalization", "design/globalization.md"},
    {"solver.tr_radius", "design/globalization.md"},
    {"solver.contact_hessian", "design/contact-models.md"},
    {"solver.penalty_hessian", "design/contact-models.md"},
    {"obstacles[].collision", "design/contact-models.md"},
    {"self_collision", "design/self-collision.md"},
    {"bodies[].mesh_size", "design/meshing.md"},
    {"bodies[].min_dihedral", "design/meshing.md"},
    {"bodies[].mesher", "design/meshing.md"},
    {"bodies[].close_holes", "design/meshing.md"},
    {"output.fields", "design/output.md"},
    {"output.compress", "design/output.md"},
};

static void key_path(const bs_schema_key *k, char *out, size_t n) {
  if (k->section[0]) snprintf(out, n, "%s.%s", k->section, k->key);
  else snprintf(out, n, "%s", k->key);
}

const char *bs__schema_design_note(const char *path) {
  for (size_t i = 0; i < sizeof design_notes / sizeof design_notes[0]; i++)
    if (!strcmp(design_notes[i].path, path)) return design_notes[i].note;
  return NULL;
}

int bs__schema_design_notes(const char *const **paths, const char *const **notes) {
  static const char *p[sizeof design_notes / sizeof design_notes[0]];
  static const char *q[sizeof design_notes / sizeof design_notes[0]];
  int n = (int)(sizeof design_notes / sizeof design_notes[0]);
  for (int i = 0; i < n; i++) p[i] = design_notes[i].path, q[i] = design_notes[i].note;
  if (paths) *paths = p;
  if (notes) *notes = q;
  return n;
}

/* Text for a table cell: '|' escaped, so that it does not end the cell. */
static void cell(FILE *f, const char *s) {
  for (; *s; s++) {
    if (*s == '|') fputc('\\', f);
    fputc(*s, f);
  }
}

static const char *type_name(bs_schema_type t) {
  switch (t) {
  case BS_SCHEMA_NUMBER: return "number";
  case BS_SCHEMA_INTEGER: return "integer";
  case BS_SCHEMA_STRING: return "string";
  case BS_SCHEMA_BOOLEAN: return "boolean";
  case BS_SCHEMA_VEC3: return "[x, y, z]";
  case BS_SCHEMA_IVEC3: return "[i, j, k] (integers)";
  case BS_SCHEMA_NUM_OR_VEC3: return "number or [x, y, z]";
  case BS_SCHEMA_NUM_OR_CHOICE: return "number or string";
  case BS_SCHEMA_OBJECT: return "object";
  case BS_SCHEMA_ARRAY: return "array of objects";
  case BS_SCHEMA_MAP: return "{name: object}";
  case BS_SCHEMA_STRINGS: return "array of strings";
  }
  return "?";
}

/* The bound texts of a range "[lo, hi)" as written in the table, trimmed. */
static void bound(const char *p, size_t n, char *out, size_t cap) {
  while (n && *p == ' ') p++, n--;
  while (n && p[n - 1] == ' ') n--;
  snprintf(out, cap, "%.*s", (int)n, p);
}

/* The range as prose: "[0, 6]", "> 0", ">= 1"; prefixed for arrays (the
 * number of elements) and triples (each element). */
static void range_text(FILE *f, const bs_schema_key *k) {
  const char *r = k->range;
  size_t len = strlen(r);
  const char *comma = strchr(r, ',');
  if (len < 3 || !comma) {
    cell(f, r);
    return;
  }
  char lo[64], hi[64];
  bound(r + 1, (size_t)(comma - r - 1), lo, sizeof lo);
  bound(comma + 1, (size_t)(r + len - 1 - comma - 1), hi, sizeof hi);
  int lo_open = r[0] == '(', hi_open = r[len - 1] == ')';
  if (k->type == BS_SCHEMA_ARRAY || k->type == BS_SCHEMA_STRINGS) fputs("elements: ", f);
  else if (k->type == BS_SCHEMA_VEC3 || k->type == BS_SCHEMA_IVEC3 || k->type == BS_SCHEMA_NUM_OR_VEC3)
    fputs("each ", f);
  if (lo[0] && hi[0]) fprintf(f, "%c%s, %s%c", lo_open ? '(' : '[', lo, hi, hi_open ? ')' : ']');
  else if (lo[0]) fprintf(f, "%s %s", lo_open ? ">" : ">=", lo);
  else if (hi[0]) fprintf(f, "%s %s", hi_open ? "<" : "<=", hi);
}

static void key_row(FILE *f, const bs_schema_key *k) {
  char path[160];
  key_path(k, path, sizeof path);
  fprintf(f, "| `%s` | ", path);
  cell(f, type_name(k->type));
  if (k->sub && (k->type == BS_SCHEMA_OBJECT || k->type == BS_SCHEMA_ARRAY || k->type == BS_SCHEMA_MAP))
    fprintf(f, " (`%s`)", k->sub);
  fputs(" | ", f);
  if (k->required) fputs("required", f);
  else if (k->def) {
    fputc('`', f);
    cell(f, k->def);
    fputc('`', f);
  } else fputs("–", f);
  fputs(" | ", f);
  int any = 0;
  if (k->choices) {
    for (int i = 0; k->choices[i]; i++) fprintf(f, "%s`%s`", i ? ", " : "", k->choices[i]);
    any = 1;
  }
  if (k->range) {
    if (any) fputs("; ", f);
    range_text(f, k);
    any = 1;
  }
  if (!any) fputs("–", f);
  fputs(" | ", f);
  cell(f, k->doc ? k->doc : "");
  const char *note = bs__schema_design_note(path);
  if (note) fprintf(f, " ([design](%s))", note);
  fputs(" |\n", f);
}

int bs_scene_schema_markdown(char **out, bs_error *err) {
  *out = NULL;
  char *buf = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&buf, &size);
  if (!f) return bs_error_set(err, BS_ENOMEM, "out of memory writing the scene-key reference");
  fputs("# Scene keys\n"
        "\n"
        "<!-- Generated by `bigstep schema --markdown` from the schema table (scene/scene_schema.c).\n"
        "     Do not edit: regenerate with `build/app/bigstep schema --markdown -o docs/scene-keys.md`. -->\n"
        "\n"
        "Every key a scene may hold, by section, in the order `bs_scene_write_json` writes them:\n"
        "its type, its default (as JSON; *required* when the section needs it), the values it\n"
        "may take and what it means, with a link to the design note where the choice of a\n"
        "default is argued. How to write a scene: [scenes.md](scenes.md). The same table is\n"
        "published for editors as a JSON Schema, `data/scene.schema.json` (`bigstep schema`).\n"
        "SI units throughout.\n",
        f);
  for (int s = 0; s < bs__schema_n_sections; s++) {
    const bs_schema_section *sec = &bs__schema_sections[s];
    fprintf(f, "\n## %s\n\n", sec->name[0] ? sec->name : "top level");
    if (sec->one_of) {
      fputs("Exactly one of ", f);
      for (const char *p = sec->one_of; *p;) {
        size_t n = strcspn(p, "|");
        fprintf(f, "%s`%.*s`", p == sec->one_of ? "" : ", ", (int)n, p);
        p += n + (p[n] == '|');
      }
      fputs(".\n\n", f);
    }
    fputs("| key | type | default | range / choices | description |\n| --- | --- | --- | --- | --- |\n", f);
    for (int i = 0; i < bs__schema_n_keys; i++)
      if (!strcmp(bs__schema_keys[i].section, sec->name)) key_row(f, &bs__schema_keys[i]);
  }
  if (fclose(f) || !buf) {
    free(buf);
    return bs_error_set(err, BS_ENOMEM, "out of memory writing the scene-key reference");
  }
  *out = buf;
  return 0;
}
