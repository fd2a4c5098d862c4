/* msh_check.c — a .msh file checked before Gmsh parses it (bs__msh_check).
 *
 * Why: Gmsh's own .msh readers (libgmsh 4.8.4, Debian 12) trust the file.
 * Found by feeding inputs straight to gmshOpen (no check before it): in two
 * runs of 3000 mutations of the seeds of tests/data/fuzz/msh (tests/fuzz/
 * driver.c; 4 and 5 seed files), 13 and 12 inputs crashed INSIDE Gmsh with
 * SIGSEGV: an element referring to a node tag that $Nodes does not define
 * (7 and 5; v2 ASCII, v4 ASCII and binary), a v2 binary element block
 * claiming more elements than the bytes left (2 and 3), a v2 element whose
 * partition count (its third tag) exceeds the tags that follow (2, 0), a v4
 * element tag outside [minElementTag, maxElementTag] (1, 1), a v4 node tag
 * outside [minNodeTag, maxNodeTag] (1, 0), a $PhysicalNames dimension
 * outside 0..3 (0, 2), v2 element lines whose tag count does not match the
 * line (0, 1); of the 552 inputs of a 200-second libFuzzer corpus, 10
 * crashed Gmsh (the same kinds) and one kept it busy for more than 20 s on
 * a loaded machine (a v4 binary entity claiming 721420288 physical tags in a
 * 501-byte file: Gmsh loops over the count past the end of the file). Two
 * allocations sized by a count happen inside Gmsh too (the MSH4 reader): 8
 * bytes per node of a node block's numNodesInBlock and 16 bytes per element
 * of the $Elements header's numElements (4e12 gives 32 TB and 64 TB
 * requests). A duplicate node tag is resolved silently (one
 * definition is kept). Every one of those inputs is refused here, before
 * Gmsh opens the file. A later 420-second libFuzzer run found one input the
 * check accepted that crashed Gmsh (SIGSEGV in PartitionUsingThisSplit, via
 * ConvertOldPartitioningToNewOne): a v2 element with a partition tag; v2
 * partition tags are refused now. Examples
 * are kept as regression inputs in tests/data/fuzz/msh/gmsh_*.msh; the
 * diagnostic tests/fuzz/gmsh_bare.c replays inputs through bare Gmsh.
 *
 * What is accepted: MeshFormat 2.x (2.0, 2.1, 2.2) or 4.1, ASCII or binary
 * (little-endian, 8-byte doubles and size_t); the sections MeshFormat (first),
 * PhysicalNames, Entities (4.1), Nodes, Elements (at most once each) and
 * Comments; anything else (NodeData, Periodic, partitioned entities,
 * parametrizations, ...) is an error naming the section, because Gmsh would
 * parse it unchecked; so is a v2 element in a partition. Each section is parsed in full: counts, tags in range,
 * finite coordinates, known element types of the block's dimension, element
 * nodes that exist, bounding entities that exist, no tag defined twice.
 *
 * The reader works on the file mapped read-only (no copy); the only
 * allocations are the sorted tag tables, sized by counts already checked
 * against the file's size. Errors are BS_EINPUT (BS_EIO for an unreadable
 * file) naming the file, the line (ASCII) or byte offset (binary), the
 * section and the value.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bs_limits.h"
#include "mesh_internal.h"

typedef struct tag_set {
  int64_t *t;
  size_t n;
} tag_set;

typedef struct msh_in {
  const char *b; /* the mapped file */
  size_t n, pos;
  const char *path;
  bs_error *err;
  int v4, binary;
  const char *sect;  /* the section being read, for messages */
  tag_set nodes;     /* sorted node tags once $Nodes is read */
  tag_set ents[4];   /* 4.1: sorted entity tags per dimension  */
  int seen_nodes, seen_elements, seen_entities, seen_names;
} msh_in;

/* ---- errors, tokens, binary words ---------------------------------------- */

