/* The VTK writers' layouts (mesh/bs_mesh.h, output): caller-given arrays,
 * zlib compression in VTK's block layout (the blocks are inflated here and
 * compared with the raw file's bytes, a full last block included), the
 * appended data's start past the 8192-byte boundaries (the Debian VTK
 * workaround), triangle surfaces, ImageData read back, and the errors. */
#define _GNU_SOURCE /* mkdtemp */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <zlib.h>

#include "bs_mesh.h"
#include "bs_vtu_read.h"

static char dir[64];
static void make_dir(void) {
  strcpy(dir, "/tmp/bs_test_vtuw_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
}
static void remove_dir(void) {
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  if (dir[0]) cr_assert_eq(system(cmd), 0);
}
TestSuite(vtuw, .init = make_dir, .fini = remove_dir);

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

/* The appended data's base (the byte after '_'), checking where it starts. */
static const unsigned char *appended_base(const char *s) {
  const char *tag = strstr(s, "<AppendedData encoding=\"raw\">");
  cr_assert_not_null(tag);
  const char *u = strchr(tag, '_');
  cr_assert_not_null(u);
  for (const char *p = tag + strlen("<AppendedData encoding=\"raw\">"); p < u; p++) cr_assert(*p == ' ' || *p == '\n');
  long at = (long)(u - s), tag_block = (long)(tag - s) / 8192;
  cr_assert_geq(at / 8192, tag_block + 1, "the binary starts a whole read block after the tag's");
  cr_assert_leq(at - (long)(tag - s), 2 * 8192 + 64, "at most two blocks of padding");
  return (const unsigned char *)u + 1;
}

/* The offset attribute of the DataArray named name (its first occurrence
 * from `from`). */
static uint64_t offset_of(const char *from, const char *name) {
  char key[96];
  snprintf(key, sizeof key, "Name=\"%s\"", name);
  const char *p = strstr(from, key);
  cr_assert_not_null(p, "no DataArray %s", name);
  const char *o = strstr(p, "offset=\"");
  cr_assert_not_null(o);
  return strtoull(o + 8, NULL, 10);
}

/* Inflates VTK's zlib layout at z; returns the bytes (malloc'ed), *n its size. */
static unsigned char *inflate_blocks(const unsigned char *z, uint64_t *n, uint64_t *last) {
  uint64_t h[3];
  memcpy(h, z, sizeof h);
  cr_assert_eq(h[1], 32768, "VTK's block size");
  const uint64_t nb = h[0];
  *last = h[2];
  *n = nb == 0 ? 0 : (nb - 1) * h[1] + (h[2] ? h[2] : h[1]);
  unsigned char *out = malloc(*n + 1);
  const unsigned char *c = z + 8 * (3 + nb);
  for (uint64_t i = 0; i < nb; i++) {
    uint64_t cs;
    memcpy(&cs, z + 8 * (3 + i), 8);
    uLongf len = (uLongf)(i + 1 < nb || !h[2] ? h[1] : h[2]);
    cr_assert_eq(uncompress(out + i * h[1], &len, c, (uLong)cs), Z_OK, "block %llu", (unsigned long long)i);
    c += cs;
  }
  return out;
}

/* A surface of n points (a strip of triangles); raw and zlib files have the
 * same bytes in every array; 4096 points make Points exactly 3 blocks. */
Test(vtuw, zlib_blocks_inflate_to_the_raw_bytes) {
  const int32_t n = 4096, nt = n - 2;
  double *x = malloc(sizeof(double) * 3 * n), *f = malloc(sizeof(double) * 9 * nt);
  int32_t *tris = malloc(sizeof(int32_t) * 3 * nt), *id = malloc(sizeof(int32_t) * n);
  for (int32_t i = 0; i < n; i++) {
    x[3 * i] = i * 0.01, x[3 * i + 1] = (i % 2) * 0.3, x[3 * i + 2] = sin(i * 0.1);
    id[i] = i * 7;
  }
  for (int32_t t = 0; t < nt; t++) {
    tris[3 * t] = t, tris[3 * t + 1] = t + 1, tris[3 * t + 2] = t + 2;
    for (int k = 0; k < 9; k++) f[9 * t + k] = cos(t + k);
  }
  bs_vtu_data pd = {"id", BS_VTU_INT32, 1, id}, cd = {"tensor", BS_VTU_FLOAT64, 9, f};
  char raw[128], zip[128];
  snprintf(raw, sizeof raw, "%s/raw.vtu", dir);
  snprintf(zip, sizeof zip, "%s/zip.vtu", dir);
  bs_vtu_surface s = {n, x, nt, tris, 1, &pd, 1, &cd, 0};
  bs_error err;
  cr_assert_eq(bs_surface_write_vtu(&s, raw, &err), 0, "%s", err.msg);
  s.compress = 1;
  cr_assert_eq(bs_surface_write_vtu(&s, zip, &err), 0, "%s", err.msg);
  size_t nr, nz;
  char *r = slurp(raw, &nr), *z = slurp(zip, &nz);
  cr_assert_not_null(strstr(z, "compressor=\"vtkZLibDataCompressor\""));
  cr_assert_null(strstr(r, "compressor="));
  const unsigned char *br = appended_base(r), *bz = appended_base(z);
  static const char *const names[] = {"id", "tensor", "Points", "connectivity", "offsets", "types"};
  int full_last = 0;
  for (int i = 0; i < 6; i++) {
    uint64_t bytes, last, count;
    const unsigned char *a = br + offset_of(r, names[i]);
    memcpy(&count, a, 8);
    unsigned char *u = inflate_blocks(bz + offset_of(z, names[i]), &bytes, &last);
    cr_assert_eq(bytes, count, "%s: %llu bytes inflated, %llu raw", names[i], (unsigned long long)bytes,
                 (unsigned long long)count);
    cr_assert_eq(memcmp(u, a + 8, bytes), 0, "%s: the inflated bytes are the raw ones", names[i]);
    full_last += !strcmp(names[i], "Points") && last == 0 && bytes == 3 * 32768;
    free(u);
  }
  cr_assert_eq(full_last, 1, "Points fill three blocks: the last-block word is 0");
  free(r), free(z), free(x), free(f), free(tris), free(id);
}

/* A tet mesh with extra arrays, raw and compressed, read back by bigstep's
 * reader: the same values, bit for bit. */
Test(vtuw, tet_arrays_round_trip_raw_and_compressed) {
  bs_mesh *m = NULL;
  bs_error err;
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 6, 6, 6, &m, &err), 0, "%s", err.msg);
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  double *x = malloc(sizeof(double) * 3 * nv), *sig = malloc(sizeof(double) * 9 * nt);
  uint8_t *flag = malloc((size_t)nv);
  for (int32_t i = 0; i < 3 * nv; i++) x[i] = m->x[i] * (1 + 0.01 * (i % 5));
  for (int32_t i = 0; i < 9 * nt; i++) sig[i] = 1e5 * sin(0.37 * i);
  for (int32_t v = 0; v < nv; v++) flag[v] = v % 3 == 0;
  bs_vtu_data pd = {"flag", BS_VTU_UINT8, 1, flag}, cd = {"cauchy", BS_VTU_FLOAT64, 9, sig};
  for (int c = 0; c < 2; c++) {
    char path[128];
    snprintf(path, sizeof path, "%s/tets%d.vtu", dir, c);
    bs_vtu_fields f = {.x = x, .n_point_data = 1, .point_data = &pd, .n_cell_data = 1, .cell_data = &cd, .compress = c};
    cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), 0, "%s", err.msg);
    bs_vtu *v = NULL;
    cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
    cr_assert_eq(v->n_cells, nt);
    cr_assert_eq(memcmp(v->x, x, sizeof(double) * 3 * nv), 0);
    const bs_vtu_array *a = bs_vtu_cell_array(v, "cauchy"), *fl = bs_vtu_point_array(v, "flag");
    cr_assert(a && a->ncomp == 9 && fl && bs_vtu_cell_array(v, "detF") && bs_vtu_cell_array(v, "material"));
    cr_assert_eq(memcmp(a->data, sig, sizeof(double) * 9 * nt), 0, "compress %d", c);
    for (int32_t p = 0; p < nv; p++) cr_assert_eq(fl->data[p], (double)flag[p]);
    bs_vtu_destroy(&v);
  }
  bs_vtu_fields only = {.custom_cells = 1};
  char path[128];
  snprintf(path, sizeof path, "%s/bare.vtu", dir);
  cr_assert_eq(bs_mesh_write_vtu(m, &only, path, &err), 0, "%s", err.msg);
  bs_vtu *v = NULL;
  cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
  cr_assert_eq(v->n_cell_data, 0, "custom_cells: no material, detF, inverted");
  cr_assert_eq(v->n_point_data, 1, "displacement only");
  bs_vtu_destroy(&v);
  free(x), free(sig), free(flag);
  bs_mesh_destroy(&m);
}

