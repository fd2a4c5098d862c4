#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"

int bs_app_usage_error(const char *cmd, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "bigstep %s: ", cmd);
  vfprintf(stderr, fmt, ap);
  fprintf(stderr, " (see 'bigstep %s --help')\n", cmd);
  va_end(ap);
  return BS_EXIT_USAGE;
}

int bs_app_load_mesh(const char *spec, double size, int refine, int merge, double min_dihedral, bs_mesh **out,
                     bs_error *err) {
  bs_mesh_read_opts o = {.size = size, .refine = refine, .merge_coincident = merge, .min_dihedral = min_dihedral};
  return bs_app_load_mesh_opts(spec, &o, out, err);
}

int bs_app_load_mesh_opts(const char *spec, const bs_mesh_read_opts *o, bs_mesh **out, bs_error *err) {
  int st = bs_mesh_load(spec, o, out, err);
  const bs_mesh *m = st ? NULL : *out;
  if (m && m->n_coincident && m->coincident_merged)
    fprintf(stderr, "bigstep: note: %s: merged %d coincident nodes (same position as another node, distinct tags)\n",
            spec, m->n_coincident);
  else if (m && m->n_coincident)
    fprintf(stderr,
            "bigstep: warning: %s: %d nodes lie at the position of another node under a distinct tag; the body is "
            "split into pieces there (bigstep mesh ... --merge-coincident merges them)\n",
            spec, m->n_coincident);
  return st;
}

int bs_app_sets_add(bs_app_sets *s, const char *key, const char *value, int quote) {
  if (s->n == s->cap) {
    int cap = s->cap ? 2 * s->cap : 16;
    char **v = realloc(s->v, sizeof(char *) * (size_t)cap);
    if (!v) return -1;
    s->v = v;
    s->cap = cap;
  }
  size_t len = strlen(key) + (value ? strlen(value) : 0) + 4;
  char *e = malloc(len);
  if (!e) return -1;
  if (!value) snprintf(e, len, "%s", key);
  else snprintf(e, len, quote ? "%s=\"%s\"" : "%s=%s", key, value);
  s->v[s->n++] = e;
  return 0;
}

void bs_app_sets_free(bs_app_sets *s) {
  for (int i = 0; i < s->n; i++) free(s->v[i]);
  free(s->v);
  memset(s, 0, sizeof *s);
}

int bs_app_flag_value(int argc, char **argv, int *i, char *fbuf, size_t n, const char **flag, const char **value) {
  const char *a = argv[*i], *eq = strchr(a, '=');
  *value = NULL;
  *flag = fbuf;
  if (!strncmp(a, "--set=", 6)) {
    snprintf(fbuf, n, "--set");
    *value = a + 6;
  } else if (eq) {
    snprintf(fbuf, n, "%.*s", (int)(eq - a), a);
    *value = eq + 1;
  } else {
    snprintf(fbuf, n, "%s", a);
    if (*i + 1 < argc) *value = argv[++*i];
  }
  return *value ? 0 : -1;
}

int bs_app_write_mesh(const bs_mesh *m, const char *path, bs_error *err) {
  const char *dot = strrchr(path, '.');
  if (dot && strcmp(dot, ".msh") == 0) return bs_mesh_write_msh(m, NULL, path, err);
  if (dot && strcmp(dot, ".vtu") == 0) return bs_mesh_write_vtu(m, NULL, path, err);
  return bs_error_set(err, BS_EINPUT, "cannot write '%s': the output extension must be .msh or .vtu", path);
}

/* Appends arg to buf (length *len, capacity cap), quoted when it has a
 * character the shell would read. */
static void append_quoted(char *buf, size_t *len, const char *arg) {
  int plain = *arg != 0;
  for (const char *c = arg; *c; c++)
    if (!strchr("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=:,+@%", *c)) plain = 0;
  if (plain) {
    *len += (size_t)sprintf(buf + *len, " %s", arg);
    return;
  }
  *len += (size_t)sprintf(buf + *len, " '");
  for (const char *c = arg; *c; c++) *len += (size_t)(*c == '\'' ? sprintf(buf + *len, "'\\''") : sprintf(buf + *len, "%c", *c));
  *len += (size_t)sprintf(buf + *len, "'");
}

char *bs_app_command_line(int argc, char **argv) {
  size_t cap = 16;
  for (int i = 0; i < argc; i++) cap += 4 * strlen(argv[i]) + 4;
  char *buf = malloc(cap);
  if (!buf) return NULL;
  size_t len = (size_t)sprintf(buf, "bigstep");
  for (int i = 0; i < argc; i++) append_quoted(buf, &len, argv[i]);
  return buf;
}