static int bad(msh_in *in, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int bad(msh_in *in, const char *fmt, ...) {
  char msg[600];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  size_t at = in->pos < in->n ? in->pos : in->n;
  if (in->binary && in->sect && strcmp(in->sect, "PhysicalNames"))
    return bs_error_set(in->err, BS_EINPUT, "%s: byte %zu: $%s: %s", in->path, at, in->sect, msg);
  size_t line = 1;
  for (size_t i = 0; i < at; i++) line += in->b[i] == '\n';
  return bs_error_set(in->err, BS_EINPUT, "%s: line %zu: %s%s%s%s", in->path, line, in->sect ? "$" : "",
                      in->sect ? in->sect : "", in->sect ? ": " : "", msg);
}

static size_t left(const msh_in *in) { return in->n - in->pos; }

static void skip_ws(msh_in *in) {
  while (in->pos < in->n && (in->b[in->pos] == ' ' || in->b[in->pos] == '\t' || in->b[in->pos] == '\r' ||
                             in->b[in->pos] == '\n'))
    in->pos++;
}

/* The next whitespace-separated token into t (NUL-terminated): its length,
 * 0 at the end of the file, -1 when longer than n - 1. */
static int token(msh_in *in, char *t, size_t n) {
  skip_ws(in);
  size_t k = 0;
  while (in->pos < in->n) {
    char c = in->b[in->pos];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') break;
    if (k + 1 >= n) return -1;
    t[k++] = c;
    in->pos++;
  }
  t[k] = '\0';
  return (int)k;
}

/* An integer in [lo, hi]: an ASCII token, or in binary a little-endian word
 * of `width` bytes (4: int, signed; 8: size_t, unsigned). */
static int rd_int(msh_in *in, int width, const char *what, int64_t lo, int64_t hi, int64_t *out) {
  int64_t v = 0;
  if (in->binary) {
    if (left(in) < (size_t)width) return bad(in, "%s: the file ends", what);
    if (width == 4) {
      int32_t w;
      memcpy(&w, in->b + in->pos, 4);
      v = w;
    } else {
      uint64_t w;
      memcpy(&w, in->b + in->pos, 8);
      if (w > (uint64_t)INT64_MAX) return bad(in, "%s = %llu is out of range", what, (unsigned long long)w);
      v = (int64_t)w;
    }
    in->pos += (size_t)width;
  } else {
    char t[48], *end = NULL;
    int k = token(in, t, sizeof t);
    if (k <= 0) return bad(in, "%s: %s", what, k == 0 ? "the file ends" : "not an integer (too long)");
    errno = 0;
    long long x = strtoll(t, &end, 10);
    if (errno || end != t + k) return bad(in, "%s = '%s' is not an integer in range", what, t);
    v = x;
  }
  if (v < lo || v > hi)
    return bad(in, "%s = %lld is out of range [%lld, %lld]", what, (long long)v, (long long)lo, (long long)hi);
  *out = v;
  return 0;
}

/* A double, finite or not: an ASCII token or 8 binary bytes. */
static int rd_f64_any(msh_in *in, const char *what, double *out) {
  double v;
  if (in->binary) {
    if (left(in) < 8) return bad(in, "%s: the file ends", what);
    memcpy(&v, in->b + in->pos, 8);
    in->pos += 8;
  } else {
    char t[64], *end = NULL;
    int k = token(in, t, sizeof t);
    if (k <= 0) return bad(in, "%s: %s", what, k == 0 ? "the file ends" : "not a number (too long)");
    v = strtod(t, &end);
    if (end != t + k) return bad(in, "%s = '%s' is not a number", what, t);
  }
  *out = v;
  return 0;
}

/* A finite double. */
static int rd_f64(msh_in *in, const char *what, double *out) {
  int rc = rd_f64_any(in, what, out);
  if (!rc && !isfinite(*out)) return bad(in, "%s = %g is not finite", what, *out);
  return rc;
}

/* The coordinates of node `tag` (3, then `extra` parametric ones): a
 * non-finite one is BS_ENUMERIC naming the node. */
static int rd_node(msh_in *in, int64_t tag, int64_t extra) {
  double x[3], u;
  int rc = 0;
  for (int k = 0; k < 3 && !rc; k++) rc = rd_f64_any(in, "node coordinate", &x[k]);
  for (int64_t k = 0; k < extra && !rc; k++) rc = rd_f64(in, "parametric node coordinate", &u);
  if (rc || (isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]))) return rc;
  bad(in, "node %lld has a non-finite coordinate (%g, %g, %g)", (long long)tag, x[0], x[1], x[2]);
  in->err->code = BS_ENUMERIC;
  return BS_ENUMERIC;
}

/* A count that must fit in the bytes left (each item at least `min_bytes`)
 * and under `limit`. */
