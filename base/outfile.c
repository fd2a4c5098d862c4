/* outfile.c — checked output files and replacing through a temporary file
 * (outfile.h). */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "outfile.h"

static void set_path(bs_outfile *o, const char *dir, const char *name) {
  memset(o, 0, sizeof *o);
  if (dir) snprintf(o->path, sizeof o->path, "%s/%s", dir, name);
  else snprintf(o->path, sizeof o->path, "%s", name);
}

int bs_outfile_open(bs_outfile *o, const char *dir, const char *name, const char *mode, bs_error *err) {
  set_path(o, dir, name);
  if (!(o->f = fopen(o->path, mode)))
    return bs_error_set(err, BS_EIO, "cannot write '%s': %s", o->path, strerror(errno));
  return 0;
}

int bs_outfile_open_replace(bs_outfile *o, const char *dir, const char *name, bs_error *err) {
  set_path(o, dir, name);
  bs_tmp_path(o->tmp, sizeof o->tmp, o->path);
  if (!(o->f = fopen(o->tmp, "wb")))
    return bs_error_set(err, BS_EIO, "cannot write '%s' (as '%s'): %s", o->path, o->tmp, strerror(errno));
  return 0;
}

static void failed(bs_outfile *o) {
  if (!o->bad) o->eno = errno;
  o->bad = 1;
}

int bs_outfile_printf(bs_outfile *o, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vfprintf(o->f, fmt, ap);
  va_end(ap);
  if (n < 0) failed(o);
  return n < 0 ? -1 : 0;
}

int bs_outfile_write(bs_outfile *o, const void *p, size_t size, size_t n) {
  if (fwrite(p, size, n, o->f) == n) return 0;
  failed(o);
  return -1;
}

static int verdict(const bs_outfile *o, bs_error *err) {
  if (!o->bad) return 0;
  return bs_error_set(err, BS_EIO, "cannot write '%s': %s", o->path, strerror(o->eno ? o->eno : EIO));
}

int bs_outfile_flush(bs_outfile *o, bs_error *err) {
  if (fflush(o->f) != 0 || ferror(o->f)) failed(o);
  return verdict(o, err);
}

int bs_outfile_close(bs_outfile *o, bs_error *err) {
  if (!o->f) return 0;
  if (fflush(o->f) != 0 || ferror(o->f)) failed(o);
  if (fclose(o->f) != 0) failed(o);
  o->f = NULL;
  int st = verdict(o, err);
  if (o->tmp[0]) {
    if (st) remove(o->tmp);
    else st = bs_tmp_commit(o->tmp, o->path, err);
  }
  return st;
}

void bs_outfile_abandon(bs_outfile *o) {
  if (!o->f) return;
  fclose(o->f);
  o->f = NULL;
  if (o->tmp[0]) remove(o->tmp);
}

void bs_tmp_path(char *tmp, size_t n, const char *path) { snprintf(tmp, n, "%s%s", path, BS_TMP_SUFFIX); }

int bs_tmp_commit(const char *tmp, const char *path, bs_error *err) {
  if (rename(tmp, path) == 0) return 0;
  int e = errno;
  remove(tmp);
  return bs_error_set(err, BS_EIO, "cannot write '%s' (renaming '%s' over it): %s", path, tmp, strerror(e));
}

int bs_outfile_replace_text(const char *dir, const char *name, const char *text, bs_error *err) {
  bs_outfile o;
  int st = bs_outfile_open_replace(&o, dir, name, err);
  if (st) return st;
  bs_outfile_write(&o, text, 1, strlen(text));
  return bs_outfile_close(&o, err);
}
