/* vtu_read.c — the XML structure of a VTU file, parsed with expat, and
 * bs_vtu_read; see bs_vtu_read.h for the scope and vtu_internal.h for the
 * parts.
 *
 * The file is read whole and handed to expat in chunks. The handlers record
 * the VTKFile attributes (byte order, header type, compressor), the Piece's
 * counts and every DataArray (its attributes, and the text of an inline one)
 * in a bs__vtu_doc. Raw appended data is not XML, so parsing stops at the
 * <AppendedData> start tag, as VTK's own reader does: the data begins after
 * the '_' that follows the tag and ends at the </AppendedData></VTKFile>
 * that must close the file. The arrays are decoded afterwards (vtu_build.c),
 * when their expected sizes are known. */
#include <errno.h>
#include <expat.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_limits.h"
#include "mesh_internal.h"
#include "vtu_internal.h"

/* ---- file ---------------------------------------------------------------- */

static int slurp(const char *path, char **buf, size_t *len, bs_error *err) {
  FILE *fp = fopen(path, "rb");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot open VTU file '%s': %s", path, strerror(e));
  }
  size_t cap = 1 << 16, n = 0;
  char *b = malloc(cap + 1);
  while (b) {
    n += fread(b + n, 1, cap - n, fp);
    if (n < cap) break;
    char *nb = cap > SIZE_MAX / 4 ? NULL : realloc(b, 2 * cap + 1);
    if (!nb) free(b);
    b = nb;
    cap *= 2;
  }
  int e = errno, bad = ferror(fp);
  fclose(fp);
  if (!b) return bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory after %zu bytes", path, n);
  if (bad) {
    free(b);
    return bs_error_set(err, BS_EIO, "cannot read VTU file '%s': %s", path, strerror(e));
  }
  b[n] = '\0';
  *buf = b;
  *len = n;
  return BS_OK;
}

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

static const char *machine_order(void) {
  const uint16_t one = 1;
  unsigned char c;
  memcpy(&c, &one, 1);
  return c ? "LittleEndian" : "BigEndian";
}

/* ---- parser state ------------------------------------------------------------ */

enum { MAX_DEPTH = 64, CHUNK = 1 << 16, NAME_CAP = 32 };

typedef struct xstate {
  const char *path;
  bs__vtu_doc *d;
  XML_Parser xp;
  bs_error *err;
  int rc;    /* the first error (parsing stopped there) */
  int depth; /* open elements; sec[k], names[k] describe the k-th (1-based) */
  bs__vtu_section sec[MAX_DEPTH + 1];
  char names[MAX_DEPTH + 1][NAME_CAP];
  int seen_root;
  int cur, cur_depth;   /* the inline DataArray whose text is collected   */
  int at_appended;      /* stopped at <AppendedData>                      */
  size_t app_tag_end;   /* the byte after its start tag                   */
} xstate;

/* Records the error rc (set by the caller in st->err) and stops expat. */
static void fail(xstate *st, int rc) {
  if (!st->rc) st->rc = rc;
  XML_StopParser(st->xp, XML_FALSE);
}

/* Sets the error expr (a bs_error_set call), stops expat and returns. */
#define FAIL(st, expr)   \
  do {                   \
    fail((st), (expr));  \
    return;              \
  } while (0)

static const char *att(const XML_Char **a, const char *key) {
  for (; *a; a += 2)
    if (!strcmp(a[0], key)) return a[1];
  return NULL;
}

/* A base-10 integer in [0, max], the whole string: 0, else -1. */
static int parse_count(const char *s, uint64_t max, uint64_t *out) {
  if (!s) return -1;
  while (is_space(*s)) s++;
  if (*s < '0' || *s > '9') return -1;
  char *e;
  errno = 0;
  unsigned long long v = strtoull(s, &e, 10);
  while (is_space(*e)) e++;
  if (*e || errno || v > max) return -1;
  *out = v;
  return 0;
}

/* ---- elements -------------------------------------------------------------- */

