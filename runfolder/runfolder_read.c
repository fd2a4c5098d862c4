/* runfolder_read.c — reading a run folder back: frames.csv and state.bin
 * (formats: bs_runfolder.h). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bs_runfolder.h"

int bs_frames_csv_lines(const char *dir) {
  char p[BS_MAX_PATH + 64];
  snprintf(p, sizeof p, "%s/frames.csv", dir);
  FILE *f = fopen(p, "r");
  if (!f) return -1;
  int n = 0, c, last = '\n';
  while ((c = fgetc(f)) != EOF) {
    if (c == '\n') n++;
    last = c;
  }
  if (last != '\n') n++;
  fclose(f);
  return n;
}

void bs_frames_table_free(bs_frames_table *t) {
  free(t->time);
  free(t->kinetic);
  free(t->total);
  free(t->max_depth);
  memset(t, 0, sizeof *t);
}

enum { C_TIME, C_KIN, C_TOTAL, C_INV, C_NEWTON, C_CG, C_FAILED, C_SECONDS, C_DEPTH, C_N };

/* Column of each field of interest in the header line (-1: absent). */
static void header_columns(char *line, int col[C_N]) {
  static const char *names[C_N] = {"time", "kinetic", "total", "inverted", "newton", "cg", "failed", "seconds",
                                   "max_depth"};
  for (int c = 0; c < C_N; c++) col[c] = -1;
  int nc = 0;
  char *save = NULL;
  line[strcspn(line, "\r\n")] = 0;
  for (char *tok = strtok_r(line, ",", &save); tok; tok = strtok_r(NULL, ",", &save), nc++)
    for (int c = 0; c < C_N; c++)
      if (!strcmp(tok, names[c])) col[c] = nc;
}

static int grow_table(bs_frames_table *t, int cap) {
  double **cols[4] = {&t->time, &t->kinetic, &t->total, &t->max_depth};
  for (int i = 0; i < 4; i++) {
    double *q = realloc(*cols[i], sizeof(double) * (size_t)cap);
    if (!q) return -1;
    *cols[i] = q;
  }
  return 0;
}

static void add_row(bs_frames_table *t, const int col[C_N], const double *v, int k) {
#define COL(c) (col[c] >= 0 && col[c] < k ? v[col[c]] : 0.0)
  t->time[t->n] = COL(C_TIME);
  t->kinetic[t->n] = COL(C_KIN);
  t->total[t->n] = COL(C_TOTAL);
  t->max_depth[t->n] = COL(C_DEPTH);
  if ((int)COL(C_INV) > t->inverted_max) t->inverted_max = (int)COL(C_INV);
  t->newton += (long)COL(C_NEWTON);
  t->cg += (long)COL(C_CG);
  t->failed += (long)COL(C_FAILED);
  t->seconds += COL(C_SECONDS);
#undef COL
  t->n++;
}

int bs_frames_csv_read(const char *dir, bs_frames_table *t, bs_error *err) {
  memset(t, 0, sizeof *t);
  char p[BS_MAX_PATH + 64], line[8192];
  snprintf(p, sizeof p, "%s/frames.csv", dir);
  FILE *f = fopen(p, "r");
  if (!f) return bs_error_set(err, BS_EIO, "cannot open '%s'", p);
  if (!fgets(line, sizeof line, f)) {
    fclose(f);
    return bs_error_set(err, BS_EINPUT, "'%s': empty (no header line)", p);
  }
  int col[C_N], cap = 64;
  header_columns(line, col);
  t->has_depth = col[C_DEPTH] >= 0;
  int st = grow_table(t, cap) ? bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", p) : 0;
  while (!st && fgets(line, sizeof line, f)) {
    double v[64];
    int k = 0;
    for (char *s = line; k < 64;) {
      v[k++] = strtod(s, NULL);
      if (!(s = strchr(s, ','))) break;
      s++;
    }
    if (t->n == cap && grow_table(t, cap *= 2)) st = bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", p);
    if (!st) add_row(t, col, v, k);
  }
  fclose(f);
  if (st) bs_frames_table_free(t);
  return st;
}

/* The header: version 2 ("BSST", uint32 2, int32 n, int32 0) or version 1
 * ("BSST1\0\0\0", int32 n, int32 0); 0 with version and n, or -1. */
static int read_state_header(FILE *f, int *version, int32_t *n) {
  unsigned char magic[8];
  int32_t hdr[2];
  if (fread(magic, 1, 8, f) != 8 || fread(hdr, 4, 2, f) != 2) return -1;
  uint32_t v2;
  memcpy(&v2, magic + 4, 4);
  if (!memcmp(magic, "BSST1\0\0\0", 8)) *version = 1;
  else if (!memcmp(magic, "BSST", 4)) *version = (int)v2;
  else return -1;
  *n = hdr[0];
  return 0;
}

int bs_state_open(const char *dir, bs_state_reader *r, bs_error *err) {
  memset(r, 0, sizeof *r);
  char p[BS_MAX_PATH + 64];
  snprintf(p, sizeof p, "%s/state.bin", dir);
  r->f = fopen(p, "rb");
  if (!r->f) return bs_error_set(err, BS_EIO, "cannot open '%s'", p);
  int st = 0;
  if (read_state_header(r->f, &r->version, &r->n)) st = bs_error_set(err, BS_EINPUT, "'%s': not a bigstep state file", p);
  else if (r->version < 1 || r->version > BS_STATE_VERSION)
    st = bs_error_set(err, BS_EINPUT, "'%s': state format version %d (this bigstep reads 1 to %d)", p, r->version,
                      BS_STATE_VERSION);
  else if (r->n <= 0) st = bs_error_set(err, BS_EINPUT, "'%s': %d vertices in the header", p, r->n);
  struct stat sb;
  size_t rec = sizeof(double) * (1 + 6 * (size_t)(r->n > 0 ? r->n : 0));
  if (!st && (fstat(fileno(r->f), &sb) || sb.st_size < 16))
    st = bs_error_set(err, BS_EIO, "cannot read the size of '%s'", p);
  if (!st) r->frames = (long)(((size_t)sb.st_size - 16) / rec);
  if (!st && r->frames == 0 && (size_t)sb.st_size > 16)
    st = bs_error_set(err, BS_EINPUT, "'%s': shorter than one frame of %d vertices (truncated?)", p, r->n);
  if (!st && !(r->buf = malloc(rec))) st = bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", p);
  if (st) {
    bs_state_close(r);
    return st;
  }
  r->x = r->buf + 1;
  r->v = r->buf + 1 + 3 * (size_t)r->n;
  return 0;
}

int bs_state_next(bs_state_reader *r) {
  size_t m = 1 + 6 * (size_t)r->n;
  if (fread(r->buf, sizeof(double), m, r->f) != m) return 1;
  r->time = r->buf[0];
  return 0;
}

void bs_state_close(bs_state_reader *r) {
  if (r->f) fclose(r->f);
  free(r->buf);
  memset(r, 0, sizeof *r);
}