static int rd_count(msh_in *in, int width, const char *what, size_t min_bytes, int64_t limit, int64_t *out) {
  int64_t v;
  int rc = rd_int(in, width, what, 0, INT64_MAX, &v);
  if (rc) return rc;
  if (v > limit) return bad(in, "%s = %lld exceeds bigstep's limit of %lld", what, (long long)v, (long long)limit);
  if ((uint64_t)v > left(in) / min_bytes)
    return bad(in, "%s = %lld cannot fit in the %zu bytes left in the file", what, (long long)v, left(in));
  *out = v; /* set only when valid: callers size loops with it */
  return 0;
}

/* The "$EndX" line of the current section. */
static int end_of_section(msh_in *in) {
  char t[64], want[64];
  snprintf(want, sizeof want, "$End%s", in->sect);
  int k = token(in, t, sizeof t);
  if (k <= 0 || strcmp(t, want) != 0) return bad(in, "expected %s, found '%s'", want, k > 0 ? t : "the end of the file");
  return 0;
}

/* ---- tag sets --------------------------------------------------------------- */

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

static int tags_alloc(msh_in *in, tag_set *s, int64_t n) {
  free(s->t);
  s->n = 0;
  s->t = malloc((size_t)(n > 0 ? n : 1) * sizeof *s->t);
  return s->t ? 0 : bs_error_set(in->err, BS_ENOMEM, "%s: out of memory for %lld tags", in->path, (long long)n);
}

/* Sorts the set; a tag defined twice is an error naming it. */
static int tags_sort_unique(msh_in *in, tag_set *s, const char *what) {
  qsort(s->t, s->n, sizeof *s->t, cmp_i64);
  for (size_t i = 1; i < s->n; i++)
    if (s->t[i] == s->t[i - 1])
      return bs_error_set(in->err, BS_EINPUT, "%s: $%s: %s tag %lld is defined twice", in->path, in->sect, what,
                          (long long)s->t[i]);
  return 0;
}

static int tags_has(const tag_set *s, int64_t t) {
  return s->n && bsearch(&t, s->t, s->n, sizeof *s->t, cmp_i64) != NULL;
}

/* ---- element types ------------------------------------------------------- */

/* Gmsh element types 1 .. 31: nodes per element and dimension. */
static const struct {
  int nodes, dim;
} elem_type[32] = {{0, -1}, {2, 1},  {3, 2},  {4, 2},  {4, 3},  {8, 3},  {6, 3},  {5, 3},  {3, 1},  {6, 2},  {9, 2},
                   {10, 3}, {27, 3}, {18, 3}, {14, 3}, {1, 0},  {8, 2},  {20, 3}, {15, 3}, {13, 3}, {9, 2},  {10, 2},
                   {12, 2}, {15, 2}, {15, 2}, {21, 2}, {4, 1},  {5, 1},  {6, 1},  {20, 3}, {35, 3}, {56, 3}};
enum { MAX_ELEM_TYPE = 31, MAX_V2_TAGS = 64, MAX_NAME = 200 };

/* ---- sections shared by both versions ------------------------------------ */

/* The rest of the current line (only blanks), with its newline. */
static int rest_of_line(msh_in *in) {
  while (in->pos < in->n && (in->b[in->pos] == ' ' || in->b[in->pos] == '\t' || in->b[in->pos] == '\r')) in->pos++;
  if (in->pos >= in->n || in->b[in->pos] != '\n') return bad(in, "expected the end of the line");
  in->pos++;
  return 0;
}

/* A count on an ASCII line of its own (v2 sections, binary files too). */
static int ascii_count(msh_in *in, const char *what, size_t min_bytes, int64_t limit, int64_t *out) {
  int binary = in->binary;
  in->binary = 0;
  int rc = rd_count(in, 8, what, min_bytes, limit, out);
  in->binary = binary;
  return rc ? rc : (binary ? rest_of_line(in) : 0);
}

