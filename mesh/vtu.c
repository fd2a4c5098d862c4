/* vtu.c — ParaView output: VTK XML UnstructuredGrid (.vtu) and collections
 * (.pvd).
 *
 * The .vtu file keeps all arrays in one <AppendedData encoding="raw"> block
 * after a '_' marker. With header_type="UInt64" each array there is an 8-byte
 * byte count followed by the raw values in the machine's byte order (stated
 * in byte_order); a DataArray's offset attribute is the position of its
 * byte count relative to the first byte after '_'. Every array is written
 * with a single fwrite (converted through one scratch buffer when its type
 * differs from the mesh's), so writing runs at disk speed.
 *
 * Arrays: Points (Float64 x 3, current positions), connectivity and offsets
 * (Int64), types (UInt8, 10 = VTK_TETRA); PointData "displacement" (x - rest)
 * and "velocity" (when given); CellData "material" (Int32), "detF" (Float64:
 * given, or the signed current volume over the rest volume) and "inverted"
 * (UInt8: detF <= 0). */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"

enum { VTK_TETRA = 10 };

static const char *byte_order(void) {
  const uint16_t one = 1;
  unsigned char c;
  memcpy(&c, &one, 1);
  return c ? "LittleEndian" : "BigEndian";
}

/* 6 x signed volume of tet (a, b, c, d) at positions x. */
static double tet_vol6(const double *x, const int32_t *t) {
  const double *p0 = x + 3 * (size_t)t[0], *p1 = x + 3 * (size_t)t[1];
  const double *p2 = x + 3 * (size_t)t[2], *p3 = x + 3 * (size_t)t[3];
  double a[3], b[3], c[3];
  for (int k = 0; k < 3; k++) {
    a[k] = p1[k] - p0[k];
    b[k] = p2[k] - p0[k];
    c[k] = p3[k] - p0[k];
  }
  return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

typedef struct appended {
  const char *name, *type;
  int ncomp;
  uint64_t bytes;
  uint64_t offset;
} appended;

/* Writes one appended block: the byte count, then the data in one fwrite. */
static int write_block(FILE *fp, const void *data, uint64_t bytes) {
  if (fwrite(&bytes, sizeof bytes, 1, fp) != 1) return -1;
  if (bytes && fwrite(data, 1, (size_t)bytes, fp) != (size_t)bytes) return -1;
  return 0;
}

int bs_mesh_write_vtu(const bs_mesh *m, const bs_vtu_fields *f, const char *path, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "write vtu: path is NULL");
  if (!m || !m->x || (m->n_tets > 0 && !m->tets))
    return bs_error_set(err, BS_EINPUT, "write vtu '%s': mesh is NULL or empty", path);
  const bs_vtu_fields none = {0};
  if (!f) f = &none;
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  const double *x = f->x ? f->x : m->x;
  const int has_vel = f->velocity != NULL;

  /* array layout in the appended block, in writing order */
  enum { A_DISP, A_VEL, A_MAT, A_DETF, A_INV, A_PTS, A_CONN, A_OFFS, A_TYPES, A_N };
  appended a[A_N] = {
      [A_DISP] = {"displacement", "Float64", 3, 24u * (uint64_t)nv, 0},
      [A_VEL] = {"velocity", "Float64", 3, has_vel ? 24u * (uint64_t)nv : 0, 0},
      [A_MAT] = {"material", "Int32", 1, 4u * (uint64_t)nt, 0},
      [A_DETF] = {"detF", "Float64", 1, 8u * (uint64_t)nt, 0},
      [A_INV] = {"inverted", "UInt8", 1, (uint64_t)nt, 0},
      [A_PTS] = {"Points", "Float64", 3, 24u * (uint64_t)nv, 0},
      [A_CONN] = {"connectivity", "Int64", 1, 32u * (uint64_t)nt, 0},
      [A_OFFS] = {"offsets", "Int64", 1, 8u * (uint64_t)nt, 0},
      [A_TYPES] = {"types", "UInt8", 1, (uint64_t)nt, 0},
  };
  uint64_t off = 0;
  for (int i = 0; i < A_N; i++) {
    if (i == A_VEL && !has_vel) continue;
    a[i].offset = off;
    off += 8 + a[i].bytes;
  }

  /* one scratch buffer, large enough for the biggest converted array */
  size_t scratch = 24u * (size_t)nv;
  if (32u * (size_t)nt > scratch) scratch = 32u * (size_t)nt;
  unsigned char *buf = bs_calloc(scratch + 8, 1, "write vtu: scratch buffer", err);
  if (!buf) {
    bs_error_prefix(err, "write vtu '%s'", path);
    return BS_ENOMEM;
  }

  FILE *fp = fopen(path, "wb");
  if (!fp) {
    int e = errno;
    free(buf);
    return bs_error_set(err, BS_EIO, "write vtu: cannot open '%s' for writing: %s", path, strerror(e));
  }

  int bad = 0;
  bad |= fprintf(fp,
                 "<?xml version=\"1.0\"?>\n"
                 "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" header_type=\"UInt64\">\n"
                 "  <UnstructuredGrid>\n"
                 "    <Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n"
                 "      <PointData Vectors=\"displacement\">\n",
                 byte_order(), nv, nt) < 0;
  for (int i = 0; i < A_N; i++) {
    if (i == A_VEL && !has_vel) continue;
    if (i == A_MAT) bad |= fputs("      </PointData>\n      <CellData Scalars=\"material\">\n", fp) < 0;
    if (i == A_PTS) bad |= fputs("      </CellData>\n      <Points>\n", fp) < 0;
    if (i == A_CONN) bad |= fputs("      </Points>\n      <Cells>\n", fp) < 0;
    if (a[i].ncomp > 1)
      bad |= fprintf(fp,
                     "        <DataArray type=\"%s\" Name=\"%s\" NumberOfComponents=\"%d\" format=\"appended\" "
                     "offset=\"%llu\"/>\n",
                     a[i].type, a[i].name, a[i].ncomp, (unsigned long long)a[i].offset) < 0;
    else
      bad |= fprintf(fp, "        <DataArray type=\"%s\" Name=\"%s\" format=\"appended\" offset=\"%llu\"/>\n", a[i].type,
                     a[i].name, (unsigned long long)a[i].offset) < 0;
  }
  bad |= fputs("      </Cells>\n"
               "    </Piece>\n"
               "  </UnstructuredGrid>\n"
               "  <AppendedData encoding=\"raw\">\n"
               "   _",
               fp) < 0;

  /* displacement */
  double *d = (double *)buf;
  for (size_t i = 0; i < 3 * (size_t)nv; i++) d[i] = x[i] - m->x[i];
  bad |= write_block(fp, d, a[A_DISP].bytes);
  if (has_vel) bad |= write_block(fp, f->velocity, a[A_VEL].bytes);
  /* material */
  if (m->material) {
    bad |= write_block(fp, m->material, a[A_MAT].bytes);
  } else {
    memset(buf, 0, (size_t)a[A_MAT].bytes);
    bad |= write_block(fp, buf, a[A_MAT].bytes);
  }
  /* detF: given, or current over rest volume */
  if (f->cell_detF) {
    memcpy(d, f->cell_detF, (size_t)nt * sizeof(double));
  } else {
    for (int32_t t = 0; t < nt; t++) {
      const int32_t *tv = m->tets + 4 * (size_t)t;
      d[t] = x == m->x ? 1.0 : tet_vol6(x, tv) / tet_vol6(m->x, tv);
    }
  }
  bad |= write_block(fp, d, a[A_DETF].bytes);
  /* inverted (detF <= 0; a NaN detF counts as inverted too) */
  for (int32_t t = 0; t < nt; t++) buf[8u * (size_t)nt + t] = !(d[t] > 0.0);
  bad |= write_block(fp, buf + 8u * (size_t)nt, a[A_INV].bytes);
  /* points */
  bad |= write_block(fp, x, a[A_PTS].bytes);
  /* connectivity, offsets, types */
  int64_t *q = (int64_t *)buf;
  for (size_t i = 0; i < 4 * (size_t)nt; i++) q[i] = m->tets[i];
  bad |= write_block(fp, q, a[A_CONN].bytes);
  for (int32_t t = 0; t < nt; t++) q[t] = 4 * (int64_t)(t + 1);
  bad |= write_block(fp, q, a[A_OFFS].bytes);
  memset(buf, VTK_TETRA, (size_t)nt);
  bad |= write_block(fp, buf, a[A_TYPES].bytes);
  bad |= fputs("\n  </AppendedData>\n</VTKFile>\n", fp) < 0;

  int e = errno;
  if (ferror(fp)) bad = 1;
  if (fclose(fp) != 0) {
    e = errno;
    bad = 1;
  }
  free(buf);
  if (bad) {
    remove(path);
    return bs_error_set(err, BS_EIO, "write vtu: writing '%s' failed: %s", path, strerror(e));
  }
  return BS_OK;
}