static void on_root(xstate *st, const char *name, const XML_Char **a) {
  const char *p = st->path;
  bs_error *err = st->err;
  if (strcmp(name, "VTKFile")) {
    fail(st, bs_error_set(err, BS_EINPUT, "'%s' is not a VTK XML file (its first element is <%s>, not <VTKFile>)",
                          p, name));
    return;
  }
  const char *type = att(a, "type"), *bo = att(a, "byte_order"), *ht = att(a, "header_type");
  const char *comp = att(a, "compressor");
  if (!type || strcmp(type, "UnstructuredGrid"))
    fail(st, bs_error_set(err, BS_EINPUT, "'%s': VTKFile type is '%s', expected 'UnstructuredGrid' (a .vtu file)", p,
                          type ? type : "(none)"));
  else if (bo && strcmp(bo, "LittleEndian") && strcmp(bo, "BigEndian"))
    fail(st, bs_error_set(err, BS_EINPUT, "'%s': byte_order '%s' (expected LittleEndian or BigEndian)", p, bo));
  else if (ht && strcmp(ht, "UInt32") && strcmp(ht, "UInt64"))
    fail(st, bs_error_set(err, BS_EINPUT, "'%s': header_type '%s' (expected UInt32 or UInt64)", p, ht));
  else if (comp && *comp && strcmp(comp, "vtkZLibDataCompressor"))
    fail(st, bs_error_set(err, BS_EINPUT, "'%s': compressor '%s' is not read (only vtkZLibDataCompressor)", p, comp));
  st->d->swap = bo && strcmp(bo, machine_order()) != 0;
  st->d->header8 = ht && !strcmp(ht, "UInt64");
  st->d->zlib = comp && *comp;
}

static void on_piece(xstate *st, const XML_Char **a) {
  bs__vtu_doc *d = st->d;
  if (++d->n_piece > 1) {
    fail(st, bs_error_set(st->err, BS_EINPUT, "'%s' has more than one <Piece>; only single-piece files are read",
                          st->path));
    return;
  }
  const char *np = att(a, "NumberOfPoints"), *nc = att(a, "NumberOfCells");
  uint64_t vp, vc;
  const int bad_p = parse_count(np, BS_MAX_VERTICES, &vp), bad_c = parse_count(nc, BS_MAX_TETS, &vc);
  if (bad_p || bad_c) {
    const char *key = bad_p ? "NumberOfPoints" : "NumberOfCells", *val = bad_p ? np : nc;
    fail(st, bs_error_set(st->err, BS_EINPUT, "'%s': <Piece> %s is '%s': expected an integer in [0, %ld] (bigstep's limit)",
                          st->path, key, val ? val : "(none)", bad_p ? (long)BS_MAX_VERTICES : (long)BS_MAX_TETS));
    return;
  }
  d->n_points = (int64_t)vp;
  d->n_cells = (int64_t)vc;
}

static int add_decl(bs__vtu_doc *d, const bs__vtu_decl *a) {
  if (d->n_arr == d->cap_arr) {
    int nc = d->cap_arr ? 2 * d->cap_arr : 16;
    bs__vtu_decl *na = realloc(d->arr, (size_t)nc * sizeof *na);
    if (!na) return -1;
    d->arr = na;
    d->cap_arr = nc;
  }
  d->arr[d->n_arr] = *a;
  return d->n_arr++;
}

/* A DataArray in section sec (BS__VTU_OTHER: kept only when appended). */
static void on_array(xstate *st, const XML_Char **a, bs__vtu_section sec) {
  const char *name = att(a, "Name"), *fmt = att(a, "format"), *ty = att(a, "type");
  const char *nc = att(a, "NumberOfComponents"), *off = att(a, "offset");
  const char *shown = name ? name : "", *p = st->path;
  bs_error *err = st->err;
  bs__vtu_decl dl = {.section = sec, .ncomp = 1};
  uint64_t v = 0;
  const int f = !fmt ? -1 : !strcmp(fmt, "ascii") ? BS__VTU_ASCII : !strcmp(fmt, "binary") ? BS__VTU_BINARY
                          : !strcmp(fmt, "appended") ? BS__VTU_APPENDED : -1;
  const int bad_off = f == BS__VTU_APPENDED && parse_count(off, UINT64_MAX, &dl.offset);
  if (sec == BS__VTU_OTHER && (f != BS__VTU_APPENDED || bad_off)) return;
  if (f < 0)
    FAIL(st, bs_error_set(err, BS_EINPUT, "'%s': array '%s' has format '%s' (expected ascii, binary or "
                          "appended)", p, shown, fmt ? fmt : "(none)"));
  if (bad_off)
    FAIL(st, bs_error_set(err, BS_EINPUT, "'%s': array '%s' has no valid offset attribute ('%s')", p, shown,
                          off ? off : "(none)"));
  if (sec != BS__VTU_OTHER && bs__vtu_type_parse(ty, &dl.type))
    FAIL(st, bs_error_set(err, BS_EINPUT, "'%s': array '%s' has unknown type '%s'", p, shown,
                          ty ? ty : "(none)"));
  if (sec != BS__VTU_OTHER && nc && (parse_count(nc, 1024, &v) || v < 1))
    FAIL(st, bs_error_set(err, BS_EINPUT, "'%s': array '%s' has NumberOfComponents '%s' (expected 1..1024)",
                          p, shown, nc));
  dl.ncomp = nc && sec != BS__VTU_OTHER ? (int)v : 1;
  dl.format = (bs__vtu_format)f;
  int idx = (dl.name = bs__strdup(shown)) ? add_decl(st->d, &dl) : -1;
  if (idx < 0) {
    free(dl.name);
    FAIL(st, bs_error_set(err, BS_ENOMEM, "'%s': out of memory", p));
  }
  if (dl.format != BS__VTU_APPENDED) {
    st->cur = idx;
    st->cur_depth = st->depth + 1;
  }
}