static int mesh_format(msh_in *in) {
  char t[64];
  if (token(in, t, sizeof t) <= 0 || strcmp(t, "$MeshFormat") != 0)
    return bad(in, "not a Gmsh .msh file (it must start with $MeshFormat)");
  in->sect = "MeshFormat";
  int k = token(in, t, sizeof t);
  double v = 0;
  char *end = NULL;
  if (k > 0) v = strtod(t, &end);
  if (k <= 0 || end != t + k) return bad(in, "the format version '%s' is not a number", k > 0 ? t : "");
  if (strcmp(t, "4.1") == 0) in->v4 = 1;
  else if (!(v >= 2 && v < 3))
    return bad(in, "format version %s is not read by bigstep (it reads 2.x and 4.1: save the mesh as 4.1 or 2.2)", t);
  int64_t type, dsize;
  int rc = rd_int(in, 4, "file-type", 0, 1, &type);
  if (!rc) rc = rd_int(in, 4, "data-size", 8, 8, &dsize);
  if (rc) return rc;
  if (type == 1) {
    if ((rc = rest_of_line(in))) return rc;
    int32_t one = 0;
    if (left(in) < 4) return bad(in, "the binary file ends before its byte-order word");
    memcpy(&one, in->b + in->pos, 4);
    if (one != 1) return bad(in, "byte-order word %d is not 1 (a big-endian or corrupted binary file)", (int)one);
    in->pos += 4;
    in->binary = 1;
  }
  return end_of_section(in);
}

static int physical_names(msh_in *in) {
  int binary = in->binary, rc;
  in->binary = 0;
  int64_t n = 0, dim = 0, tag = 0;
  rc = rd_count(in, 8, "number of physical names", 7, BS_MAX_MSH_PHYSICALS, &n);
  for (int64_t i = 0; i < n && !rc; i++) {
    rc = rd_int(in, 4, "physical dimension", 0, 3, &dim);
    if (!rc) rc = rd_int(in, 4, "physical tag", -INT32_MAX, INT32_MAX, &tag);
    if (rc) break;
    skip_ws(in);
    if (in->pos >= in->n || in->b[in->pos] != '"') {
      rc = bad(in, "the name of physical group %lld is not in double quotes", (long long)tag);
      break;
    }
    size_t s = ++in->pos;
    while (in->pos < in->n && in->b[in->pos] != '"' && in->b[in->pos] != '\n') in->pos++;
    if (in->pos >= in->n || in->b[in->pos] != '"') rc = bad(in, "the name of physical group %lld has no closing quote", (long long)tag);
    else if (in->pos - s > MAX_NAME) rc = bad(in, "the name of physical group %lld is longer than %d characters", (long long)tag, MAX_NAME);
    else in->pos++;
  }
  if (!rc) rc = end_of_section(in);
  in->binary = binary;
  return rc;
}

/* An element's nodes: each a defined node tag. */
static int element_nodes(msh_in *in, int width, int64_t etag, int nn) {
  int64_t v;
  for (int j = 0; j < nn; j++) {
    int rc = rd_int(in, width, "element node tag", 1, INT64_MAX, &v);
    if (rc) return rc;
    if (!tags_has(&in->nodes, v))
      return bad(in, "element %lld refers to node %lld, which is not defined", (long long)etag, (long long)v);
  }
  return 0;
}

/* A Gmsh element type bigstep knows (1 .. 31: every Lagrange line,
 * triangle, quadrangle, tet, hex, prism, pyramid of order <= 5 Gmsh writes
 * by default). */
static int element_type(msh_in *in, int64_t *type) {
  return rd_int(in, 4, "element type (Gmsh types 1 to 31)", 1, MAX_ELEM_TYPE, type);
}

/* ---- version 4.1 ---------------------------------------------------------- */

static int entity4(msh_in *in, int d) {
  int64_t tag = 0, np = 0, nb = 0, v = 0;
  double x;
  int rc = rd_int(in, 4, "entity tag", 1, INT32_MAX, &tag);
  for (int k = 0; k < (d == 0 ? 3 : 6) && !rc; k++) rc = rd_f64(in, "entity coordinate", &x);
  if (!rc) rc = rd_count(in, 8, "number of physical tags", 2, BS_MAX_MSH_PHYSICALS, &np);
  for (int64_t i = 0; i < np && !rc; i++) rc = rd_int(in, 4, "physical tag", -INT32_MAX, INT32_MAX, &v);
  if (!rc && d > 0) {
    rc = rd_count(in, 8, "number of bounding entities", 2, BS_MAX_MSH_ENTITIES, &nb);
    for (int64_t i = 0; i < nb && !rc; i++) {
      rc = rd_int(in, 4, "bounding entity tag", -INT32_MAX, INT32_MAX, &v);
      if (!rc && !tags_has(&in->ents[d - 1], v < 0 ? -v : v))
        rc = bad(in, "entity %lld of dimension %d is bounded by entity %lld of dimension %d, which is not defined",
                 (long long)tag, d, (long long)v, d - 1);
    }
  }
  if (!rc) in->ents[d].t[in->ents[d].n++] = tag;
  return rc;
}

