/* scene_schema.h — the scene schema as one table (not installed): every key
 * the JSON loader accepts, by section, with its type, allowed values, simple
 * range, default (as JSON text) and a one-line description.
 *
 * Who reads it:
 *  - the loader (scene.c): the keys allowed in each object (check_keys), the
 *    integer ranges (get_int), the allowed strings (get_choice), the "did you
 *    mean" suggestions;
 *  - bs_scene_schema_json (scene_schema_json.c): the published JSON Schema,
 *    data/scene.schema.json;
 *  - bs_scene_schema_markdown (scene_schema_markdown.c): the scene-key
 *    reference, docs/scene-keys.md (test_scene_keys_doc.c keeps it in step);
 *  - the tests (test_scene_schema.c): defaults against a resolved scene,
 *    ranges, types and required keys against the loader, every shipped scene.
 *
 * Sections are named by their path from the top level: "" (the top level),
 * "time", "bodies[]" (an element of the array "bodies"), "bodies[].box",
 * "bodies[].material" (also the values of the map "bodies[].materials"), ...
 * A key of type OBJECT, ARRAY or MAP names the section of its value, of its
 * elements or of its map values in `sub`.
 *
 * Adding a key is one row in scene_schema.c and the struct field it fills,
 * e.g. the field `int out_compress` of bs_scene and the row
 *     {"output", "compress", BS_SCHEMA_BOOLEAN, .def = "false", SC(out_compress),
 *      .doc = "zlib-compress the VTU arrays"},
 * which binds the key to the field: the loader reads it (type, range and
 * choice checked), the scene starts from its default, and the writer writes
 * it, all through the table; then `bigstep schema -o data/scene.schema.json`
 * (and `bigstep schema --markdown` for the key reference, where it exists).
 * A key whose value has rules beyond its own (an object, an array, a map, a
 * choice between keys) is left unbound (size 0) and read and written by hand
 * in scene.c and scene_write.c. A new section also needs a row in
 * bs__schema_sections and an instance in tests/scene_full.h.
 *
 * Ranges are intervals: "[0, 6]", "(0, )" (> 0), "[0, )" (>= 0); an empty
 * bound is unbounded. For VEC3, IVEC3 and NUM_OR_VEC3 they bound each
 * element; for ARRAY and STRINGS the number of elements.
 *
 * Nothing here allocates, prints or fails except where a status is returned. */
#ifndef BS_SCENE_SCHEMA_H
#define BS_SCENE_SCHEMA_H

#include <stddef.h>

typedef enum {
  BS_SCHEMA_NUMBER = 0,   /* a finite number                                    */
  BS_SCHEMA_INTEGER,      /* a whole number in `range`                          */
  BS_SCHEMA_STRING,       /* a string; one of `choices` when they are given     */
  BS_SCHEMA_BOOLEAN,      /* true or false                                      */
  BS_SCHEMA_VEC3,         /* an array of 3 finite numbers                       */
  BS_SCHEMA_IVEC3,        /* an array of 3 whole numbers                        */
  BS_SCHEMA_NUM_OR_VEC3,  /* a number (the same for x, y, z) or an array of 3   */
  BS_SCHEMA_NUM_OR_CHOICE, /* a number, or one of the strings `choices`        */
  BS_SCHEMA_OBJECT,       /* an object following the section `sub`              */
  BS_SCHEMA_ARRAY,        /* an array of objects following the section `sub`    */
  BS_SCHEMA_MAP,          /* {name: an object following the section `sub`}     */
  BS_SCHEMA_STRINGS       /* an array of strings, each one of `choices` if given */
} bs_schema_type;

