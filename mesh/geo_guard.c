/* geo_guard.c — the security rule for Gmsh scripts: a .geo file (and every
 * file it includes or merges, and the "FILE.opt" options file Gmsh reads
 * beside it) is scanned before Gmsh parses it, and a command that runs a
 * program (SystemCall, NonBlockingSystemCall, OnelabRun) is refused unless
 * the process allowed them (bs_mesh_set_geo_system_calls). Gmsh 4.8 has no
 * option that disables them.
 *
 * The scan tokenizes as Gmsh's lexer does for what matters here: // and
 * slash-star comments and "..." strings are skipped (a keyword in a string
 * is not a command; Gmsh has no eval), identifiers are compared whole and
 * case-sensitively. An Include or Merge of a literal "path" is scanned in
 * turn (relative to the including file's folder, as Gmsh resolves it), at
 * most BS_GEO_MAX_DEPTH deep; an Include or Merge of a computed name
 * (StrCat, Sprintf, a variable) cannot be checked and is refused as well. */
#define _POSIX_C_SOURCE 200809L

#include <ctype.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "mesh_internal.h"

#define BS_GEO_MAX_DEPTH 16
#define BS_GEO_MAX_BYTES (256L << 20) /* a script larger than 256 MiB is refused */

static atomic_int allow_system_calls;

void bs_mesh_set_geo_system_calls(int allow) { atomic_store(&allow_system_calls, allow != 0); }
int bs_mesh_geo_system_calls(void) { return atomic_load(&allow_system_calls); }

static const char *const run_words[] = {"SystemCall", "NonBlockingSystemCall", "OnelabRun", NULL};

/* The whole file as a string (NUL-terminated) into *out (the caller frees). */
static int slurp(const char *path, char **out, long *len, bs_error *err) {
  FILE *f = fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "%s: cannot read the Gmsh script: %s", path, strerror(errno));
  long n = -1;
  int st = 0;
  if (fseek(f, 0, SEEK_END) == 0) n = ftell(f);
  if (n < 0 || n > BS_GEO_MAX_BYTES || fseek(f, 0, SEEK_SET) != 0)
    st = bs_error_set(err, BS_EINPUT, "%s: cannot read the Gmsh script (%ld bytes; at most %ld)", path, n,
                      BS_GEO_MAX_BYTES);
  else if (!(*out = bs_calloc((size_t)n + 1, 1, "a Gmsh script", err)))
    st = BS_ENOMEM;
  else if (fread(*out, 1, (size_t)n, f) != (size_t)n) {
    st = bs_error_set(err, BS_EIO, "%s: cannot read the Gmsh script: %s", path, strerror(errno));
    free(*out);
    *out = NULL;
  } else
    *len = n;
  fclose(f);
  return st;
}

/* Skips blanks and comments from p; returns the next token's start. */
static const char *skip_space(const char *p, const char *end, int *line) {
  while (p < end) {
    if (*p == '\n') ++*line, p++;
    else if (isspace((unsigned char)*p)) p++;
    else if (p + 1 < end && p[0] == '/' && p[1] == '/')
      while (p < end && *p != '\n') p++;
    else if (p + 1 < end && p[0] == '/' && p[1] == '*') {
      for (p += 2; p < end && !(p + 1 < end && p[0] == '*' && p[1] == '/'); p++)
        if (*p == '\n') ++*line;
      p = p + 2 < end ? p + 2 : end;
    } else break;
  }
  return p;
}

/* The string literal at p ('"' at p): its end after the closing quote; its
 * text (escapes kept) into out (truncated to n). */
static const char *string_lit(const char *p, const char *end, int *line, char *out, size_t n) {
  size_t k = 0;
  for (p++; p < end && *p != '"'; p++) {
    if (*p == '\\' && p + 1 < end) p++;
    if (*p == '\n') ++*line;
    if (k + 1 < n) out[k++] = *p;
  }
  if (n) out[k] = 0;
  return p < end ? p + 1 : end;
}

static int scan_file(const char *path, int depth, bs_error *err);

/* The file an Include / Merge names, relative to the folder of `from`. */
static int scan_included(const char *from, const char *name, int line, int depth, bs_error *err) {
  char full[4096];
  const char *slash = strrchr(from, '/');
  if (name[0] == '/' || !slash) snprintf(full, sizeof full, "%s", name);
  else snprintf(full, sizeof full, "%.*s/%s", (int)(slash - from), from, name);
  struct stat st;
  if (stat(full, &st) != 0)
    return bs_error_set(err, BS_EINPUT, "%s:%d: includes '%s', which cannot be checked: %s", from, line, name,
                        strerror(errno));
  return scan_file(full, depth + 1, err);
}

static int scan_text(const char *path, const char *p, const char *end, int depth, bs_error *err) {
  int line = 1;
  while ((p = skip_space(p, end, &line)) < end) {
    char tmp[2048];
    if (*p == '"') {
      p = string_lit(p, end, &line, tmp, sizeof tmp);
      continue;
    }
    if (!(isalpha((unsigned char)*p) || *p == '_')) {
      p++;
      continue;
    }
    const char *w = p;
    while (p < end && (isalnum((unsigned char)*p) || *p == '_')) p++;
    const size_t len = (size_t)(p - w);
    for (int i = 0; run_words[i]; i++)
      if (len == strlen(run_words[i]) && !memcmp(w, run_words[i], len))
        return bs_error_set(err, BS_EINPUT,
                            "%s:%d: the Gmsh script runs a program (%s), which is refused for untrusted inputs "
                            "(allow it with --allow-geo-system if you trust the file)",
                            path, line, run_words[i]);
    if ((len == 7 && !memcmp(w, "Include", 7)) || (len == 5 && !memcmp(w, "Merge", 5))) {
      const char *q = skip_space(p, end, &line);
      if (q >= end || *q != '"')
        return bs_error_set(err, BS_EINPUT,
                            "%s:%d: %.*s of a computed file name cannot be checked for system calls and is refused "
                            "(allow it with --allow-geo-system if you trust the file)",
                            path, line, (int)len, w);
      p = string_lit(q, end, &line, tmp, sizeof tmp);
      int st = scan_included(path, tmp, line, depth, err);
      if (st) return st;
    }
  }
  return 0;
}

static int scan_file(const char *path, int depth, bs_error *err) {
  if (depth > BS_GEO_MAX_DEPTH)
    return bs_error_set(err, BS_EINPUT, "%s: Gmsh scripts include each other more than %d deep", path,
                        BS_GEO_MAX_DEPTH);
  const char *ext = strrchr(path, '.');
  /* Merge of a mesh or CAD file reads data, not a script. */
  static const char *const data_ext[] = {".msh", ".step", ".stp", ".brep", ".iges", ".igs", ".stl", ".STEP",
                                         ".STP", ".BREP", ".IGES", ".IGS", ".STL", ".vtk", ".pos", NULL};
  for (int i = 0; ext && data_ext[i]; i++)
    if (!strcmp(ext, data_ext[i])) return 0;
  long n = 0;
  char *text = NULL;
  int st = slurp(path, &text, &n, err);
  if (st) return st;
  st = scan_text(path, text, text + n, depth, err);
  free(text);
  return st;
}

int bs__geo_check(const char *path, bs_error *err) {
  if (atomic_load(&allow_system_calls)) return 0;
  int st = scan_file(path, 0, err);
  if (st) return st;
  char opt[4096];
  struct stat sb;
  snprintf(opt, sizeof opt, "%s.opt", path); /* Gmsh merges FILE.opt after FILE */
  return stat(opt, &sb) == 0 ? scan_file(opt, 1, err) : 0;
}