static int entities4(msh_in *in) {
  int64_t cnt[4] = {0};
  int rc = 0;
  for (int d = 0; d < 4 && !rc; d++) rc = rd_count(in, 8, "number of entities", 8, BS_MAX_MSH_ENTITIES, &cnt[d]);
  for (int d = 0; d < 4 && !rc; d++) {
    if ((rc = tags_alloc(in, &in->ents[d], cnt[d]))) break;
    for (int64_t i = 0; i < cnt[d] && !rc; i++) rc = entity4(in, d);
    if (!rc) rc = tags_sort_unique(in, &in->ents[d], d == 0 ? "point entity" : d == 1 ? "curve entity" : d == 2 ? "surface entity" : "volume entity");
  }
  return rc ? rc : end_of_section(in);
}

/* The (dimension, tag) of a 4.1 node or element block: an entity of $Entities. */
static int block_entity(msh_in *in, int64_t *dim) {
  int64_t tag;
  int rc = rd_int(in, 4, "entity dimension", 0, 3, dim);
  if (!rc) rc = rd_int(in, 4, "entity tag", 1, INT32_MAX, &tag);
  if (!rc && !tags_has(&in->ents[*dim], tag))
    rc = bad(in, "block of entity %lld of dimension %lld, which $Entities does not define", (long long)tag, (long long)*dim);
  return rc;
}

/* The header's number of items and [min, max] tag range. */
static int block_header4(msh_in *in, const char *what, int64_t limit, int64_t *nb, int64_t *n, int64_t *lo, int64_t *hi) {
  char w[96];
  snprintf(w, sizeof w, "number of %s", what);
  int rc = rd_count(in, 8, "number of entity blocks", 8, limit, nb);
  if (!rc) rc = rd_count(in, 8, w, 4, limit, n);
  if (!rc) rc = rd_int(in, 8, "minimum tag", 0, INT64_MAX, lo);
  if (!rc) rc = rd_int(in, 8, "maximum tag", 0, INT64_MAX, hi);
  if (!rc && *n > 0 && (*lo < 1 || *hi < *lo || (uint64_t)(*hi - *lo) < (uint64_t)(*n - 1)))
    rc = bad(in, "the tag range [%lld, %lld] cannot hold %lld %s with distinct positive tags", (long long)*lo,
             (long long)*hi, (long long)*n, what);
  return rc;
}

static int node_block4(msh_in *in, int64_t nn, int64_t lo, int64_t hi) {
  int64_t dim, par = 0, k = 0, t;
  int rc = block_entity(in, &dim);
  if (!rc) rc = rd_int(in, 4, "parametric flag (1 only on curves and surfaces)", 0, (dim == 1 || dim == 2), &par);
  if (!rc) rc = rd_count(in, 8, "number of nodes in the block", 8, BS_MAX_VERTICES, &k);
  if (!rc && k > nn - (int64_t)in->nodes.n) rc = bad(in, "the blocks hold more nodes than the header's %lld", (long long)nn);
  for (int64_t i = 0; i < k && !rc; i++)
    if (!(rc = rd_int(in, 8, "node tag (in the header's range)", lo, hi, &t))) in->nodes.t[in->nodes.n++] = t;
  if (rc) return rc;
  const int64_t *tags = in->nodes.t + in->nodes.n - k; /* this block's, in file order */
  for (int64_t i = 0; i < k && !rc; i++) rc = rd_node(in, tags[i], par ? dim : 0);
  return rc;
}

static int nodes4(msh_in *in) {
  int64_t nb = 0, nn = 0, lo = 0, hi = 0;
  int rc = block_header4(in, "nodes", BS_MAX_VERTICES, &nb, &nn, &lo, &hi);
  if (!rc) rc = tags_alloc(in, &in->nodes, nn);
  for (int64_t b = 0; b < nb && !rc; b++) rc = node_block4(in, nn, lo, hi);
  if (!rc && (int64_t)in->nodes.n != nn)
    rc = bad(in, "the blocks hold %zu nodes, the header says %lld", in->nodes.n, (long long)nn);
  if (!rc) rc = tags_sort_unique(in, &in->nodes, "node");
  return rc ? rc : end_of_section(in);
}