typedef struct bs_schema_key {
  const char *section;         /* "", "time", "bodies[]", ...                     */
  const char *key;
  bs_schema_type type;
  int required;                /* 1: the loader refuses the section without it    */
  const char *sub;             /* OBJECT, ARRAY, MAP: the section of the value    */
  const char *const *choices;  /* NULL-terminated; NULL: any string               */
  const char *range;           /* NULL: none                                      */
  const char *def;             /* the default as JSON text; NULL: none            */
  const char *doc;             /* one line                                        */
  /* The struct field the key is bound to (size 0: unbound, read and written
   * by hand): its byte offset in the section's struct (bs_scene for "",
   * "time", "solver", "self_collision" and "output"; bs_scene_body for
   * "bodies[]", "bodies[].box" and "bodies[].initial_state";
   * bs_scene_material; bs_scene_obstacle; bs_scene_qoi) and its size. The
   * field's C type follows the key's type: NUMBER double, INTEGER and BOOLEAN
   * int, STRING with choices an int enum (the choice's value below), STRING
   * char[size], VEC3 and NUM_OR_VEC3 double[3], IVEC3 int[3]. */
  size_t offset, size;
  const int *values;           /* a choice's stored value, per choice; NULL: its index */
  int path;                    /* STRING: 1 for a file path (resolved against the scene's
                                  folder when loaded, written absolute when it exists) */
} bs_schema_key;

typedef struct bs_schema_section {
  const char *name;
  const char *one_of; /* "a|b|c": exactly one of these keys (NULL: no such rule) */
} bs_schema_section;

/* The table, in the order the keys are documented and written. */
extern const bs_schema_key bs__schema_keys[];
extern const int bs__schema_n_keys;
extern const bs_schema_section bs__schema_sections[];
extern const int bs__schema_n_sections;

/* The row of section.key, or NULL. */
const bs_schema_key *bs__schema_find(const char *section, const char *key);

/* The index of value in k->choices, or -1 (also when k has none). */
int bs__schema_choice(const bs_schema_key *k, const char *value);

/* A parsed range. */
typedef struct bs_schema_range {
  int has_lo, has_hi, lo_open, hi_open;
  double lo, hi;
} bs_schema_range;

/* Parses k->range (all zero when k has none); 1 when k has a range. */
int bs__schema_range(const bs_schema_key *k, bs_schema_range *r);

/* 1 when v lies in r. */
int bs__schema_in_range(const bs_schema_range *r, double v);

/* r as text, e.g. "[0, 6]", "> 0", ">= 1" (for messages). */
void bs__schema_range_text(const bs_schema_range *r, char *out, size_t n);

/* The candidate nearest to word (case-insensitive optimal string alignment
 * distance: insertions, deletions, substitutions, adjacent transpositions)
 * when it is close enough to be a likely typo (distance <= 1, or <= 2 for
 * words of 6 characters or more, and less than the word's length); else NULL.
 * cands is NULL-terminated, or counted by n when n >= 0. */
const char *bs__schema_nearest(const char *word, const char *const *cands, int n);

/* 1 when k is bound to a struct field (k->size > 0). */
int bs__schema_bound(const bs_schema_key *k);

/* The value stored for choice i of k (k->values[i], or i). */
int bs__schema_choice_value(const bs_schema_key *k, int i);

/* The choice of k whose stored value is v, or NULL. */
const char *bs__schema_choice_name(const bs_schema_key *k, int v);

/* Sets every bound key of `section` that has a default to it, in the struct
 * at base (the section's struct, see bs_schema_key). */
void bs__schema_defaults(const char *section, void *base);

/* The candidate keys of a section, NULL-terminated, into keys (room for cap
 * entries); the count. */
int bs__schema_section_keys(const char *section, const char **keys, int cap);

/* The design note (a path relative to docs/, e.g. "design/globalization.md")
 * of the key path ("solver.globalization", "bodies[].mesher", a section such
 * as "self_collision"), or NULL; the reference links each key to its note. */
const char *bs__schema_design_note(const char *path);

/* Every (key path, design note) pair of that table into *paths and *notes
 * (static arrays, not to be freed); the count. */
int bs__schema_design_notes(const char *const **paths, const char *const **notes);

#endif