static void on_appended(xstate *st, const XML_Char **a) {
  if (st->depth != 1)
    FAIL(st, bs_error_set(st->err, BS_EINPUT, "'%s': <AppendedData> inside <%s>: a closing tag is missing "
                          "before it", st->path, st->names[st->depth]));
  const char *enc = att(a, "encoding");
  if (!enc || (strcmp(enc, "raw") && strcmp(enc, "base64")))
    FAIL(st, bs_error_set(st->err, BS_EINPUT, "'%s': AppendedData encoding is '%s' (expected raw or base64)",
                          st->path, enc ? enc : "(none)"));
  st->d->app_base64 = !strcmp(enc, "base64");
  st->app_tag_end = (size_t)(XML_GetCurrentByteIndex(st->xp) + XML_GetCurrentByteCount(st->xp));
  st->at_appended = 1;
  XML_StopParser(st->xp, XML_FALSE);
}

static void XMLCALL on_start(void *ud, const XML_Char *name, const XML_Char **a) {
  xstate *st = ud;
  if (st->rc || st->at_appended) return;
  if (st->depth >= MAX_DEPTH)
    FAIL(st, bs_error_set(st->err, BS_EINPUT, "'%s': elements nested more than %d deep", st->path, MAX_DEPTH));
  bs__vtu_section own = BS__VTU_OTHER;
  if (st->depth == 0) {
    on_root(st, name, a);
    st->seen_root = 1;
  } else if (!strcmp(name, "Piece")) {
    on_piece(st, a);
  } else if (!strcmp(name, "DataArray")) {
    on_array(st, a, st->sec[st->depth]); /* the section of its parent */
  } else if (!strcmp(name, "AppendedData")) {
    on_appended(st, a);
  } else {
    static const struct {
      const char *name;
      bs__vtu_section sec;
    } sections[] = {{"PointData", BS__VTU_POINTDATA}, {"CellData", BS__VTU_CELLDATA},
                    {"Points", BS__VTU_POINTS},       {"Cells", BS__VTU_CELLS}};
    for (size_t i = 0; i < sizeof sections / sizeof sections[0]; i++)
      if (!strcmp(name, sections[i].name)) own = sections[i].sec;
  }
  st->depth++;
  st->sec[st->depth] = own;
  snprintf(st->names[st->depth], NAME_CAP, "%s", name);
}

static void XMLCALL on_end(void *ud, const XML_Char *name) {
  xstate *st = ud;
  (void)name;
  if (st->depth == st->cur_depth) st->cur = st->cur_depth = -1;
  if (st->depth > 0) st->depth--;
}

/* Character data directly inside the inline DataArray being read. */
static void XMLCALL on_text(void *ud, const XML_Char *s, int len) {
  xstate *st = ud;
  if (st->rc || st->cur < 0 || st->depth != st->cur_depth || len <= 0) return;
  bs__vtu_decl *a = &st->d->arr[st->cur];
  if (a->text_len + (size_t)len + 1 > a->text_cap) {
    size_t cap = a->text_cap ? 2 * a->text_cap : 256;
    while (cap < a->text_len + (size_t)len + 1) cap *= 2;
    char *t = realloc(a->text, cap);
    if (!t) FAIL(st, bs_error_set(st->err, BS_ENOMEM, "'%s': out of memory", st->path));
    a->text = t;
    a->text_cap = cap;
  }
  memcpy(a->text + a->text_len, s, (size_t)len);
  a->text_len += (size_t)len;
  a->text[a->text_len] = '\0';
}

/* ---- the document ------------------------------------------------------------- */

