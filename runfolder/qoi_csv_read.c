/* qoi_csv_read.c — reading a run folder's qoi.csv back (format:
 * bs_runfolder.h): the header's names, then one row per frame. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_runfolder.h"

void bs_qoi_table_free(bs_qoi_table *t) {
  for (int i = 0; t->names && i < t->n_qoi; i++) free(t->names[i]);
  free(t->names);
  free(t->time);
  free(t->values);
  memset(t, 0, sizeof *t);
}

int bs_qoi_table_column(const bs_qoi_table *t, const char *name) {
  for (int i = 0; i < t->n_qoi; i++)
    if (!strcmp(t->names[i], name)) return i;
  return -1;
}

/* The header "frame,time,NAME,...": the names into t. */
static int read_header(char *line, const char *p, bs_qoi_table *t, bs_error *err) {
  line[strcspn(line, "\r\n")] = 0;
  if (strncmp(line, "frame,time", 10) || (line[10] && line[10] != ','))
    return bs_error_set(err, BS_EINPUT, "'%s' line 1: the header must start with frame,time", p);
  int n = 0;
  for (char *c = line + 10; *c; c++) n += *c == ',';
  if (!(t->names = calloc((size_t)n + 1, sizeof(char *)))) return bs_error_set(err, BS_ENOMEM, "out of memory");
  char *save = NULL, *tok = strtok_r(line + 10, ",", &save);
  for (; tok; tok = strtok_r(NULL, ",", &save)) {
    if (!(t->names[t->n_qoi] = strdup(tok))) return bs_error_set(err, BS_ENOMEM, "out of memory");
    t->n_qoi++;
  }
  if (t->n_qoi != n) return bs_error_set(err, BS_EINPUT, "'%s' line 1: an empty column name", p);
  return 0;
}

/* One row "frame,time,v,...": exactly 2 + n_qoi finite numbers. */
static int read_row(char *line, const char *p, int ln, bs_qoi_table *t, bs_error *err) {
  line[strcspn(line, "\r\n")] = 0;
  const int nc = 2 + t->n_qoi;
  double *row = t->values + (size_t)t->n_rows * (size_t)t->n_qoi;
  char *c = line;
  for (int k = 0; k < nc; k++) {
    char *end;
    double v = strtod(c, &end);
    if (end == c || !isfinite(v) || (*end != ',' && *end != 0) || (*end == 0) != (k == nc - 1))
      return bs_error_set(err, BS_EINPUT, "'%s' line %d: expected %d finite numbers, column %d is not one", p, ln,
                          nc, k + 1);
    if (k == 1) t->time[t->n_rows] = v;
    else if (k > 1) row[k - 2] = v;
    c = end + 1;
  }
  t->n_rows++;
  return 0;
}

static int grow(bs_qoi_table *t, int *cap, bs_error *err) {
  if (t->n_rows < *cap) return 0;
  int c = *cap ? 2 * *cap : 64;
  double *tt = realloc(t->time, sizeof(double) * (size_t)c);
  if (tt) t->time = tt;
  double *vv = tt ? realloc(t->values, sizeof(double) * (size_t)c * (size_t)(t->n_qoi ? t->n_qoi : 1)) : NULL;
  if (!vv) return bs_error_set(err, BS_ENOMEM, "out of memory reading qoi.csv");
  t->values = vv;
  *cap = c;
  return 0;
}

int bs_qoi_csv_read(const char *dir, bs_qoi_table *t, bs_error *err) {
  memset(t, 0, sizeof *t);
  char p[BS_MAX_PATH + 64], line[16384];
  snprintf(p, sizeof p, "%s/qoi.csv", dir);
  FILE *f = fopen(p, "r");
  if (!f) return bs_error_set(err, BS_EIO, "cannot open '%s'", p);
  int st = fgets(line, sizeof line, f) ? read_header(line, p, t, err)
                                       : bs_error_set(err, BS_EINPUT, "'%s' is empty (no header)", p);
  int cap = 0;
  for (int ln = 2; !st && fgets(line, sizeof line, f); ln++) {
    if (!strchr(line, '\n') && !feof(f)) st = bs_error_set(err, BS_EINPUT, "'%s' line %d is too long", p, ln);
    else if (line[0] == '\n' || line[0] == '\r') continue;
    else if (!(st = grow(t, &cap, err))) st = read_row(line, p, ln, t, err);
  }
  fclose(f);
  if (st) bs_qoi_table_free(t);
  return st;
}