Test(vtuw, bad_arrays_and_paths_are_errors) {
  bs_mesh *m = NULL;
  bs_error err;
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  cr_assert_eq(bs_mesh_create_box(lo, hi, 1, 1, 1, &m, &err), 0, "%s", err.msg);
  double d[6] = {0};
  char path[128];
  snprintf(path, sizeof path, "%s/bad.vtu", dir);
  bs_vtu_data noname = {"", BS_VTU_FLOAT64, 1, d}, nocomp = {"q", BS_VTU_FLOAT64, 0, d}, nodata = {"q", BS_VTU_INT32, 1, NULL};
  bs_vtu_data badtype = {"q", (bs_vtu_type)7, 1, d};
  const bs_vtu_data *bad[4] = {&noname, &nocomp, &nodata, &badtype};
  for (int i = 0; i < 4; i++) {
    bs_vtu_fields f = {.n_cell_data = 1, .cell_data = bad[i]};
    cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), BS_EINPUT, "case %d", i);
    cr_assert(strstr(err.msg, "cell data") && strstr(err.msg, path), "%s", err.msg);
    cr_assert_neq(access(path, F_OK), 0, "no file is left behind");
  }
  int32_t tri[3] = {0, 1, 5};
  bs_vtu_surface s = {.n_points = 3, .x = d, .n_tris = 1, .tris = tri};
  cr_assert_eq(bs_surface_write_vtu(&s, path, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "triangle 0 uses point 5 of 3"), "%s", err.msg);
  cr_assert_eq(bs_mesh_write_vtu(m, NULL, "/nonexistent/dir/x.vtu", &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, "/nonexistent/dir/x.vtu"));
  bs_mesh_destroy(&m);
}

