#define _POSIX_C_SOURCE 200809L
/* VTU and PVD writers: the file is read back and its header, block sizes
 * and raw values checked bit for bit. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"

static char dir[64];

static void make_dir(void) {
  strcpy(dir, "/tmp/bs_test_vtu_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
}

static void remove_dir(void) {
  if (dir[0]) rmdir(dir);
}

TestSuite(vtu, .init = make_dir, .fini = remove_dir);

static char *slurp(const char *path, size_t *n) {
  FILE *fp = fopen(path, "rb");
  cr_assert_not_null(fp, "cannot read back %s", path);
  fseek(fp, 0, SEEK_END);
  long len = ftell(fp);
  fseek(fp, 0, SEEK_SET);
  char *s = malloc((size_t)len + 1);
  cr_assert_eq(fread(s, 1, (size_t)len, fp), (size_t)len);
  s[len] = 0;
  fclose(fp);
  *n = (size_t)len;
  return s;
}

/* Value of attribute `attr` in the XML element that contains `needle`
 * (searched in the text header only). */
static int attr(const char *xml, const char *needle, const char *attr, char *out, size_t cap) {
  const char *p = strstr(xml, needle);
  if (!p) return -1;
  const char *start = p;
  while (start > xml && *start != '<') start--;
  const char *end = strchr(p, '>');
  char key[64];
  snprintf(key, sizeof key, " %s=\"", attr);
  const char *a = strstr(start, key);
  if (!a || a > end) return -1;
  a += strlen(key);
  const char *q = strchr(a, '"');
  size_t len = (size_t)(q - a);
  if (len >= cap) return -1;
  memcpy(out, a, len);
  out[len] = 0;
  return 0;
}

typedef struct block {
  const unsigned char *data;
  uint64_t bytes, offset;
  char type[16];
} block;

/* The appended block of the DataArray named `name`. */
static block find_block(const char *s, size_t n, const char *name) {
  block b = {0};
  char needle[80], off[32];
  snprintf(needle, sizeof needle, "Name=\"%s\"", name);
  cr_assert_eq(attr(s, needle, "offset", off, sizeof off), 0, "no DataArray %s", name);
  cr_assert_eq(attr(s, needle, "type", b.type, sizeof b.type), 0);
  char fmt[32];
  cr_assert_eq(attr(s, needle, "format", fmt, sizeof fmt), 0);
  cr_assert_str_eq(fmt, "appended");
  const char *app = strstr(s, "<AppendedData encoding=\"raw\">");
  cr_assert_not_null(app);
  const char *base = strchr(app, '_');
  cr_assert_not_null(base);
  base++;
  b.offset = strtoull(off, NULL, 10);
  cr_assert((size_t)(base - s) + b.offset + 8 <= n, "block %s beyond the end of the file", name);
  memcpy(&b.bytes, base + b.offset, 8);
  b.data = (const unsigned char *)base + b.offset + 8;
  cr_assert((size_t)(base - s) + b.offset + 8 + b.bytes <= n, "block %s (%llu bytes) beyond the end", name,
            (unsigned long long)b.bytes);
  return b;
}

static bs_mesh *small_box(void) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 0.5, 0.25};
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 2, 3, 2, &m, &err), BS_OK, "%s", err.msg);
  return m;
}

