/* vtu_read.c — reads back VTU (raw appended) and PVD files; see
 * bs_vtu_read.h for the scope and the contract.
 *
 * The file is read whole. Its XML part (everything before the raw bytes) is
 * scanned tag by tag with a small scanner that knows elements, attributes
 * (single or double quoted, the five XML entities and numeric character
 * references), comments, processing instructions and declarations: enough
 * for VTK's XML, which has no mixed content before <AppendedData>. The raw
 * block starts after the '_' that follows the <AppendedData> start tag; an
 * array's offset attribute is the position of its byte-count header relative
 * to the first byte after '_', and the header (UInt64 or UInt32) holds the
 * number of bytes that follow. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_vtu_read.h"

/* ---- file ------------------------------------------------------------ */

static int slurp(const char *path, const char *what, char **buf, size_t *len, bs_error *err) {
  FILE *fp = fopen(path, "rb");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot open %s '%s': %s", what, path, strerror(e));
  }
  size_t cap = 1 << 16, n = 0;
  char *b = malloc(cap + 1);
  if (!b) {
    fclose(fp);
    return bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory", path);
  }
  for (;;) {
    size_t got = fread(b + n, 1, cap - n, fp);
    n += got;
    if (n < cap) break;
    char *nb = cap > SIZE_MAX / 4 ? NULL : realloc(b, 2 * cap + 1);
    if (!nb) {
      free(b);
      fclose(fp);
      return bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory after %zu bytes", path, n);
    }
    b = nb;
    cap *= 2;
  }
  int e = errno;
  int bad = ferror(fp);
  fclose(fp);
  if (bad) {
    free(b);
    return bs_error_set(err, BS_EIO, "cannot read %s '%s': %s", what, path, strerror(e));
  }
  b[n] = '\0';
  *buf = b;
  *len = n;
  return BS_OK;
}

/* ---- XML tag scanner ----------------------------------------------------- */

enum { MAX_ATTR = 32 };

typedef struct xtag {
  const char *name;
  size_t name_len;
  int closing, selfclose;
  int nattr;
  struct {
    const char *k, *v;
    size_t kl, vl;
  } a[MAX_ATTR];
  const char *end; /* one past the '>' */
} xtag;

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
static int is_name(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == ':' ||
         c == '-' || c == '.';
}

static const char *find(const char *p, const char *end, const char *s) {
  size_t n = strlen(s);
  for (; p + n <= end; p++)
    if (memcmp(p, s, n) == 0) return p;
  return NULL;
}

/* Next element tag at or after *pos (text, comments, <?...?> and <!...> are
 * skipped). 1: found (*pos moves past it); 0: no more tags; -1: malformed,
 * *why says how. */
static int next_tag(const char **pos, const char *end, xtag *t, const char **why) {
  const char *p = *pos;
  for (;;) {
    while (p < end && *p != '<') p++;
    if (p >= end) {
      *pos = p;
      return 0;
    }
    if (p + 4 <= end && !memcmp(p, "<!--", 4)) {
      const char *q = find(p + 4, end, "-->");
      if (!q) return *why = "an unterminated comment", -1;
      p = q + 3;
    } else if (p + 2 <= end && p[1] == '?') {
      const char *q = find(p + 2, end, "?>");
      if (!q) return *why = "an unterminated <? ... ?>", -1;
      p = q + 2;
    } else if (p + 2 <= end && p[1] == '!') {
      const char *q = memchr(p, '>', (size_t)(end - p));
      if (!q) return *why = "an unterminated <! ... >", -1;
      p = q + 1;
    } else {
      break;
    }
  }
  memset(t, 0, sizeof *t);
  p++;
  if (p < end && *p == '/') {
    t->closing = 1;
    p++;
  }
  t->name = p;
  while (p < end && is_name(*p)) p++;
  t->name_len = (size_t)(p - t->name);
  if (!t->name_len) return *why = "a '<' not followed by an element name", -1;
  for (;;) {
    while (p < end && is_space(*p)) p++;
    if (p >= end) return *why = "an unterminated tag", -1;
    if (*p == '>') {
      p++;
      break;
    }
    if (*p == '/' && p + 1 < end && p[1] == '>') {
      if (t->closing) return *why = "a malformed closing tag", -1;
      t->selfclose = 1;
      p += 2;
      break;
    }
    if (t->closing) return *why = "a malformed closing tag", -1;
    if (t->nattr >= MAX_ATTR) return *why = "a tag with too many attributes", -1;
    const char *k = p;
    while (p < end && is_name(*p)) p++;
    if (p == k) return *why = "a malformed attribute", -1;
    size_t kl = (size_t)(p - k);
    while (p < end && is_space(*p)) p++;
    if (p >= end || *p != '=') return *why = "an attribute without '='", -1;
    p++;
    while (p < end && is_space(*p)) p++;
    if (p >= end || (*p != '"' && *p != '\'')) return *why = "an unquoted attribute value", -1;
    char q = *p++;
    const char *v = p;
    while (p < end && *p != q) p++;
    if (p >= end) return *why = "an unterminated attribute value", -1;
    t->a[t->nattr].k = k;
    t->a[t->nattr].kl = kl;
    t->a[t->nattr].v = v;
    t->a[t->nattr].vl = (size_t)(p - v);
    t->nattr++;
    p++;
  }
  t->end = p;
  *pos = p;
  return 1;
}

