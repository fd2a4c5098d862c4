#define _POSIX_C_SOURCE 200809L
/* The VTU reader on what ParaView and meshio write (tests/data/vtu/, made by
 * tests/data/vtu/make.sh from one bigstep frame): every re-saved file reads
 * to the same points, tets and arrays as bigstep's own, and `bigstep check`
 * counts the same on them; malformed files (a huge NumberOfPoints, a
 * truncated block, bad base64, a zlib block of the wrong size, a non-finite
 * point, an out-of-range vertex, a missing closing tag, ...) each give an
 * error naming the file and what is wrong. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_vtu_read.h"
#include "cli_util.h"
#include "vtu_internal.h"

#define DATA BS_SOURCE_DIR "/tests/data/vtu/"

static char dir[64];

static void make_dir(void) {
  strcpy(dir, "/tmp/bs_test_vtu_read_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
}

static void remove_dir(void) {
  if (dir[0]) {
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    (void)!system(cmd);
  }
}

TestSuite(vtu_read, .init = make_dir, .fini = remove_dir);

static bs_vtu *read_ok(const char *path) {
  bs_vtu *v = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_vtu_read(path, &v, &err), BS_OK, "%s", err.msg);
  cr_assert_not_null(v);
  return v;
}

/* ---- re-saved files read the same ---------------------------------------------- */

/* |a - b| <= tol max(|b|, 1) for n values; tol < 0: a == (float)b. */
static void expect_close(const double *a, const double *b, size_t n, double tol, const char *file, const char *what) {
  for (size_t i = 0; i < n; i++) {
    const int ok = tol < 0 ? a[i] == (double)(float)b[i] : fabs(a[i] - b[i]) <= tol * fmax(fabs(b[i]), 1.0);
    cr_assert(ok, "%s: %s[%zu] = %.17g, bigstep.vtu has %.17g", file, what, i, a[i], b[i]);
  }
}

static void expect_array(const bs_vtu *v, const bs_vtu *ref, int cell, const char *name, double tol,
                         const char *file) {
  const bs_vtu_array *a = cell ? bs_vtu_cell_array(v, name) : bs_vtu_point_array(v, name);
  const bs_vtu_array *r = cell ? bs_vtu_cell_array(ref, name) : bs_vtu_point_array(ref, name);
  cr_assert_not_null(r, "bigstep.vtu has no %s", name);
  cr_assert_not_null(a, "%s has no %s array '%s'", file, cell ? "cell" : "point", name);
  cr_assert_eq(a->ncomp, r->ncomp, "%s: %s", file, name);
  cr_assert_eq(a->n_tuples, r->n_tuples, "%s: %s", file, name);
  expect_close(a->data, r->data, (size_t)(a->ncomp * a->n_tuples), tol, file, name);
}

Test(vtu_read, resaved_files_read_as_the_original) {
  static const struct {
    const char *file;
    double tol_x, tol; /* points, the other arrays (0 exact, -1 Float32) */
  } files[] = {
      {"bigstep_be32.vtu", 0, 0},          {"meshio_zlib.vtu", 0, 0},
      {"meshio_binary.vtu", 0, 0},         {"meshio_ascii.vtu", 1e-11, 1e-11},
      {"meshio_float32.vtu", -1, 0},       {"paraview_ascii.vtu", 0, 0},
      {"paraview_binary_zlib.vtu", 0, 0},  {"paraview_appended.vtu", 0, 0},
      {"paraview_appended_zlib.vtu", 0, 0}, {"paraview_appended_base64_zlib.vtu", 0, 0},
  };
  bs_vtu *ref = read_ok(DATA "bigstep.vtu");
  cr_assert_eq(ref->n_points, 100);
  cr_assert_eq(ref->n_cells, 288);
  const double *detF = bs_vtu_cell_array(ref, "detF")->data;
  cr_assert(detF[0] != 1.0, "the frame is deformed");
  for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
    char path[512];
    snprintf(path, sizeof path, DATA "%s", files[f].file);
    bs_vtu *v = read_ok(path);
    cr_assert_eq(v->n_points, ref->n_points, "%s", path);
    cr_assert_eq(v->n_cells, ref->n_cells, "%s", path);
    cr_assert_eq(memcmp(v->tets, ref->tets, 4 * (size_t)ref->n_cells * sizeof(int32_t)), 0, "%s: tets differ", path);
    expect_close(v->x, ref->x, 3 * (size_t)ref->n_points, files[f].tol_x, path, "Points");
    cr_assert_not_null(v->displacement, "%s", path);
    expect_array(v, ref, 0, "displacement", files[f].tol, path);
    expect_array(v, ref, 0, "velocity", files[f].tol, path);
    expect_array(v, ref, 1, "detF", files[f].tol, path);
    expect_array(v, ref, 1, "material", 0, path);
    expect_array(v, ref, 1, "inverted", 0, path);
    bs_vtu_destroy(&v);
  }
  bs_vtu_destroy(&ref);
}