static int element_block4(msh_in *in, tag_set *et, int64_t ne, int64_t lo, int64_t hi) {
  int64_t dim = 0, type = 0, k = 0, t = 0;
  int rc = block_entity(in, &dim);
  if (!rc) rc = element_type(in, &type);
  if (!rc && elem_type[type].dim != dim)
    rc = bad(in, "element type %lld is %d-D, in a block of dimension %lld", (long long)type, elem_type[type].dim, (long long)dim);
  if (!rc) rc = rd_count(in, 8, "number of elements in the block", 4, BS_MAX_ELEMENTS, &k);
  if (!rc && k > ne - (int64_t)et->n) rc = bad(in, "the blocks hold more elements than the header's %lld", (long long)ne);
  for (int64_t i = 0; i < k && !rc; i++) {
    if ((rc = rd_int(in, 8, "element tag (in the header's range)", lo, hi, &t))) break;
    et->t[et->n++] = t;
    rc = element_nodes(in, 8, t, elem_type[type].nodes);
  }
  return rc;
}

static int elements4(msh_in *in) {
  int64_t nb = 0, ne = 0, lo = 0, hi = 0;
  tag_set et = {0};
  int rc = block_header4(in, "elements", BS_MAX_ELEMENTS, &nb, &ne, &lo, &hi);
  if (!rc) rc = tags_alloc(in, &et, ne);
  for (int64_t b = 0; b < nb && !rc; b++) rc = element_block4(in, &et, ne, lo, hi);
  if (!rc && (int64_t)et.n != ne) rc = bad(in, "the blocks hold %zu elements, the header says %lld", et.n, (long long)ne);
  if (!rc) rc = tags_sort_unique(in, &et, "element");
  free(et.t);
  return rc ? rc : end_of_section(in);
}

/* ---- version 2 ------------------------------------------------------------- */

static int nodes2(msh_in *in) {
  int64_t nn = 0, t = 0;
  int rc = ascii_count(in, "number of nodes", 8, BS_MAX_VERTICES, &nn);
  if (!rc) rc = tags_alloc(in, &in->nodes, nn);
  for (int64_t i = 0; i < nn && !rc; i++) {
    if ((rc = rd_int(in, 4, "node tag", 1, INT32_MAX, &t))) break;
    in->nodes.t[in->nodes.n++] = t;
    rc = rd_node(in, t, 0);
  }
  if (!rc) rc = tags_sort_unique(in, &in->nodes, "node");
  return rc ? rc : end_of_section(in);
}

/* The tags of a v2 element (physical, elementary, partitions...): the third
 * tag counts the element's partitions and must be 0 (Gmsh converts a v2
 * partitioning when it reads one, and crashed doing it on a fuzzed file). */
static int element_tags2(msh_in *in, int64_t etag, int64_t ntags) {
  int64_t v;
  for (int64_t j = 0; j < ntags; j++) {
    int rc = rd_int(in, 4, "element tag value", -INT32_MAX, INT32_MAX, &v);
    if (rc) return rc;
    if (j == 2 && v != 0)
      return bad(in, "element %lld lists %lld partitions: partitioned meshes are not read by bigstep", (long long)etag,
                 (long long)v);
  }
  return 0;
}

/* One v2 element after its type and number of tags are known. */
static int element2(msh_in *in, tag_set *et, int64_t t, int64_t type, int64_t ntags) {
  et->t[et->n++] = t;
  int rc = element_tags2(in, t, ntags);
  return rc ? rc : element_nodes(in, 4, t, elem_type[type].nodes);
}

static int elements2_ascii(msh_in *in, tag_set *et, int64_t ne) {
  int64_t t = 0, type = 0, ntags = 0;
  int rc = 0;
  for (int64_t i = 0; i < ne && !rc; i++) {
    rc = rd_int(in, 4, "element tag", 1, INT32_MAX, &t);
    if (!rc) rc = element_type(in, &type);
    if (!rc) rc = rd_int(in, 4, "number of element tags", 0, MAX_V2_TAGS, &ntags);
    if (!rc) rc = element2(in, et, t, type, ntags);
  }
  return rc;
}