static int tag_is(const xtag *t, const char *name) {
  return t->name_len == strlen(name) && !memcmp(t->name, name, t->name_len);
}

/* Decodes XML entities of s[0..n) into a new string (NULL on allocation
 * failure). Unknown entities are kept as written. */
static char *decode(const char *s, size_t n) {
  char *o = malloc(n + 1), *w = o;
  if (!o) return NULL;
  for (size_t i = 0; i < n;) {
    if (s[i] == '&') {
      static const struct {
        const char *e;
        char c;
      } ent[] = {{"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
      int done = 0;
      for (size_t k = 0; k < sizeof ent / sizeof ent[0] && !done; k++) {
        size_t el = strlen(ent[k].e);
        if (i + el <= n && !memcmp(s + i, ent[k].e, el)) {
          *w++ = ent[k].c;
          i += el;
          done = 1;
        }
      }
      if (!done && i + 3 < n && s[i + 1] == '#') {
        size_t j = i + 2;
        int hex = s[j] == 'x' || s[j] == 'X';
        if (hex) j++;
        unsigned long c = 0;
        size_t d0 = j;
        while (j < n && s[j] != ';' && j - d0 < 8) {
          char ch = s[j];
          int dv = ch >= '0' && ch <= '9' ? ch - '0'
                   : hex && ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
                   : hex && ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                                   : -1;
          if (dv < 0) break;
          c = c * (hex ? 16u : 10u) + (unsigned)dv;
          j++;
        }
        if (j < n && s[j] == ';' && j > d0 && c > 0 && c < 128) {
          *w++ = (char)c;
          i = j + 1;
          done = 1;
        }
      }
      if (done) continue;
    }
    *w++ = s[i++];
  }
  *w = '\0';
  return o;
}

/* Attribute `key` of t, decoded into a new string; NULL when absent (or on
 * allocation failure: *nomem is set). */
static char *attr_dup(const xtag *t, const char *key, int *nomem) {
  size_t kl = strlen(key);
  for (int i = 0; i < t->nattr; i++)
    if (t->a[i].kl == kl && !memcmp(t->a[i].k, key, kl)) {
      char *s = decode(t->a[i].v, t->a[i].vl);
      if (!s) *nomem = 1;
      return s;
    }
  return NULL;
}

/* Attribute into a fixed buffer: 1 found, 0 absent, -1 too long. */
static int attr_get(const xtag *t, const char *key, char *out, size_t cap) {
  size_t kl = strlen(key);
  for (int i = 0; i < t->nattr; i++)
    if (t->a[i].kl == kl && !memcmp(t->a[i].k, key, kl)) {
      if (t->a[i].vl >= cap) return -1;
      memcpy(out, t->a[i].v, t->a[i].vl);
      out[t->a[i].vl] = '\0';
      return 1;
    }
  return 0;
}

static int parse_i64(const char *s, int64_t *out) {
  if (!*s) return -1;
  char *e;
  errno = 0;
  long long v = strtoll(s, &e, 10);
  while (is_space(*e)) e++;
  if (*e || errno) return -1;
  *out = v;
  return 0;
}

static int parse_u64(const char *s, uint64_t *out) {
  while (is_space(*s)) s++;
  if (!*s || *s == '-') return -1;
  char *e;
  errno = 0;
  unsigned long long v = strtoull(s, &e, 10);
  while (is_space(*e)) e++;
  if (*e || errno) return -1;
  *out = v;
  return 0;
}

/* ---- VTK value types ----------------------------------------------------- */

typedef enum { T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64, T_N } vtype;
static const char *const type_name[T_N] = {"Int8",  "UInt8",  "Int16",  "UInt16",  "Int32",
                                           "UInt32", "Int64", "UInt64", "Float32", "Float64"};
static const int type_size[T_N] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};

static int type_parse(const char *s, vtype *t) {
  for (int i = 0; i < T_N; i++)
    if (!strcmp(s, type_name[i])) {
      *t = (vtype)i;
      return 0;
    }
  /* legacy VTK spellings */
  static const struct {
    const char *s;
    vtype t;
  } alt[] = {{"Float", T_F32}, {"Double", T_F64}, {"Int", T_I32}, {"Char", T_I8}, {"UChar", T_U8}};
  for (size_t i = 0; i < sizeof alt / sizeof alt[0]; i++)
    if (!strcmp(s, alt[i].s)) {
      *t = alt[i].t;
      return 0;
    }
  return -1;
}

/* The element at src in type t (bytes reversed first when swap), as a double
 * and, for integer types, as an int64 (*is_int = 1; UInt64 above INT64_MAX
 * gives *is_int = 0). */
static double load(const unsigned char *src, vtype t, int swap, int64_t *iv, int *is_int) {
  unsigned char b[8];
  int n = type_size[t];
  if (swap)
    for (int k = 0; k < n; k++) b[k] = src[n - 1 - k];
  else
    memcpy(b, src, (size_t)n);
  *is_int = 1;
  switch (t) {
    case T_I8: { int8_t v; memcpy(&v, b, 1); *iv = v; return v; }
    case T_U8: { uint8_t v; memcpy(&v, b, 1); *iv = v; return v; }
    case T_I16: { int16_t v; memcpy(&v, b, 2); *iv = v; return v; }
    case T_U16: { uint16_t v; memcpy(&v, b, 2); *iv = v; return v; }
    case T_I32: { int32_t v; memcpy(&v, b, 4); *iv = v; return v; }
    case T_U32: { uint32_t v; memcpy(&v, b, 4); *iv = v; return v; }
    case T_I64: { int64_t v; memcpy(&v, b, 8); *iv = v; return (double)v; }
    case T_U64: {
      uint64_t v;
      memcpy(&v, b, 8);
      *is_int = v <= (uint64_t)INT64_MAX;
      *iv = *is_int ? (int64_t)v : 0;
      return (double)v;
    }
    case T_F32: { float v; memcpy(&v, b, 4); *is_int = 0; *iv = 0; return v; }
    default: { double v; memcpy(&v, b, 8); *is_int = 0; *iv = 0; return v; }
  }
}

/* ---- VTU ----------------------------------------------------------------- */

enum { S_OTHER = 0, S_POINTDATA, S_CELLDATA, S_POINTS, S_CELLS };

typedef struct pend {
  char *name;
  vtype type;
  int ncomp;
  uint64_t offset;
  int section;
  const unsigned char *data; /* set when located: first value byte       */
  uint64_t bytes;            /* byte count from the block's header       */
} pend;

void bs_vtu_destroy(bs_vtu **pv) {
  if (!pv || !*pv) return;
  bs_vtu *v = *pv;
  free(v->x);
  free(v->tets);
  for (int i = 0; i < v->n_point_data; i++) {
    free(v->point_data[i].name);
    free(v->point_data[i].data);
  }
  for (int i = 0; i < v->n_cell_data; i++) {
    free(v->cell_data[i].name);
    free(v->cell_data[i].data);
  }
  free(v->point_data);
  free(v->cell_data);
  free(v);
  *pv = NULL;
}

static const bs_vtu_array *find_array(const bs_vtu_array *a, int n, const char *name) {
  if (!name) return NULL;
  for (int i = 0; i < n; i++)
    if (!strcmp(a[i].name, name)) return &a[i];
  return NULL;
}

const bs_vtu_array *bs_vtu_point_array(const bs_vtu *v, const char *name) {
  return v ? find_array(v->point_data, v->n_point_data, name) : NULL;
}

const bs_vtu_array *bs_vtu_cell_array(const bs_vtu *v, const char *name) {
  return v ? find_array(v->cell_data, v->n_cell_data, name) : NULL;
}

/* Converts a located array to n doubles (bit-exact copy for native Float64). */
static void to_doubles(const pend *a, int swap, size_t n, double *out) {
  if (a->type == T_F64 && !swap) {
    memcpy(out, a->data, n * sizeof(double));
    return;
  }
  int64_t iv;
  int is_int;
  const int sz = type_size[a->type];
  for (size_t i = 0; i < n; i++) out[i] = load(a->data + i * (size_t)sz, a->type, swap, &iv, &is_int);
}

/* Integer value i of a located array; -1 in *ok when not an integer. */
static int64_t int_at(const pend *a, int swap, size_t i, int *ok) {
  int64_t iv;
  int is_int;
  double d = load(a->data + i * (size_t)type_size[a->type], a->type, swap, &iv, &is_int);
  if (is_int) {
    *ok = 1;
    return iv;
  }
  /* float types: accept exact integers */
  if (d == floor(d) && fabs(d) < 9.0e15) {
    *ok = 1;
    return (int64_t)d;
  }
  *ok = 0;
  return 0;
}

static const char *machine_order(void) {
  const uint16_t one = 1;
  unsigned char c;
  memcpy(&c, &one, 1);
  return c ? "LittleEndian" : "BigEndian";
}

static const char *section_name(int s) {
  switch (s) {
    case S_POINTDATA: return "PointData";
    case S_CELLDATA: return "CellData";
    case S_POINTS: return "Points";
    case S_CELLS: return "Cells";
    default: return "?";
  }
}

int bs_vtu_read(const char *path, bs_vtu **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "read vtu: out is NULL");
  *out = NULL;
  if (!path) return bs_error_set(err, BS_EINPUT, "read vtu: path is NULL");
  char *buf = NULL;
  size_t len = 0;
  int rc = slurp(path, "VTU file", &buf, &len, err);
  if (rc) return rc;

  const char *p = buf, *end = buf + len, *why = NULL;
  pend *arr = NULL;
  int n_arr = 0, cap_arr = 0;
  bs_vtu *v = NULL;
  char val[256];
  int seen_vtk = 0, n_piece = 0, header8 = 0, swap = 0, depth = 0;
  int64_t npts = -1, ncells = -1;
  int stack[32]; /* section of each open element */
  const unsigned char *base = NULL;

  if (len >= 3 && (unsigned char)p[0] == 0xEF && (unsigned char)p[1] == 0xBB && (unsigned char)p[2] == 0xBF) p += 3;
  while (p < end && is_space(*p)) p++;
  if (p >= end) {
    rc = bs_error_set(err, BS_EINPUT, "'%s' is empty: not a VTU file", path);
    goto fail;
  }
  if (*p != '<') {
    rc = bs_error_set(err, BS_EINPUT, "'%s' is not a VTK XML file (it does not start with '<')", path);
    goto fail;
  }
  while (!base) {
    xtag t;
    int r = next_tag(&p, end, &t, &why);
    if (r < 0) {
      rc = bs_error_set(err, BS_EINPUT, "'%s': malformed XML at byte %ld: %s", path, (long)(p - buf), why);
      goto fail;
    }
    if (r == 0) {
      rc = bs_error_set(err, BS_EINPUT,
                        seen_vtk ? "'%s' ends before its <AppendedData> block (truncated file, or arrays not "
                                   "written in appended raw form)"
                                 : "'%s' is not a VTK XML file (no <VTKFile> element)",
                        path);
      goto fail;
    }
    if (!seen_vtk && !(tag_is(&t, "VTKFile") && !t.closing)) {
      rc = bs_error_set(err, BS_EINPUT, "'%s' is not a VTK XML file (its first element is <%.*s>, not <VTKFile>)",
                        path, (int)t.name_len, t.name);
      goto fail;
    }
    if (t.closing) {
      if (depth == 0) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': unexpected </%.*s> before <AppendedData>", path, (int)t.name_len,
                          t.name);
        goto fail;
      }
      depth--;
      continue;
    }
    int section = depth > 0 ? stack[depth - 1] : S_OTHER;
    if (tag_is(&t, "VTKFile")) {
      if (seen_vtk) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': a second <VTKFile> element", path);
        goto fail;
      }
      seen_vtk = 1;
      if (attr_get(&t, "type", val, sizeof val) != 1 || strcmp(val, "UnstructuredGrid")) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': VTKFile type is '%s', expected 'UnstructuredGrid' (a .vtu file)",
                          path, attr_get(&t, "type", val, sizeof val) == 1 ? val : "(none)");
        goto fail;
      }
      int r2 = attr_get(&t, "byte_order", val, sizeof val);
      if (r2 == 1) {
        if (strcmp(val, "LittleEndian") && strcmp(val, "BigEndian")) {
          rc = bs_error_set(err, BS_EINPUT, "'%s': unknown byte_order '%s'", path, val);
          goto fail;
        }
        swap = strcmp(val, machine_order()) != 0;
      }
      header8 = 0;
      if (attr_get(&t, "header_type", val, sizeof val) == 1) {
        if (!strcmp(val, "UInt64")) header8 = 1;
        else if (strcmp(val, "UInt32")) {
          rc = bs_error_set(err, BS_EINPUT, "'%s': header_type '%s' (expected UInt64 or UInt32)", path, val);
          goto fail;
        }
      }
      if (attr_get(&t, "compressor", val, sizeof val) != 0) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': compressed data (compressor '%s') is not supported", path, val);
        goto fail;
      }
    } else if (tag_is(&t, "Piece")) {
      if (++n_piece > 1) {
        rc = bs_error_set(err, BS_EINPUT, "'%s' has more than one <Piece>; only single-piece files are read", path);
        goto fail;
      }
      char np[64], nc[64];
      if (attr_get(&t, "NumberOfPoints", np, sizeof np) != 1 || parse_i64(np, &npts) || npts < 0 ||
          npts > INT32_MAX || attr_get(&t, "NumberOfCells", nc, sizeof nc) != 1 || parse_i64(nc, &ncells) ||
          ncells < 0 || ncells > INT32_MAX) {
        rc = bs_error_set(err, BS_EINPUT,
                          "'%s': <Piece> needs NumberOfPoints and NumberOfCells, integers in [0, 2^31)", path);
        goto fail;
      }
    } else if (tag_is(&t, "DataArray")) {
      int nm = 0;
      char *name = attr_dup(&t, "Name", &nm);
      if (nm) {
        rc = bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
        goto fail;
      }
      if (!name) name = decode("", 0);
      const char *shown = name ? name : "";
      char fmt[64] = "", ty[64] = "", off[64] = "", nc[64] = "1";
      if (attr_get(&t, "format", fmt, sizeof fmt) != 1 || strcmp(fmt, "appended")) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': array '%s' has format '%s'; only format=\"appended\" is read", path,
                          shown, fmt[0] ? fmt : "(none)");
        free(name);
        goto fail;
      }
      vtype vt;
      if (attr_get(&t, "type", ty, sizeof ty) != 1 || type_parse(ty, &vt)) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': array '%s' has unknown type '%s'", path, shown, ty);
        free(name);
        goto fail;
      }
      uint64_t o;
      if (attr_get(&t, "offset", off, sizeof off) != 1 || parse_u64(off, &o)) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': array '%s' has no valid offset attribute ('%s')", path, shown, off);
        free(name);
        goto fail;
      }
      int64_t ncomp = 1;
      if (attr_get(&t, "NumberOfComponents", nc, sizeof nc) < 0 || parse_i64(nc, &ncomp) || ncomp < 1 ||
          ncomp > 1024) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': array '%s' has NumberOfComponents '%s' (expected 1..1024)", path,
                          shown, nc);
        free(name);
        goto fail;
      }
      if (n_arr == cap_arr) {
        int nc2 = cap_arr ? 2 * cap_arr : 16;
        pend *na = realloc(arr, (size_t)nc2 * sizeof *na);
        if (!na) {
          free(name);
          rc = bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
          goto fail;
        }
        arr = na;
        cap_arr = nc2;
      }
      arr[n_arr++] = (pend){name, vt, (int)ncomp, o, section, NULL, 0};
      if (!name) {
        rc = bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
        goto fail;
      }
    } else if (tag_is(&t, "AppendedData")) {
      if (attr_get(&t, "encoding", val, sizeof val) != 1 || strcmp(val, "raw")) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': AppendedData encoding is '%s'; only \"raw\" is read", path,
                          attr_get(&t, "encoding", val, sizeof val) == 1 ? val : "(none)");
        goto fail;
      }
      if (t.selfclose) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': <AppendedData/> is empty", path);
        goto fail;
      }
      const char *q = t.end;
      while (q < end && is_space(*q)) q++;
      if (q >= end || *q != '_') {
        rc = bs_error_set(err, BS_EINPUT, "'%s': the raw data after <AppendedData> does not start with '_'%s", path,
                          q >= end ? " (truncated file)" : "");
        goto fail;
      }
      base = (const unsigned char *)q + 1;
      break;
    }
    if (!t.selfclose) {
      if (depth >= (int)(sizeof stack / sizeof stack[0])) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': elements nested too deeply", path);
        goto fail;
      }
      int s = section;
      if (tag_is(&t, "PointData")) s = S_POINTDATA;
      else if (tag_is(&t, "CellData")) s = S_CELLDATA;
      else if (tag_is(&t, "Points")) s = S_POINTS;
      else if (tag_is(&t, "Cells")) s = S_CELLS;
      else if (!tag_is(&t, "DataArray")) s = S_OTHER;
      stack[depth++] = s;
    }
  }
  if (n_piece == 0) {
    rc = bs_error_set(err, BS_EINPUT, "'%s' has no <Piece>", path);
    goto fail;
  }

  /* Locate every block: header, byte count, and the data within the file. */
  const uint64_t avail = (uint64_t)((const unsigned char *)end - base);
  const uint64_t hs = header8 ? 8 : 4;
  uint64_t data_end = 0;
  for (int i = 0; i < n_arr; i++) {
    pend *a = &arr[i];
    if (a->offset > avail || avail - a->offset < hs) {
      rc = bs_error_set(err, BS_EINPUT,
                        "'%s': array '%s' (offset %llu) starts past the end of the appended data (%llu bytes): "
                        "truncated file",
                        path, a->name, (unsigned long long)a->offset, (unsigned long long)avail);
      goto fail;
    }
    unsigned char h[8];
    memcpy(h, base + a->offset, (size_t)hs);
    if (swap)
      for (uint64_t k = 0; k < hs / 2; k++) {
        unsigned char c = h[k];
        h[k] = h[hs - 1 - k];
        h[hs - 1 - k] = c;
      }
    if (header8) {
      memcpy(&a->bytes, h, 8);
    } else {
      uint32_t b32;
      memcpy(&b32, h, 4);
      a->bytes = b32;
    }
    if (a->bytes > avail - a->offset - hs) {
      rc = bs_error_set(err, BS_EINPUT,
                        "'%s': array '%s' (offset %llu, %llu bytes) runs past the end of the file (%llu bytes of "
                        "appended data): truncated file",
                        path, a->name, (unsigned long long)a->offset, (unsigned long long)a->bytes,
                        (unsigned long long)avail);
      goto fail;
    }
    a->data = base + a->offset + hs;
    if (a->offset + hs + a->bytes > data_end) data_end = a->offset + hs + a->bytes;
  }
  {
    const char *q = (const char *)base + data_end;
    while (q < end && is_space(*q)) q++;
    if ((size_t)(end - q) < 15 || memcmp(q, "</AppendedData>", 15)) {
      rc = bs_error_set(err, BS_EINPUT, "'%s': no </AppendedData> after the last array: truncated file", path);
      goto fail;
    }
    q += 15;
    while (q < end && is_space(*q)) q++;
    if ((size_t)(end - q) < 10 || memcmp(q, "</VTKFile>", 10)) {
      rc = bs_error_set(err, BS_EINPUT, "'%s': no </VTKFile> after </AppendedData>: truncated file", path);
      goto fail;
    }
  }

  /* Check each array's size against its tuples. */
  pend *pts = NULL, *conn = NULL, *offs = NULL, *types = NULL;
  int n_pd = 0, n_cd = 0;
  for (int i = 0; i < n_arr; i++) {
    pend *a = &arr[i];
    const uint64_t sz = (uint64_t)type_size[a->type];
    int64_t tuples = -1;
    if (a->section == S_POINTDATA) tuples = npts, n_pd++;
    else if (a->section == S_CELLDATA) tuples = ncells, n_cd++;
    else if (a->section == S_POINTS) {
      if (pts) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': <Points> holds more than one array", path);
        goto fail;
      }
      pts = a;
      tuples = npts;
      if (a->ncomp != 3) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': the Points array has %d components, expected 3", path, a->ncomp);
        goto fail;
      }
    } else if (a->section == S_CELLS) {
      pend **slot = !strcmp(a->name, "connectivity") ? &conn
                    : !strcmp(a->name, "offsets")    ? &offs
                    : !strcmp(a->name, "types")      ? &types
                                                     : NULL;
      if (slot) {
        if (*slot) {
          rc = bs_error_set(err, BS_EINPUT, "'%s': two Cells arrays named '%s'", path, a->name);
          goto fail;
        }
        *slot = a;
        if (a->type == T_F32 || a->type == T_F64) {
          rc = bs_error_set(err, BS_EINPUT, "'%s': Cells array '%s' has type %s, expected an integer type", path,
                            a->name, type_name[a->type]);
          goto fail;
        }
        if (slot != &conn) tuples = ncells;
      }
    }
    if (a->bytes % sz) {
      rc = bs_error_set(err, BS_EINPUT, "'%s': array '%s' holds %llu bytes, not a whole number of %s values", path,
                        a->name, (unsigned long long)a->bytes, type_name[a->type]);
      goto fail;
    }
    if (tuples >= 0 && a->bytes != (uint64_t)tuples * (uint64_t)a->ncomp * sz) {
      rc = bs_error_set(err, BS_EINPUT,
                        "'%s': %s array '%s' holds %llu bytes, expected %llu (%lld tuples x %d components of %s)",
                        path, section_name(a->section), a->name, (unsigned long long)a->bytes,
                        (unsigned long long)((uint64_t)tuples * (uint64_t)a->ncomp * sz), (long long)tuples, a->ncomp,
                        type_name[a->type]);
      goto fail;
    }
  }
  if (!pts && npts > 0) {
    rc = bs_error_set(err, BS_EINPUT, "'%s' has no Points array", path);
    goto fail;
  }
  if (ncells > 0 && (!conn || !offs || !types)) {
    rc = bs_error_set(err, BS_EINPUT, "'%s': <Cells> lacks the '%s' array", path,
                      !conn ? "connectivity" : !offs ? "offsets" : "types");
    goto fail;
  }

  v = calloc(1, sizeof *v);
  if (!v) goto nomem;
  v->n_points = (int32_t)npts;
  v->n_cells = (int32_t)ncells;
  v->x = malloc(3 * (size_t)npts * sizeof(double) + 1);
  v->tets = malloc(4 * (size_t)ncells * sizeof(int32_t) + 1);
  v->point_data = calloc((size_t)n_pd + 1, sizeof *v->point_data);
  v->cell_data = calloc((size_t)n_cd + 1, sizeof *v->cell_data);
  if (!v->x || !v->tets || !v->point_data || !v->cell_data) goto nomem;

  /* points */
  if (npts > 0) to_doubles(pts, swap, 3 * (size_t)npts, v->x);
  for (int32_t i = 0; i < v->n_points; i++) {
    const double *q = v->x + 3 * (size_t)i;
    if (!isfinite(q[0]) || !isfinite(q[1]) || !isfinite(q[2])) {
      rc = bs_error_set(err, BS_ENUMERIC, "'%s': point %d has a non-finite coordinate (%g, %g, %g)", path, i, q[0],
                        q[1], q[2]);
      goto fail;
    }
  }

  /* cells: tetrahedra only */
  if (ncells > 0) {
    const uint64_t n_conn = conn->bytes / (uint64_t)type_size[conn->type];
    int64_t prev = 0;
    for (int64_t c = 0; c < ncells; c++) {
      int ok;
      int64_t ty = int_at(types, swap, (size_t)c, &ok);
      if (!ok || ty != 10) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': cell %lld has VTK type %lld; only tetrahedra (10) are read", path,
                          (long long)c, (long long)ty);
        goto fail;
      }
      int64_t o = int_at(offs, swap, (size_t)c, &ok);
      if (!ok || o - prev != 4 || (uint64_t)o > n_conn) {
        rc = bs_error_set(err, BS_EINPUT,
                          "'%s': cell %lld ends at connectivity offset %lld after %lld (of %llu entries): expected 4 "
                          "vertices per tetrahedron",
                          path, (long long)c, (long long)o, (long long)prev, (unsigned long long)n_conn);
        goto fail;
      }
      for (int k = 0; k < 4; k++) {
        int64_t id = int_at(conn, swap, (size_t)(prev + k), &ok);
        if (!ok || id < 0 || id >= npts) {
          rc = bs_error_set(err, BS_EINPUT, "'%s': cell %lld vertex %d is %lld, outside [0, %lld)", path, (long long)c,
                            k, (long long)id, (long long)npts);
          goto fail;
        }
        v->tets[4 * c + k] = (int32_t)id;
      }
      prev = o;
    }
    if ((uint64_t)prev != n_conn) {
      rc = bs_error_set(err, BS_EINPUT, "'%s': connectivity has %llu entries but the cells use %lld", path,
                        (unsigned long long)n_conn, (long long)prev);
      goto fail;
    }
  }

  /* point and cell data */
  for (int i = 0; i < n_arr; i++) {
    pend *a = &arr[i];
    if (a->section != S_POINTDATA && a->section != S_CELLDATA) continue;
    bs_vtu_array *d = a->section == S_POINTDATA ? &v->point_data[v->n_point_data++]
                                                 : &v->cell_data[v->n_cell_data++];
    d->name = a->name;
    a->name = NULL;
    snprintf(d->type, sizeof d->type, "%s", type_name[a->type]);
    d->ncomp = a->ncomp;
    d->n_tuples = a->section == S_POINTDATA ? npts : ncells;
    size_t n = (size_t)d->n_tuples * (size_t)d->ncomp;
    d->data = malloc(n * sizeof(double) + 1);
    if (!d->data) goto nomem;
    to_doubles(a, swap, n, d->data);
  }
  const bs_vtu_array *disp = bs_vtu_point_array(v, "displacement");
  v->displacement = disp && disp->ncomp == 3 ? disp->data : NULL;

  for (int i = 0; i < n_arr; i++) free(arr[i].name);
  free(arr);
  free(buf);
  *out = v;
  return BS_OK;