/* ---- bigstep check on re-saved files --------------------------------------------- */

typedef struct counts {
  int tets, inverted;
  long long pairs;
  int status;
} counts;

static counts check(const char *file) {
  char cmd[1024], *out;
  snprintf(cmd, sizeof cmd, "%s check %s%s", BS_BIGSTEP_EXE, DATA, file);
  counts c = {0};
  c.status = bs_test_run(cmd, &out);
  /* the frame's row: frame, time, tets, inverted, self_pairs, ... file */
  int found = 0;
  for (const char *p = out; !found && (p = strstr(p, file)); p += strlen(file)) {
    const char *ls = p;
    while (ls > out && ls[-1] != '\n') ls--;
    int frame;
    char time[32];
    found = sscanf(ls, "%d %31s %d %d %lld", &frame, time, &c.tets, &c.inverted, &c.pairs) == 5;
  }
  cr_assert(found, "no row for %s in: %s", file, out);
  free(out);
  return c;
}

Test(vtu_read, check_counts_the_same_on_resaved_files) {
  const counts ref = check("bigstep_pushed.vtu");
  cr_assert_eq(ref.status, 1, "problems found: exit 1");
  cr_assert_eq(ref.tets, 288);
  cr_assert_gt(ref.inverted, 0);
  cr_assert_gt(ref.pairs, 0);
  const char *pushed[] = {"meshio_pushed_zlib.vtu", "paraview_pushed_appended_zlib.vtu"};
  for (int i = 0; i < 2; i++) {
    counts c = check(pushed[i]);
    cr_assert(c.status == ref.status && c.tets == ref.tets && c.inverted == ref.inverted && c.pairs == ref.pairs,
              "%s: exit %d, %d tets, %d inverted, %lld pairs; bigstep_pushed.vtu: exit %d, %d, %d, %lld", pushed[i],
              c.status, c.tets, c.inverted, c.pairs, ref.status, ref.tets, ref.inverted, ref.pairs);
  }
  const char *clean[] = {"bigstep.vtu", "meshio_zlib.vtu", "paraview_binary_zlib.vtu", "paraview_appended_zlib.vtu"};
  for (int i = 0; i < 4; i++) {
    counts c = check(clean[i]);
    cr_assert(c.status == 0 && c.tets == 288 && c.inverted == 0 && c.pairs == 0, "%s: exit %d, %d tets, %d, %lld",
              clean[i], c.status, c.tets, c.inverted, c.pairs);
  }
}

/* ---- malformed files --------------------------------------------------------------- */

typedef struct buf {
  char *s;
  size_t n;
} buf;

static buf load(const char *name) {
  char path[512];
  snprintf(path, sizeof path, DATA "%s", name);
  FILE *fp = fopen(path, "rb");
  cr_assert_not_null(fp, "%s", path);
  buf b = {malloc(1 << 20), 0};
  b.n = fread(b.s, 1, 1 << 20, fp);
  fclose(fp);
  cr_assert_lt(b.n, (size_t)1 << 20);
  b.s[b.n] = '\0';
  return b;
}

static const char *find(const buf *b, const char *s, size_t from) {
  size_t n = strlen(s);
  for (size_t i = from; i + n <= b->n; i++)
    if (!memcmp(b->s + i, s, n)) return b->s + i;
  cr_assert_fail("'%s' not found", s);
  return NULL;
}

