/* pvd_read.c — reads a PVD collection (VTKFile type="Collection") with
 * expat: its DataSet entries' timestep and file, the file resolved against
 * the PVD's folder; see bs_vtu_read.h. The file is streamed to expat in
 * chunks, so a PVD of any length takes little memory beyond its entries. */
#include <errno.h>
#include <expat.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_vtu_read.h"

enum { CHUNK = 1 << 16 };

typedef struct pstate {
  const char *path;
  XML_Parser xp;
  bs_error *err;
  int rc;
  int depth, seen_root;
  bs_pvd *pv;
  int cap;
} pstate;

static void fail(pstate *st, int rc) {
  if (!st->rc) st->rc = rc;
  XML_StopParser(st->xp, XML_FALSE);
}

static const char *att(const XML_Char **a, const char *key) {
  for (; *a; a += 2)
    if (!strcmp(a[0], key)) return a[1];
  return NULL;
}

/* file resolved against the folder of the PVD (unless absolute). */
static char *resolve(const char *pvd, const char *file) {
  const char *slash = strrchr(pvd, '/');
  size_t dl = file[0] != '/' && slash ? (size_t)(slash - pvd) + 1 : 0, fl = strlen(file);
  char *full = malloc(dl + fl + 1);
  if (!full) return NULL;
  memcpy(full, pvd, dl);
  memcpy(full + dl, file, fl + 1);
  return full;
}

static int add_entry(pstate *st, char *file, double time) {
  bs_pvd *pv = st->pv;
  if (pv->n == st->cap) {
    int nc = st->cap ? 2 * st->cap : 16;
    char **nf = realloc(pv->files, (size_t)nc * sizeof *nf);
    if (nf) pv->files = nf;
    double *nt = realloc(pv->times, (size_t)nc * sizeof *nt);
    if (nt) pv->times = nt;
    if (!nf || !nt) return -1;
    st->cap = nc;
  }
  pv->files[pv->n] = file;
  pv->times[pv->n] = time;
  pv->n++;
  return 0;
}

static void on_dataset(pstate *st, const XML_Char **a) {
  const int k = st->pv->n;
  const char *file = att(a, "file"), *ts = att(a, "timestep");
  if (!file || !file[0]) {
    fail(st, bs_error_set(st->err, BS_EINPUT, "'%s': DataSet entry %d has no file attribute", st->path, k));
    return;
  }
  double time = 0;
  if (ts) {
    char *e = NULL;
    time = strtod(ts, &e);
    if (e == ts || *e || !isfinite(time)) {
      fail(st, bs_error_set(st->err, BS_EINPUT, "'%s': DataSet entry %d ('%s') has an invalid timestep '%s'",
                            st->path, k, file, ts));
      return;
    }
  }
  char *full = resolve(st->path, file);
  if (!full || add_entry(st, full, time)) {
    free(full);
    fail(st, bs_error_set(st->err, BS_ENOMEM, "reading '%s': out of memory", st->path));
  }
}

static void XMLCALL on_start(void *ud, const XML_Char *name, const XML_Char **a) {
  pstate *st = ud;
  if (st->rc) return;
  if (st->depth++ > 0) {
    if (!strcmp(name, "DataSet")) on_dataset(st, a);
    return;
  }
  st->seen_root = 1;
  const char *type = att(a, "type");
  if (strcmp(name, "VTKFile"))
    fail(st, bs_error_set(st->err, BS_EINPUT, "'%s' is not a VTK XML file (its first element is <%s>)", st->path,
                          name));
  else if (!type || strcmp(type, "Collection"))
    fail(st, bs_error_set(st->err, BS_EINPUT, "'%s': VTKFile type is '%s', expected 'Collection' (a .pvd file)",
                          st->path, type ? type : "(none)"));
}

static void XMLCALL on_end(void *ud, const XML_Char *name) {
  pstate *st = ud;
  (void)name;
  st->depth--;
}

static int xml_error(pstate *st) {
  const enum XML_Error e = XML_GetErrorCode(st->xp);
  const unsigned long line = (unsigned long)XML_GetCurrentLineNumber(st->xp);
  const unsigned long col = (unsigned long)XML_GetCurrentColumnNumber(st->xp);
  if (!st->seen_root)
    return bs_error_set(st->err, BS_EINPUT, "'%s' is not a VTK XML file (%s at line %lu, column %lu)", st->path,
                        XML_ErrorString(e), line, col);
  return bs_error_set(st->err, BS_EINPUT, "'%s': malformed XML at line %lu, column %lu: %s%s", st->path, line, col,
                      XML_ErrorString(e),
                      e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN ? " (truncated file)" : "");
}

/* Streams fp to the parser. */
static int parse(pstate *st, FILE *fp) {
  char *buf = malloc(CHUNK);
  if (!buf) return bs_error_set(st->err, BS_ENOMEM, "reading '%s': out of memory", st->path);
  int rc = BS_OK;
  for (;;) {
    size_t n = fread(buf, 1, CHUNK, fp);
    if (ferror(fp)) {
      int e = errno;
      rc = bs_error_set(st->err, BS_EIO, "cannot read PVD file '%s': %s", st->path, strerror(e));
      break;
    }
    const int final = n < CHUNK;
    if (XML_Parse(st->xp, buf, (int)n, final) != XML_STATUS_OK) {
      rc = st->rc ? st->rc : xml_error(st);
      break;
    }
    if (final) break;
  }
  free(buf);
  return rc;
}

void bs_pvd_destroy(bs_pvd **pp) {
  if (!pp || !*pp) return;
  bs_pvd *p = *pp;
  for (int i = 0; i < p->n; i++) free(p->files[i]);
  free(p->files);
  free(p->times);
  free(p);
  *pp = NULL;
}

int bs_pvd_read(const char *path, bs_pvd **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "read pvd: out is NULL");
  *out = NULL;
  if (!path) return bs_error_set(err, BS_EINPUT, "read pvd: path is NULL");
  FILE *fp = fopen(path, "rb");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot open PVD file '%s': %s", path, strerror(e));
  }
  pstate st = {.path = path, .err = err, .pv = calloc(1, sizeof(bs_pvd))};
  st.xp = st.pv ? XML_ParserCreate(NULL) : NULL;
  int rc = !st.xp ? bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory", path) : BS_OK;
  if (!rc) {
    XML_SetUserData(st.xp, &st);
    XML_SetElementHandler(st.xp, on_start, on_end);
    rc = parse(&st, fp);
  }
  if (st.xp) XML_ParserFree(st.xp);
  fclose(fp);
  if (rc) {
    bs_pvd_destroy(&st.pv);
    return rc;
  }
  *out = st.pv;
  return BS_OK;
}