/* An attribute's numbers, parsed. */
static int attr_numbers(const char *s, const char *attr, double *out, int n) {
  char key[64];
  snprintf(key, sizeof key, " %s=\"", attr);
  const char *p = strstr(s, key);
  if (!p) return -1;
  p += strlen(key);
  for (int i = 0; i < n; i++) {
    char *end;
    out[i] = strtod(p, &end);
    if (end == p) return -1;
    p = end;
  }
  return *p == '"' ? 0 : -1;
}

Test(vtuw, image_data_reads_back) {
  const int32_t n[3] = {5, 4, 3};
  double values[60];
  for (int i = 0; i < 60; i++) values[i] = 0.1 * i - 2.0 + 1e-17 * i;
  const double D[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
  bs_vti_grid g = {{n[0], n[1], n[2]}, {0.5, -1.25, 3}, 0.125, D, "phi", values};
  char path[128];
  snprintf(path, sizeof path, "%s/g.vti", dir);
  bs_error err;
  cr_assert_eq(bs_vti_write(&g, path, &err), 0, "%s", err.msg);
  size_t len;
  char *s = slurp(path, &len);
  double ext[6], org[3], sp[3], dir9[9];
  cr_assert_eq(attr_numbers(s, "WholeExtent", ext, 6), 0);
  cr_assert_eq(attr_numbers(s, "Origin", org, 3), 0);
  cr_assert_eq(attr_numbers(s, "Spacing", sp, 3), 0);
  cr_assert_eq(attr_numbers(s, "Direction", dir9, 9), 0);
  for (int k = 0; k < 3; k++) {
    cr_assert_eq(ext[2 * k], 0);
    cr_assert_eq(ext[2 * k + 1], n[k] - 1);
    cr_assert_eq(org[k], g.origin[k]);
    cr_assert_eq(sp[k], 0.125);
  }
  for (int i = 0; i < 9; i++) cr_assert_eq(dir9[i], D[i]);
  cr_assert_not_null(strstr(s, "Name=\"phi\" format=\"appended\" offset=\"0\""));
  const unsigned char *b = appended_base(s);
  uint64_t bytes;
  memcpy(&bytes, b, 8);
  cr_assert_eq(bytes, sizeof values);
  cr_assert_eq(memcmp(b + 8, values, sizeof values), 0, "the values, bit for bit, i fastest");
  cr_assert_not_null(strstr((const char *)b + 8 + bytes, "</AppendedData>"));
  free(s);
  g.h = 0;
  cr_assert_eq(bs_vti_write(&g, path, &err), BS_EINPUT);
  cr_assert(strstr(err.msg, "spacing"), "%s", err.msg);
}