/* Replaces the first `old` (at or after `from`) with `new`. */
static void replace(buf *b, const char *old, const char *new, size_t from) {
  char *p = (char *)find(b, old, from);
  size_t at = (size_t)(p - b->s), ol = strlen(old), nl = strlen(new);
  cr_assert_lt(b->n + nl, (size_t)1 << 20);
  memmove(b->s + at + nl, b->s + at + ol, b->n - at - ol + 1);
  memcpy(b->s + at, new, nl);
  b->n = b->n + nl - ol;
}

/* The first byte of array `name`'s appended block (its header). */
static unsigned char *block(buf *b, const char *name) {
  char key[64];
  snprintf(key, sizeof key, "Name=\"%s\"", name);
  const char *a = find(b, key, 0), *o = find(b, "offset=\"", (size_t)(a - b->s));
  const char *us = strchr(find(b, "<AppendedData", 0), '_');
  return (unsigned char *)us + 1 + strtoull(o + 8, NULL, 10);
}

/* Writes b as `name` in the test folder, reads it: the status must be
 * `code` and the message must name the file and hold each of the phrases. */
static void expect_error(buf *b, const char *name, int code, const char *phrase1, const char *phrase2) {
  char path[256];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *fp = fopen(path, "wb");
  cr_assert_not_null(fp);
  cr_assert_eq(fwrite(b->s, 1, b->n, fp), b->n);
  fclose(fp);
  free(b->s);
  bs_vtu *v = NULL;
  bs_error err = {0};
  int rc = bs_vtu_read(path, &v, &err);
  cr_assert_eq(rc, code, "%s: status %d (%s), expected %d", name, rc, err.msg, code);
  cr_assert_null(v);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, phrase1), "%s: '%s' not in: %s", name, phrase1, err.msg);
  if (phrase2) cr_assert_not_null(strstr(err.msg, phrase2), "%s: '%s' not in: %s", name, phrase2, err.msg);
}

Test(vtu_read, huge_counts_are_refused_before_allocating) {
  buf b = load("bigstep.vtu"); /* raw: 50000000 x 3 x 8 bytes claimed, 2400 there */
  replace(&b, "NumberOfPoints=\"100\"", "NumberOfPoints=\"50000000\"", 0);
  expect_error(&b, "huge_raw.vtu", BS_EINPUT, "Points array 'Points' (50000000 x 3 Float64)",
               "expected 1200000000");
  b = load("meshio_zlib.vtu");
  replace(&b, "NumberOfPoints=\"100\"", "NumberOfPoints=\"50000000\"", 0);
  expect_error(&b, "huge_zlib.vtu", BS_EINPUT, "holds 2400 bytes (uncompressed), expected 1200000000", NULL);
  b = load("meshio_ascii.vtu");
  replace(&b, "NumberOfPoints=\"100\"", "NumberOfPoints=\"50000000\"", 0);
  expect_error(&b, "huge_ascii.vtu", BS_EINPUT, "hold at most", "expected 150000000");
  b = load("paraview_appended_zlib.vtu"); /* the types must hold the cells before tets are allocated */
  replace(&b, "NumberOfCells=\"288\"", "NumberOfCells=\"400000000\"", 0);
  expect_error(&b, "huge_cells_zlib.vtu", BS_EINPUT, "Cells array 'types' (400000000 x 1 UInt8)",
               "holds 288 bytes (uncompressed), expected 400000000");
  b = load("bigstep.vtu");
  replace(&b, "NumberOfCells=\"288\"", "NumberOfCells=\"4294967296\"", 0);
  expect_error(&b, "huge_cells.vtu", BS_EINPUT, "NumberOfCells is '4294967296'", "[0, 500000000] (bigstep's limit)");
  b = load("bigstep.vtu"); /* above the limit, whatever the file holds */
  replace(&b, "NumberOfPoints=\"100\"", "NumberOfPoints=\"100000001\"", 0);
  expect_error(&b, "over_limit.vtu", BS_EINPUT, "NumberOfPoints is '100000001'", "[0, 100000000] (bigstep's limit)");
}