static int xml_error(xstate *st) {
  const enum XML_Error e = XML_GetErrorCode(st->xp);
  const unsigned long line = (unsigned long)XML_GetCurrentLineNumber(st->xp);
  const unsigned long col = (unsigned long)XML_GetCurrentColumnNumber(st->xp);
  if (!st->seen_root)
    return bs_error_set(st->err, BS_EINPUT, "'%s' is not a VTK XML file (%s at line %lu, column %lu)", st->path,
                        XML_ErrorString(e), line, col);
  const int at_end = e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN || e == XML_ERROR_PARTIAL_CHAR ||
                     e == XML_ERROR_UNCLOSED_CDATA_SECTION;
  return bs_error_set(st->err, BS_EINPUT, "'%s': malformed XML at line %lu, column %lu: %s%s", st->path, line, col,
                      XML_ErrorString(e), at_end ? " (truncated file)" : "");
}

/* Feeds the file to expat until its end or <AppendedData>. */
static int parse_xml(xstate *st) {
  XML_Parser xp = XML_ParserCreate(NULL);
  if (!xp) return bs_error_set(st->err, BS_ENOMEM, "'%s': out of memory for the XML parser", st->path);
  st->xp = xp;
  XML_SetUserData(xp, st);
  XML_SetElementHandler(xp, on_start, on_end);
  XML_SetCharacterDataHandler(xp, on_text);
  const size_t len = st->d->len;
  size_t pos = 0;
  enum XML_Status s;
  for (;;) {
    const size_t n = len - pos < CHUNK ? len - pos : CHUNK;
    const int final = pos + n == len;
    s = XML_Parse(xp, st->d->buf + pos, (int)n, final);
    pos += n;
    if (final || s != XML_STATUS_OK) break;
  }
  int rc = st->rc;
  if (!rc && !st->at_appended && s != XML_STATUS_OK) rc = xml_error(st);
  XML_ParserFree(xp);
  st->xp = NULL;
  return rc;
}

static int ends_with(const char *begin, const char *end, const char *s) {
  size_t n = strlen(s);
  return (size_t)(end - begin) >= n && !memcmp(end - n, s, n);
}

/* The appended data: after the '_' that follows the <AppendedData> tag, up
 * to the </AppendedData> that, with </VTKFile>, must end the file. */
static int locate_appended(xstate *st) {
  bs__vtu_doc *d = st->d;
  const char *p = d->buf + st->app_tag_end, *end = d->buf + d->len;
  while (p < end && is_space(*p)) p++;
  if (p >= end || *p != '_')
    return bs_error_set(st->err, BS_EINPUT, "'%s': the data after <AppendedData> does not start with '_'%s",
                        st->path, p >= end ? " (truncated file)" : "");
  const char *base = p + 1, *q = end;
  while (q > base && is_space(q[-1])) q--;
  if (!ends_with(base, q, "</VTKFile>"))
    return bs_error_set(st->err, BS_EINPUT, "'%s' does not end with </VTKFile> after its appended data: truncated "
                        "file", st->path);
  q -= strlen("</VTKFile>");
  while (q > base && is_space(q[-1])) q--;
  if (!ends_with(base, q, "</AppendedData>"))
    return bs_error_set(st->err, BS_EINPUT, "'%s': no </AppendedData> before the closing </VTKFile>: truncated file",
                        st->path);
  q -= strlen("</AppendedData>");
  d->app = (const unsigned char *)base;
  d->app_len = (size_t)(q - base);
  return BS_OK;
}

int bs__vtu_doc_read(const char *path, bs__vtu_doc *d, bs_error *err) {
  memset(d, 0, sizeof *d);
  int rc = slurp(path, &d->buf, &d->len, err);
  if (rc) return rc;
  size_t i = 0;
  while (i < d->len && is_space(d->buf[i])) i++;
  if (i == d->len) return bs_error_set(err, BS_EINPUT, "'%s' is empty: not a VTU file", path);
  xstate st = {.path = path, .d = d, .err = err, .cur = -1, .cur_depth = -1};
  rc = parse_xml(&st);
  if (!rc && st.at_appended) rc = locate_appended(&st);
  return rc;
}

void bs__vtu_doc_free(bs__vtu_doc *d) {
  for (int i = 0; i < d->n_arr; i++) {
    free(d->arr[i].name);
    free(d->arr[i].text);
  }
  free(d->arr);
  free(d->buf);
  memset(d, 0, sizeof *d);
}

int bs_vtu_read(const char *path, bs_vtu **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "read vtu: out is NULL");
  *out = NULL;
  if (!path) return bs_error_set(err, BS_EINPUT, "read vtu: path is NULL");
  bs__vtu_doc d;
  int rc = bs__vtu_doc_read(path, &d, err);
  if (!rc) rc = bs__vtu_build(path, &d, out, err);
  bs__vtu_doc_free(&d);
  return rc;
}