Test(vtu, write_and_read_back) {
  bs_mesh *m = small_box();
  int32_t nv = m->n_vertices, nt = m->n_tets;
  double *x = malloc(sizeof(double) * 3 * (size_t)nv);
  double *vel = malloc(sizeof(double) * 3 * (size_t)nv);
  for (int32_t v = 0; v < nv; v++)
    for (int k = 0; k < 3; k++) {
      /* stretch by 1.5 along x, plus a rigid shift: detF = 1.5 */
      x[3 * v + k] = (k == 0 ? 1.5 : 1.0) * m->x[3 * v + k] + 0.1 * (k + 1) + 1e-17 * v;
      vel[3 * v + k] = sin(0.3 * v + k);
    }
  char path[128];
  snprintf(path, sizeof path, "%s/box.vtu", dir);
  bs_vtu_fields f = {.x = x, .velocity = vel, .cell_detF = NULL};
  bs_error err = {0};
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), BS_OK, "%s", err.msg);

  size_t n;
  char *s = slurp(path, &n);
  char val[64];
  cr_assert(strncmp(s, "<?xml", 5) == 0);
  cr_assert_eq(attr(s, "<VTKFile", "type", val, sizeof val), 0);
  cr_assert_str_eq(val, "UnstructuredGrid");
  cr_assert_eq(attr(s, "<VTKFile", "header_type", val, sizeof val), 0);
  cr_assert_str_eq(val, "UInt64");
  cr_assert_eq(attr(s, "<VTKFile", "byte_order", val, sizeof val), 0);
  const uint16_t one = 1;
  cr_assert_str_eq(val, *(const unsigned char *)&one ? "LittleEndian" : "BigEndian");
  cr_assert_eq(attr(s, "<Piece", "NumberOfPoints", val, sizeof val), 0);
  cr_assert_eq(atoi(val), nv);
  cr_assert_eq(attr(s, "<Piece", "NumberOfCells", val, sizeof val), 0);
  cr_assert_eq(atoi(val), nt);

  block pts = find_block(s, n, "Points");
  block disp = find_block(s, n, "displacement");
  block bvel = find_block(s, n, "velocity");
  block conn = find_block(s, n, "connectivity");
  block offs = find_block(s, n, "offsets");
  block types = find_block(s, n, "types");
  block mat = find_block(s, n, "material");
  block detf = find_block(s, n, "detF");
  block inv = find_block(s, n, "inverted");
  cr_assert_str_eq(pts.type, "Float64");
  cr_assert_str_eq(conn.type, "Int64");
  cr_assert_str_eq(offs.type, "Int64");
  cr_assert_str_eq(types.type, "UInt8");
  cr_assert_str_eq(mat.type, "Int32");
  cr_assert_str_eq(detf.type, "Float64");
  cr_assert_str_eq(inv.type, "UInt8");
  cr_assert_eq(pts.bytes, 8u * 3 * nv);
  cr_assert_eq(disp.bytes, 8u * 3 * nv);
  cr_assert_eq(bvel.bytes, 8u * 3 * nv);
  cr_assert_eq(conn.bytes, 8u * 4 * nt);
  cr_assert_eq(offs.bytes, 8u * nt);
  cr_assert_eq(types.bytes, 1u * nt);
  cr_assert_eq(mat.bytes, 4u * nt);
  cr_assert_eq(detf.bytes, 8u * nt);
  cr_assert_eq(inv.bytes, 1u * nt);

  /* blocks tile the appended section exactly, in offset order */
  block all[9] = {disp, bvel, mat, detf, inv, pts, conn, offs, types};
  uint64_t next = 0;
  for (int i = 0; i < 9; i++) {
    uint64_t lo = UINT64_MAX;
    int at = -1;
    for (int j = 0; j < 9; j++)
      if (all[j].offset >= next && all[j].offset < lo) lo = all[j].offset, at = j;
    cr_assert(at >= 0 && all[at].offset == next, "gap or overlap at offset %llu", (unsigned long long)next);
    next = all[at].offset + 8 + all[at].bytes;
  }
  const char *tail = (const char *)types.data + types.bytes;
  cr_assert(strstr(tail, "</AppendedData>") && strstr(tail, "</VTKFile>"), "file does not end with the closing tags");

  /* values, bit for bit */
  cr_assert(memcmp(pts.data, x, 24u * nv) == 0, "points differ from the input");
  double p5[3];
  memcpy(p5, pts.data + 24 * 5, sizeof p5);
  cr_assert(memcmp(p5, x + 15, sizeof p5) == 0);
  cr_assert(memcmp(bvel.data, vel, 24u * nv) == 0, "velocity differs");
  for (int32_t i = 0; i < 3 * nv; i++) {
    double d;
    memcpy(&d, disp.data + 8 * (size_t)i, 8);
    cr_assert_eq(d, x[i] - m->x[i], "displacement %d", i);
  }
  for (int32_t t = 0; t < nt; t++) {
    int64_t c[4], o;
    int32_t mt;
    double df;
    memcpy(c, conn.data + 32 * (size_t)t, 32);
    for (int k = 0; k < 4; k++) cr_assert_eq(c[k], m->tets[4 * t + k], "connectivity of cell %d", t);
    memcpy(&o, offs.data + 8 * (size_t)t, 8);
    cr_assert_eq(o, 4 * (int64_t)(t + 1));
    cr_assert_eq(types.data[t], 10);
    memcpy(&mt, mat.data + 4 * (size_t)t, 4);
    cr_assert_eq(mt, m->material[t]);
    cr_assert_eq(mt, 1);
    memcpy(&df, detf.data + 8 * (size_t)t, 8);
    cr_assert(fabs(df - 1.5) < 1e-12, "detF of cell %d = %.17g", t, df);
    cr_assert_eq(inv.data[t], 0);
  }
  free(s);
  remove(path);
  free(x);
  free(vel);
  bs_mesh_destroy(&m);
}