Test(vtu_read, truncated_blocks) {
  /* raw: 200 bytes cut out before the closing tags, inside 'types' */
  buf b = load("bigstep.vtu");
  const size_t tail = strlen("\n  </AppendedData>\n</VTKFile>\n");
  memmove(b.s + b.n - tail - 200, b.s + b.n - tail, tail + 1);
  b.n -= 200;
  expect_error(&b, "cut_raw.vtu", BS_EINPUT, "Cells array 'types'", "truncated");
  /* zlib, raw appended: the last block's compressed bytes cut */
  b = load("paraview_appended_zlib.vtu");
  memmove(b.s + b.n - tail - 5, b.s + b.n - tail, tail + 1);
  b.n -= 5;
  expect_error(&b, "cut_zlib.vtu", BS_EINPUT, "runs past the end of the data", "truncated");
  /* the file itself cut short */
  b = load("paraview_appended_base64_zlib.vtu");
  b.n -= 40;
  expect_error(&b, "cut_file.vtu", BS_EINPUT, "does not end with </VTKFile>", "truncated");
}

Test(vtu_read, bad_base64) {
  buf b = load("meshio_zlib.vtu");
  char *p = (char *)find(&b, "Name=\"Points\"", 0);
  p = strchr(p, '>') + 1;
  while (*p == ' ' || *p == '\n') p++;
  p[30] = '*';
  expect_error(&b, "b64_char.vtu", BS_EINPUT, "Points array 'Points'", "bad base64");
  b = load("paraview_binary_zlib.vtu");
  p = strchr((char *)find(&b, "Name=\"detF\"", 0), '>') + 1;
  while (*p == ' ' || *p == '\n') p++;
  p[1] = '=';
  expect_error(&b, "b64_pad.vtu", BS_EINPUT, "CellData array 'detF'", "'=' in the first half of a group");
}

Test(vtu_read, zlib_block_of_the_wrong_size) {
  /* ParaView's raw appended zlib, UInt64 words [nblocks, size, last, csize 0] */
  buf b = load("paraview_appended_zlib.vtu");
  uint64_t h[4];
  unsigned char *blk = block(&b, "Points");
  memcpy(h, blk, sizeof h);
  cr_assert_eq(h[0], 1);
  h[3] -= 4; /* compressed size too small: the zlib stream is cut */
  memcpy(blk, h, sizeof h);
  expect_error(&b, "zlib_csize.vtu", BS_EINPUT, "Points array 'Points'", "zlib block 0 of 1");
  b = load("paraview_appended_zlib.vtu");
  blk = block(&b, "Points");
  memcpy(h, blk, sizeof h);
  h[2] += 8; /* uncompressed size larger than Points holds */
  memcpy(blk, h, sizeof h);
  expect_error(&b, "zlib_usize.vtu", BS_EINPUT, "holds 2408 bytes (uncompressed), expected 2400", NULL);
  b = load("paraview_appended_zlib.vtu");
  blk = block(&b, "detF");
  blk[4 * 8 + 6] ^= 0x55; /* a corrupt deflate stream */
  expect_error(&b, "zlib_data.vtu", BS_EINPUT, "CellData array 'detF'", "zlib block 0 of 1");
}