nomem:
  rc = bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory", path);
fail:
  for (int i = 0; i < n_arr; i++) free(arr[i].name);
  free(arr);
  free(buf);
  bs_vtu_destroy(&v);
  return rc;
}

int bs_vtu_rest(const bs_vtu *v, const char *path, double *rest, bs_error *err) {
  const char *f = path ? path : "vtu";
  if (!v || !rest) return bs_error_set(err, BS_EINPUT, "'%s': rest positions: NULL argument", f);
  if (!v->displacement)
    return bs_error_set(err, BS_EINPUT,
                        "'%s' has no 3-component 'displacement' point data: the rest shape cannot be recovered", f);
  for (int32_t i = 0; i < v->n_points; i++)
    for (int k = 0; k < 3; k++) {
      double r = v->x[3 * (size_t)i + k] - v->displacement[3 * (size_t)i + k];
      if (!isfinite(r))
        return bs_error_set(err, BS_ENUMERIC, "'%s': point %d has a non-finite displacement or rest coordinate", f,
                            i);
      rest[3 * (size_t)i + k] = r;
    }
  return BS_OK;
}

/* ---- PVD ----------------------------------------------------------------- */

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
  char *buf = NULL;
  size_t len = 0;
  int rc = slurp(path, "PVD file", &buf, &len, err);
  if (rc) return rc;
  bs_pvd *pv = calloc(1, sizeof *pv);
  int cap = 0, seen_vtk = 0, seen_end = 0;
  const char *p = buf, *end = buf + len, *why = NULL;
  if (!pv) goto nomem;
  while (p < end && is_space(*p)) p++;
  if (p >= end || *p != '<') {
    rc = bs_error_set(err, BS_EINPUT, "'%s' is not a VTK XML file (it does not start with '<')", path);
    goto fail;
  }
  for (;;) {
    xtag t;
    int r = next_tag(&p, end, &t, &why);
    if (r < 0) {
      rc = bs_error_set(err, BS_EINPUT, "'%s': malformed XML at byte %ld: %s", path, (long)(p - buf), why);
      goto fail;
    }
    if (r == 0) break;
    if (!seen_vtk) {
      char ty[64] = "";
      if (!tag_is(&t, "VTKFile") || t.closing) {
        rc = bs_error_set(err, BS_EINPUT, "'%s' is not a VTK XML file (its first element is <%.*s>)", path,
                          (int)t.name_len, t.name);
        goto fail;
      }
      if (attr_get(&t, "type", ty, sizeof ty) != 1 || strcmp(ty, "Collection")) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': VTKFile type is '%s', expected 'Collection' (a .pvd file)", path,
                          ty[0] ? ty : "(none)");
        goto fail;
      }
      seen_vtk = 1;
      continue;
    }
    if (t.closing && tag_is(&t, "VTKFile")) seen_end = 1;
    if (t.closing || !tag_is(&t, "DataSet")) continue;
    int nm = 0;
    char *file = attr_dup(&t, "file", &nm);
    if (nm) goto nomem;
    if (!file || !file[0]) {
      free(file);
      rc = bs_error_set(err, BS_EINPUT, "'%s': DataSet entry %d has no file attribute", path, pv->n);
      goto fail;
    }
    double time = 0;
    char ts[128];
    int r2 = attr_get(&t, "timestep", ts, sizeof ts);
    if (r2 != 0) {
      char *e = NULL;
      if (r2 == 1) time = strtod(ts, &e);
      if (r2 < 0 || e == ts || *e || !isfinite(time)) {
        rc = bs_error_set(err, BS_EINPUT, "'%s': DataSet entry %d ('%s') has an invalid timestep '%s'", path, pv->n,
                          file, r2 < 0 ? "(too long)" : ts);
        free(file);
        goto fail;
      }
    }
    /* resolve against the PVD's folder */
    const char *slash = strrchr(path, '/');
    if (file[0] != '/' && slash) {
      size_t dl = (size_t)(slash - path) + 1, fl = strlen(file);
      char *full = malloc(dl + fl + 1);
      if (!full) {
        free(file);
        goto nomem;
      }
      memcpy(full, path, dl);
      memcpy(full + dl, file, fl + 1);
      free(file);
      file = full;
    }
    if (pv->n == cap) {
      int nc = cap ? 2 * cap : 16;
      char **nf = realloc(pv->files, (size_t)nc * sizeof *nf);
      if (nf) pv->files = nf;
      double *nt = realloc(pv->times, (size_t)nc * sizeof *nt);
      if (nt) pv->times = nt;
      if (!nf || !nt) {
        free(file);
        goto nomem;
      }
      cap = nc;
    }
    pv->files[pv->n] = file;
    pv->times[pv->n] = time;
    pv->n++;
  }
  if (!seen_vtk) {
    rc = bs_error_set(err, BS_EINPUT, "'%s' is not a VTK XML file (no <VTKFile> element)", path);
    goto fail;
  }
  if (!seen_end) {
    rc = bs_error_set(err, BS_EINPUT, "'%s': no </VTKFile> at the end: truncated file", path);
    goto fail;
  }
  free(buf);
  *out = pv;
  return BS_OK;

nomem:
  rc = bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory", path);
fail:
  free(buf);
  bs_pvd_destroy(&pv);
  return rc;
}