Test(vtu, rest_and_inverted) {
  bs_mesh *m = small_box();
  int32_t nv = m->n_vertices, nt = m->n_tets;
  char path[128];
  snprintf(path, sizeof path, "%s/rest.vtu", dir);
  bs_error err = {0};
  /* no fields: rest positions, zero displacement, detF 1, no velocity */
  cr_assert_eq(bs_mesh_write_vtu(m, NULL, path, &err), BS_OK, "%s", err.msg);
  size_t n;
  char *s = slurp(path, &n);
  cr_assert_null(strstr(s, "Name=\"velocity\""));
  block pts = find_block(s, n, "Points");
  cr_assert(memcmp(pts.data, m->x, 24u * nv) == 0);
  block disp = find_block(s, n, "displacement");
  for (int32_t i = 0; i < 3 * nv; i++) {
    double d;
    memcpy(&d, disp.data + 8 * (size_t)i, 8);
    cr_assert_eq(d, 0.0);
  }
  block detf = find_block(s, n, "detF");
  for (int32_t t = 0; t < nt; t++) {
    double df;
    memcpy(&df, detf.data + 8 * (size_t)t, 8);
    cr_assert_eq(df, 1.0);
  }
  free(s);

  /* mirrored positions invert every tet; a given detF is written as is */
  double *x = malloc(sizeof(double) * 3 * (size_t)nv);
  double *dF = malloc(sizeof(double) * (size_t)nt);
  for (int32_t i = 0; i < 3 * nv; i++) x[i] = (i % 3 == 1 ? -1.0 : 1.0) * m->x[i];
  bs_vtu_fields f = {.x = x};
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), BS_OK, "%s", err.msg);
  s = slurp(path, &n);
  detf = find_block(s, n, "detF");
  block inv = find_block(s, n, "inverted");
  for (int32_t t = 0; t < nt; t++) {
    double df;
    memcpy(&df, detf.data + 8 * (size_t)t, 8);
    cr_assert(fabs(df + 1.0) < 1e-12, "mirrored cell %d: detF %.17g", t, df);
    cr_assert_eq(inv.data[t], 1, "mirrored cell %d not flagged inverted", t);
  }
  free(s);
  for (int32_t t = 0; t < nt; t++) dF[t] = t % 2 ? 0.5 : -0.25;
  f.cell_detF = dF;
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), BS_OK, "%s", err.msg);
  s = slurp(path, &n);
  detf = find_block(s, n, "detF");
  inv = find_block(s, n, "inverted");
  cr_assert(memcmp(detf.data, dF, 8u * nt) == 0);
  for (int32_t t = 0; t < nt; t++) cr_assert_eq(inv.data[t], t % 2 ? 0 : 1);
  free(s);
  remove(path);
  free(x);
  free(dF);
  bs_mesh_destroy(&m);
}

Test(vtu, pvd_lists_files) {
  char path[128];
  snprintf(path, sizeof path, "%s/run.pvd", dir);
  const double times[3] = {0.0, 1.0 / 24.0, 2.0 / 24.0};
  const char *files[3] = {"frame_0000.vtu", "frame_0001.vtu", "a&b\"<c>.vtu"};
  bs_error err = {0};
  cr_assert_eq(bs_pvd_write(path, 3, times, files, &err), BS_OK, "%s", err.msg);
  size_t n;
  char *s = slurp(path, &n);
  char val[64];
  cr_assert_eq(attr(s, "<VTKFile", "type", val, sizeof val), 0);
  cr_assert_str_eq(val, "Collection");
  cr_assert_not_null(strstr(s, "<Collection>"));
  const char *p = s;
  const char *expect[3] = {"frame_0000.vtu", "frame_0001.vtu", "a&amp;b&quot;&lt;c&gt;.vtu"};
  for (int i = 0; i < 3; i++) {
    p = strstr(p, "<DataSet");
    cr_assert_not_null(p, "entry %d missing", i);
    cr_assert_eq(attr(p, "<DataSet", "file", val, sizeof val), 0);
    cr_assert_str_eq(val, expect[i]);
    cr_assert_eq(attr(p, "<DataSet", "timestep", val, sizeof val), 0);
    cr_assert_eq(strtod(val, NULL), times[i], "timestep %d: %s", i, val);
    p++;
  }
  cr_assert_null(strstr(p, "<DataSet"));
  cr_assert_not_null(strstr(p, "</Collection>"));
  free(s);

  /* an empty collection is valid */
  cr_assert_eq(bs_pvd_write(path, 0, NULL, NULL, &err), BS_OK, "%s", err.msg);
  s = slurp(path, &n);
  cr_assert_null(strstr(s, "<DataSet"));
  free(s);
  remove(path);

  /* a non-finite time names the entry */
  const double bad[2] = {0.0, NAN};
  cr_assert_eq(bs_pvd_write(path, 2, bad, files, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "entry 1") && strstr(err.msg, "frame_0001.vtu"), "message: %s", err.msg);
}

Test(vtu, missing_directory) {
  bs_mesh *m = small_box();
  char path[160];
  snprintf(path, sizeof path, "%s/no_such_dir/out.vtu", dir);
  bs_error err = {0};
  cr_assert_eq(bs_mesh_write_vtu(m, NULL, path, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, path), "message does not name the path: %s", err.msg);
  cr_assert_eq(err.code, BS_EIO);
  snprintf(path, sizeof path, "%s/no_such_dir/run.pvd", dir);
  const double t = 0;
  const char *file = "a.vtu";
  cr_assert_eq(bs_pvd_write(path, 1, &t, &file, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, path), "message does not name the path: %s", err.msg);
  cr_assert_eq(bs_mesh_write_vtu(m, NULL, NULL, &err), BS_EINPUT);
  bs_mesh_destroy(&m);
}