Test(vtu_read, non_finite_point_and_bad_connectivity) {
  buf b = load("bigstep.vtu");
  const double nan = NAN;
  memcpy(block(&b, "Points") + 8 + 3 * 8 * 7 + 8, &nan, 8); /* point 7, y */
  expect_error(&b, "nan.vtu", BS_ENUMERIC, "point 7 has a non-finite coordinate", NULL);
  b = load("meshio_ascii.vtu");
  size_t at = (size_t)(strchr(find(&b, "Name=\"Points\"", 0), '>') - b.s);
  replace(&b, "e", "x", at); /* the first value: -5.00000000000x-01 */
  expect_error(&b, "garbage_ascii.vtu", BS_EINPUT, "Points array 'Points'", "is not a number of type Float64");
  b = load("meshio_ascii.vtu");
  replace(&b, "-5.00000000000e-01", "nan", at);
  expect_error(&b, "nan_ascii.vtu", BS_ENUMERIC, "point 0 has a non-finite coordinate", NULL);
  b = load("bigstep.vtu");
  const int64_t id = 100;
  memcpy(block(&b, "connectivity") + 8 + 8 * 5, &id, 8); /* cell 1, vertex 1 */
  expect_error(&b, "conn.vtu", BS_EINPUT, "cell 1 vertex 1 is 100, outside [0, 100)", NULL);
  b = load("paraview_appended.vtu");
  unsigned char *t = block(&b, "types");
  t[8 + 287] = 5; /* a triangle */
  expect_error(&b, "triangle.vtu", BS_EINPUT, "cell 287 has VTK type 5; only tetrahedra (10) and quadratic tetrahedra (24) are read", NULL);
  b = load("paraview_appended.vtu");
  t = block(&b, "types");
  t[8 + 3] = 24; /* one quadratic tetra among linear ones */
  expect_error(&b, "mixed.vtu", BS_EINPUT, "cell 3 has VTK type 24 but cell 0 has type 10", NULL);
}

Test(vtu_read, missing_closing_tags_and_unsupported_forms) {
  buf b = load("meshio_ascii.vtu");
  replace(&b, "</Points>", "", 0);
  expect_error(&b, "no_points_end.vtu", BS_EINPUT, "malformed XML at line", "mismatched tag");
  b = load("bigstep.vtu");
  replace(&b, "</UnstructuredGrid>", "", 0);
  expect_error(&b, "no_grid_end.vtu", BS_EINPUT, "<AppendedData> inside <UnstructuredGrid>", "missing");
  b = load("meshio_zlib.vtu");
  replace(&b, "</VTKFile>", "", 0);
  expect_error(&b, "no_end.vtu", BS_EINPUT, "malformed XML", "truncated");
  b = load("meshio_zlib.vtu");
  replace(&b, "vtkZLibDataCompressor", "vtkLZ4DataCompressor", 0);
  expect_error(&b, "lz4.vtu", BS_EINPUT, "compressor 'vtkLZ4DataCompressor' is not read", NULL);
  b = load("meshio_zlib.vtu");
  replace(&b, "format=\"binary\"", "format=\"hex\"", 0);
  expect_error(&b, "hex.vtu", BS_EINPUT, "has format 'hex'", NULL);
  b = load("bigstep.vtu");
  replace(&b, "<AppendedData encoding=\"raw\">\n   _", "<AppendedData encoding=\"raw\">\n   ", 0);
  expect_error(&b, "no_underscore.vtu", BS_EINPUT, "does not start with '_'", NULL);
}

/* Corrupted bytes anywhere (bit flips, XML punctuation, random bytes, a cut
 * file) in each form: the reader returns OK or an error naming the file,
 * never crashes (the sanitizer build checks the memory accesses). */
Test(vtu_read, corrupted_bytes_give_errors_not_crashes) {
  static const char *const files[] = {"bigstep.vtu", "meshio_zlib.vtu", "meshio_ascii.vtu",
                                      "paraview_appended_base64_zlib.vtu", "paraview_appended_zlib.vtu"};
  char path[256];
  snprintf(path, sizeof path, "%s/mutant.vtu", dir);
  uint32_t seed = 12345;
  int errors = 0, reads = 0;
  for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
    buf b = load(files[f]);
    char *m = malloc(b.n + 1);
    for (int it = 0; it < 150; it++) {
      memcpy(m, b.s, b.n);
      size_t n = b.n;
      seed = seed * 1103515245u + 12345u;
      const int kind = (int)(seed >> 16) % 4, count = 1 + (int)(seed >> 8) % 4;
      for (int k = 0; k < count; k++) {
        seed = seed * 1103515245u + 12345u;
        const size_t at = (seed >> 4) % b.n;
        if (kind == 0) m[at] ^= (char)(1u << ((seed >> 2) % 8));
        else if (kind == 1) m[at] = "0123456789<>/=\"_ &;"[(seed >> 3) % 19];
        else if (kind == 2) n = at < n ? at : n;
        else m[at] = (char)(seed >> 24);
      }
      FILE *fp = fopen(path, "wb");
      cr_assert_not_null(fp);
      cr_assert_eq(fwrite(m, 1, n, fp), n);
      fclose(fp);
      bs_vtu *v = NULL;
      bs_error err = {0};
      int rc = bs_vtu_read(path, &v, &err);
      reads++;
      if (rc) {
        errors++;
        cr_assert(rc == BS_EINPUT || rc == BS_ENUMERIC, "%s mutant %d: status %d: %s", files[f], it, rc, err.msg);
        cr_assert_null(v);
        cr_assert_not_null(strstr(err.msg, path), "%s mutant %d: %s", files[f], it, err.msg);
      } else {
        cr_assert(v->n_points >= 0 && v->n_cells >= 0);
      }
      bs_vtu_destroy(&v);
    }
    free(m);
    free(b.s);
  }
  cr_assert_gt(errors, reads / 2, "most mutants are refused (%d of %d)", errors, reads);
}