/* XML attribute value with &, <, >, " and ' escaped. */
static int put_escaped(FILE *fp, const char *s) {
  for (; *s; s++) {
    int r;
    switch (*s) {
      case '&': r = fputs("&amp;", fp); break;
      case '<': r = fputs("&lt;", fp); break;
      case '>': r = fputs("&gt;", fp); break;
      case '"': r = fputs("&quot;", fp); break;
      case '\'': r = fputs("&apos;", fp); break;
      default: r = fputc(*s, fp); break;
    }
    if (r < 0) return -1;
  }
  return 0;
}

int bs_pvd_write(const char *path, int n, const double *times, const char *const *files, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "write pvd: path is NULL");
  if (n < 0) return bs_error_set(err, BS_EINPUT, "write pvd '%s': negative number of entries %d", path, n);
  if (n > 0 && (!times || !files))
    return bs_error_set(err, BS_EINPUT, "write pvd '%s': %s is NULL", path, times ? "files" : "times");
  for (int i = 0; i < n; i++) {
    if (!files[i]) return bs_error_set(err, BS_EINPUT, "write pvd '%s': file of entry %d is NULL", path, i);
    if (!isfinite(times[i]))
      return bs_error_set(err, BS_EINPUT, "write pvd '%s': time of entry %d ('%s') is not finite", path, i, files[i]);
  }
  FILE *fp = fopen(path, "w");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "write pvd: cannot open '%s' for writing: %s", path, strerror(e));
  }
  int bad = 0;
  bad |= fprintf(fp,
                 "<?xml version=\"1.0\"?>\n"
                 "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"%s\">\n"
                 "  <Collection>\n",
                 byte_order()) < 0;
  for (int i = 0; i < n && !bad; i++) {
    bad |= fprintf(fp, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"", times[i]) < 0;
    bad |= put_escaped(fp, files[i]) < 0;
    bad |= fputs("\"/>\n", fp) < 0;
  }
  bad |= fputs("  </Collection>\n</VTKFile>\n", fp) < 0;
  int e = errno;
  if (ferror(fp)) bad = 1;
  if (fclose(fp) != 0) {
    e = errno;
    bad = 1;
  }
  if (bad) {
    remove(path);
    return bs_error_set(err, BS_EIO, "write pvd: writing '%s' failed: %s", path, strerror(e));
  }
  return BS_OK;
}