/* Binary v2: blocks of (type, number of elements, number of tags). */
static int elements2_binary(msh_in *in, tag_set *et, int64_t ne) {
  int64_t type, k = 0, ntags = 0, t;
  int rc = 0;
  while ((int64_t)et->n < ne && !rc) {
    rc = element_type(in, &type);
    if (!rc) rc = rd_int(in, 4, "number of elements in the block", 1, ne - (int64_t)et->n, &k);
    if (!rc) rc = rd_int(in, 4, "number of element tags", 0, MAX_V2_TAGS, &ntags);
    if (!rc && (uint64_t)k > left(in) / (4 * (size_t)(1 + ntags + elem_type[type].nodes)))
      rc = bad(in, "a block of %lld elements cannot fit in the %zu bytes left", (long long)k, left(in));
    for (int64_t i = 0; i < k && !rc; i++) {
      rc = rd_int(in, 4, "element tag", 1, INT32_MAX, &t);
      if (!rc) rc = element2(in, et, t, type, ntags);
    }
  }
  return rc;
}

static int elements2(msh_in *in) {
  int64_t ne = 0;
  tag_set et = {0};
  int rc = ascii_count(in, "number of elements", 4, BS_MAX_ELEMENTS, &ne);
  if (!rc) rc = tags_alloc(in, &et, ne);
  if (!rc) rc = in->binary ? elements2_binary(in, &et, ne) : elements2_ascii(in, &et, ne);
  if (!rc) rc = tags_sort_unique(in, &et, "element");
  free(et.t);
  return rc ? rc : end_of_section(in);
}

/* ---- the file ---------------------------------------------------------------- */

static int skip_comments(msh_in *in) {
  char t[64];
  int k;
  while ((k = token(in, t, sizeof t)) != 0)
    if (k > 0 && strcmp(t, "$EndComments") == 0) return 0;
  return bad(in, "no $EndComments");
}

static int section(msh_in *in, const char *name) {
  static const char *const names[] = {"PhysicalNames", "Entities", "Nodes", "Elements", "Comments"};
  int *seen[] = {&in->seen_names, &in->seen_entities, &in->seen_nodes, &in->seen_elements, NULL};
  int s = 0;
  while (s < 5 && strcmp(name, names[s]) != 0) s++;
  if (s == 5)
    return bad(in, "section $%.40s is not read by bigstep (it reads $MeshFormat, $PhysicalNames, $Entities, $Nodes, "
               "$Elements and $Comments)", name);
  in->sect = names[s];
  if (s == 4) return skip_comments(in);
  if (*seen[s]) return bad(in, "the section appears twice");
  *seen[s] = 1;
  if (s == 1 && !in->v4) return bad(in, "a version 2 file has no $Entities section");
  if (s == 2 && in->v4 && !in->seen_entities) return bad(in, "$Entities must come before $Nodes");
  if (s == 3 && !in->seen_nodes) return bad(in, "$Nodes must come before $Elements");
  int rc = (in->binary && in->v4 && s > 0) ? rest_of_line(in) : 0; /* binary data start on the next line */
  if (rc) return rc;
  switch (s) {
  case 0: return physical_names(in);
  case 1: return entities4(in);
  case 2: return in->v4 ? nodes4(in) : nodes2(in);
  default: return in->v4 ? elements4(in) : elements2(in);
  }
}

static int check_all(msh_in *in) {
  int rc = mesh_format(in);
  char t[64];
  int k;
  while (!rc && (k = token(in, t, sizeof t)) != 0) {
    in->sect = NULL;
    if (k < 0 || t[0] != '$') return bad(in, "expected a section ($Name), found '%.20s'", t);
    rc = section(in, t + 1);
  }
  in->sect = NULL;
  if (!rc && (!in->seen_nodes || !in->seen_elements))
    rc = bad(in, "the file has no $%s section", in->seen_nodes ? "Elements" : "Nodes");
  return rc;
}

int bs__msh_check(const char *path, bs_error *err) {
  int fd = open(path, O_RDONLY);
  if (fd < 0) return bs_error_set(err, BS_EIO, "%s: cannot open the mesh file: %s", path, strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    return bs_error_set(err, BS_EIO, "%s: not a regular file", path);
  }
  if (st.st_size == 0) {
    close(fd);
    return bs_error_set(err, BS_EINPUT, "%s: the file is empty", path);
  }
  void *map = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE, fd, 0);
  close(fd);
  if (map == MAP_FAILED) return bs_error_set(err, BS_EIO, "%s: cannot map the mesh file: %s", path, strerror(errno));
  msh_in in = {.b = map, .n = (size_t)st.st_size, .path = path, .err = err};
  int rc = check_all(&in);
  munmap(map, (size_t)st.st_size);
  free(in.nodes.t);
  for (int d = 0; d < 4; d++) free(in.ents[d].t);
  return rc;
}