/* ---- the decoders directly ---------------------------------------------------------- */

Test(vtu_read, base64_pieces_decode_as_one) {
  /* "ab" and "cde" encoded separately (VTK's header, then its data) */
  unsigned char *out;
  size_t n;
  bs_error err = {0};
  cr_assert_eq(bs__vtu_base64("YWI=\n  Y2Rl", 11, &out, &n, &err), BS_OK, "%s", err.msg);
  cr_assert_eq(n, 5);
  cr_assert_eq(memcmp(out, "abcde", 5), 0);
  free(out);
  cr_assert_eq(bs__vtu_base64("YWI", 3, &out, &n, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "ends inside a group"), "%s", err.msg);
  cr_assert_eq(bs__vtu_base64("YW=I", 4, &out, &n, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "after '='"), "%s", err.msg);
}

Test(vtu_read, zlib_header_claims_are_bounded) {
  bs__vtu_doc d = {.zlib = 1}; /* UInt32 words, machine order */
  const unsigned char *data;
  unsigned char *owned;
  size_t used;
  bs_error err = {0};
  /* one block claiming 2^31 bytes from 16 compressed ones */
  uint32_t h[4 + 4] = {1, 1u << 31, 0, 16};
  cr_assert_eq(bs__vtu_block(&d, (const unsigned char *)h, sizeof h, 1u << 31, &used, &data, &owned, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "more than zlib can expand"), "%s", err.msg);
  /* more blocks than the bytes could list */
  uint32_t g[4] = {1000000, 8, 8, 1};
  cr_assert_eq(bs__vtu_block(&d, (const unsigned char *)g, sizeof g, 8000000, &used, &data, &owned, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "lists 1000000 blocks"), "%s", err.msg);
  /* a last block larger than the block size */
  uint32_t k[4] = {1, 8, 9, 0};
  cr_assert_eq(bs__vtu_block(&d, (const unsigned char *)k, sizeof k, 9, &used, &data, &owned, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "a last block of 9"), "%s", err.msg);
}

Test(vtu_read, pvd_errors) {
  char path[256];
  snprintf(path, sizeof path, "%s/cut.pvd", dir);
  FILE *fp = fopen(path, "w");
  fputs("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n"
        "    <DataSet timestep=\"0.5\" file=\"a.vtu\"/>\n    <DataSet timestep=\"x\" file=\"b.vtu\"/>\n",
        fp);
  fclose(fp);
  bs_pvd *p = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_pvd_read(path, &p, &err), BS_EINPUT);
  cr_assert_null(p);
  cr_assert_not_null(strstr(err.msg, "invalid timestep 'x'"), "%s", err.msg);
  fp = fopen(path, "w");
  fputs("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n"
        "    <DataSet timestep=\"0.5\" file=\"a.vtu\"/>\n",
        fp);
  fclose(fp);
  cr_assert_eq(bs_pvd_read(path, &p, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "truncated"), "%s", err.msg);
  snprintf(path, sizeof path, "%s/missing.pvd", dir);
  cr_assert_eq(bs_pvd_read(path, &p, &err), BS_EIO);
}
