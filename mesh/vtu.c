/* vtu.c — ParaView output: VTK XML UnstructuredGrid files (.vtu) of tet
 * meshes and of triangle surfaces, and collections (.pvd).
 *
 * A .vtu keeps all arrays in one <AppendedData encoding="raw"> block after
 * a '_' marker, each raw or zlib-compressed (vtk_xml.h: the layouts, and
 * bs_mesh.h). Order, in the XML and in the block: PointData, CellData,
 * Points (Float64 x 3), connectivity and offsets (Int64), types (UInt8: 10
 * VTK_TETRA, 24 VTK_QUADRATIC_TETRA for a quadratic mesh, 5 VTK_TRIANGLE). Arrays the caller holds are written from its
 * memory; converted ones (displacement, connectivity, ...) from one buffer
 * filled first, so every array is one fwrite. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_mesh.h"
#include "vtk_xml.h"

enum { VTK_TRIANGLE = 5, VTK_TETRA = 10, VTK_QUADRATIC_TETRA = 24 };

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

/* ---- an unstructured grid to write ---------------------------------------- */

enum { SEC_POINT_DATA, SEC_CELL_DATA, SEC_POINTS, SEC_CELLS };

typedef struct out_array {
  const char *name, *type;
  int ncomp, section;
  bs_vtk_blob blob;
  uint64_t offset;
} out_array;

typedef struct ugrid {
  int64_t n_points, n_cells;
  int compress;
  int n, cap;
  out_array *a;       /* in writing order: sections ascending             */
  const char *vectors, *scalars; /* PointData Vectors / CellData Scalars   */
  unsigned char *buf; /* the converted topology (connectivity, offsets, types) */
  unsigned char *data;/* the converted data arrays                          */
} ugrid;

static const char *type_name(bs_vtu_type t) {
  switch (t) {
    case BS_VTU_FLOAT64: return "Float64";
    case BS_VTU_INT32: return "Int32";
    case BS_VTU_UINT8: return "UInt8";
  }
  return NULL;
}

static size_t type_size(bs_vtu_type t) { return t == BS_VTU_FLOAT64 ? 8 : t == BS_VTU_INT32 ? 4 : 1; }

/* Appends an array (encoded at once when the grid is compressed). */
static int ug_add(ugrid *g, int section, const char *name, const char *type, int ncomp, const void *data,
                  uint64_t bytes, bs_error *err) {
  if (g->n == g->cap) {
    int cap = g->cap ? 2 * g->cap : 16;
    out_array *a = realloc(g->a, sizeof *a * (size_t)cap);
    if (!a) return bs_error_set(err, BS_ENOMEM, "out of memory");
    g->a = a;
    g->cap = cap;
  }
  out_array *o = &g->a[g->n];
  *o = (out_array){.name = name, .type = type, .ncomp = ncomp, .section = section};
  int st = bs__vtk_blob_encode(&o->blob, data, bytes, g->compress, name, err);
  if (!st) g->n++;
  return st;
}

/* Appends the caller's arrays of one section (n_tuples each), checked. */
static int ug_add_given(ugrid *g, int section, int n, const bs_vtu_data *d, int64_t n_tuples, bs_error *err) {
  const char *what = section == SEC_POINT_DATA ? "point" : "cell";
  if (n > 0 && !d) return bs_error_set(err, BS_EINPUT, "%d %s data arrays but no array list", n, what);
  for (int i = 0; i < n; i++) {
    const char *tn = type_name(d[i].type);
    if (!d[i].name || !d[i].name[0]) return bs_error_set(err, BS_EINPUT, "%s data array %d has no name", what, i);
    if (!tn || d[i].ncomp < 1 || (!d[i].data && n_tuples > 0))
      return bs_error_set(err, BS_EINPUT, "%s data '%s': %s", what, d[i].name,
                          !tn ? "unknown type" : d[i].ncomp < 1 ? "NumberOfComponents < 1" : "no data");
    uint64_t bytes = (uint64_t)n_tuples * (uint64_t)d[i].ncomp * type_size(d[i].type);
    int st = ug_add(g, section, d[i].name, tn, d[i].ncomp, d[i].data, bytes, err);
    if (st) return st;
  }
  return 0;
}

/* Points, then connectivity, offsets and types of n_cells cells of k
 * vertices each (cells: k int32 per cell) into buf (32 k + 9 bytes a cell). */
static int ug_add_topology(ugrid *g, const double *x, int k, const int32_t *cells, int vtk_type, unsigned char *buf,
                           bs_error *err) {
  const int64_t nc = g->n_cells;
  int64_t *conn = (int64_t *)buf, *offs = conn + k * nc;
  unsigned char *types = (unsigned char *)(offs + nc);
  for (int64_t i = 0; i < k * nc; i++) conn[i] = cells[i];
  for (int64_t c = 0; c < nc; c++) offs[c] = k * (c + 1);
  memset(types, vtk_type, (size_t)nc);
  int st = ug_add(g, SEC_POINTS, "Points", "Float64", 3, x, 24u * (uint64_t)g->n_points, err);
  if (!st) st = ug_add(g, SEC_CELLS, "connectivity", "Int64", 1, conn, 8u * (uint64_t)(k * nc), err);
  if (!st) st = ug_add(g, SEC_CELLS, "offsets", "Int64", 1, offs, 8u * (uint64_t)nc, err);
  if (!st) st = ug_add(g, SEC_CELLS, "types", "UInt8", 1, types, (uint64_t)nc, err);
  return st;
}

static void ug_free(ugrid *g) {
  for (int i = 0; i < g->n; i++) bs__vtk_blob_free(&g->a[i].blob);
  free(g->a);
  free(g->buf);
  free(g->data);
  memset(g, 0, sizeof *g);
}

/* The XML of one DataArray. */
static int put_array(FILE *fp, const out_array *a) {
  int bad = fprintf(fp, "        <DataArray type=\"%s\" Name=\"", a->type) < 0;
  bad |= bs__vtk_put_escaped(fp, a->name) < 0;
  if (a->ncomp > 1) bad |= fprintf(fp, "\" NumberOfComponents=\"%d", a->ncomp) < 0;
  bad |= fprintf(fp, "\" format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)a->offset) < 0;
  return bad;
}

/* The XML header and the '_' marker (after bs__vtk_start_appended's
 * padding), with the sections' tags. */
static int put_header(FILE *fp, const ugrid *g) {
  static const char *const open[] = {"PointData", "CellData", "Points", "Cells"};
  int bad = fprintf(fp,
                    "<?xml version=\"1.0\"?>\n"
                    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" header_type=\"UInt64\"%s>\n"
                    "  <UnstructuredGrid>\n"
                    "    <Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n",
                    bs__vtk_byte_order(), g->compress ? " compressor=\"vtkZLibDataCompressor\"" : "",
                    (long long)g->n_points, (long long)g->n_cells) < 0;
  int i = 0;
  for (int sec = SEC_POINT_DATA; sec <= SEC_CELLS; sec++) {
    const char *attr = sec == SEC_POINT_DATA ? g->vectors : sec == SEC_CELL_DATA ? g->scalars : NULL;
    bad |= fprintf(fp, "      <%s", open[sec]) < 0;
    if (attr) bad |= fprintf(fp, " %s=\"%s\"", sec == SEC_POINT_DATA ? "Vectors" : "Scalars", attr) < 0;
    bad |= fputs(">\n", fp) < 0;
    for (; i < g->n && g->a[i].section == sec; i++) bad |= put_array(fp, &g->a[i]);
    bad |= fprintf(fp, "      </%s>\n", open[sec]) < 0;
  }
  bad |= fputs("    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n", fp) < 0;
  bad |= bs__vtk_start_appended(fp) < 0;
  return bad;
}

/* Offsets, header, blocks, trailer. `what` names the writer in messages. */
static int ug_write(ugrid *g, const char *what, const char *path, bs_error *err) {
  uint64_t off = 0;
  for (int i = 0; i < g->n; i++) {
    g->a[i].offset = off;
    off += g->a[i].blob.encoded;
  }
  FILE *fp = fopen(path, "wb");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "write %s: cannot open '%s' for writing: %s", what, path, strerror(e));
  }
  int bad = put_header(fp, g);
  for (int i = 0; i < g->n && !bad; i++) bad |= bs__vtk_blob_write(fp, &g->a[i].blob);
  bad |= fputs("\n  </AppendedData>\n</VTKFile>\n", fp) < 0;
  return bs__vtk_close(fp, bad, what, path, err);
}

/* ---- tet meshes ------------------------------------------------------------ */

/* Fills the converted arrays of a tet mesh into g->data: displacement, then
 * (unless custom_cells) detF, material and inverted. */
static int tet_builtins(const bs_mesh *m, const bs_vtu_fields *f, const double *x, ugrid *g, bs_error *err) {
  const int32_t nv = m->n_vertices, nt = m->n_tets;
  const size_t cells = f->custom_cells ? 0 : 13u * (size_t)nt;
  unsigned char *b = g->data = malloc(24u * (size_t)nv + cells + 8);
  if (!b) return bs_error_set(err, BS_ENOMEM, "out of memory (%d vertices, %d tets)", nv, nt);
  double *disp = (double *)b, *detF = disp + 3 * (size_t)nv;
  for (size_t i = 0; i < 3 * (size_t)nv; i++) disp[i] = x[i] - m->x[i];
  int st = ug_add(g, SEC_POINT_DATA, "displacement", "Float64", 3, disp, 24u * (uint64_t)nv, err);
  if (!st && f->velocity) st = ug_add(g, SEC_POINT_DATA, "velocity", "Float64", 3, f->velocity, 24u * (uint64_t)nv, err);
  if (!st) st = ug_add_given(g, SEC_POINT_DATA, f->n_point_data, f->point_data, nv, err);
  if (st || f->custom_cells) return st;
  int32_t *mat = (int32_t *)(detF + nt);
  uint8_t *inv = (uint8_t *)(mat + nt);
  for (int32_t t = 0; t < nt; t++) {
    const int32_t *tv = m->tets + 4 * (size_t)t;
    detF[t] = f->cell_detF ? f->cell_detF[t] : x == m->x ? 1.0 : tet_vol6(x, tv) / tet_vol6(m->x, tv);
    mat[t] = m->material ? m->material[t] : 0;
    inv[t] = !(detF[t] > 0.0); /* a NaN detF counts as inverted too */
  }
  st = ug_add(g, SEC_CELL_DATA, "material", "Int32", 1, mat, 4u * (uint64_t)nt, err);
  if (!st) st = ug_add(g, SEC_CELL_DATA, "detF", "Float64", 1, detF, 8u * (uint64_t)nt, err);
  if (!st) st = ug_add(g, SEC_CELL_DATA, "inverted", "UInt8", 1, inv, (uint64_t)nt, err);
  return st;
}

int bs_mesh_write_vtu(const bs_mesh *m, const bs_vtu_fields *f, const char *path, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "write vtu: path is NULL");
  if (!m || !m->x || (m->n_tets > 0 && !m->tets))
    return bs_error_set(err, BS_EINPUT, "write vtu '%s': mesh is NULL or empty", path);
  const bs_vtu_fields none = {0};
  if (!f) f = &none;
  const double *x = f->x ? f->x : m->x;
  ugrid g = {.n_points = m->n_vertices, .n_cells = m->n_tets, .compress = f->compress, .vectors = "displacement"};
  if (!f->custom_cells) g.scalars = "material";
  const int k = m->tets10 ? 10 : 4; /* a quadratic mesh: its 10-node cells */
  g.buf = malloc((8u * (unsigned)k + 9u) * (size_t)m->n_tets + 8);
  int st = g.buf ? 0 : bs_error_set(err, BS_ENOMEM, "out of memory (%d tets)", m->n_tets);
  if (!st) st = tet_builtins(m, f, x, &g, err);
  if (!st) st = ug_add_given(&g, SEC_CELL_DATA, f->n_cell_data, f->cell_data, m->n_tets, err);
  if (!st)
    st = ug_add_topology(&g, x, k, m->tets10 ? m->tets10 : m->tets, m->tets10 ? VTK_QUADRATIC_TETRA : VTK_TETRA, g.buf,
                         err);
  if (!st) st = ug_write(&g, "vtu", path, err);
  else bs_error_prefix(err, "write vtu '%s'", path);
  ug_free(&g);
  return st;
}

/* ---- triangle surfaces ----------------------------------------------------- */

int bs_surface_write_vtu(const bs_vtu_surface *s, const char *path, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "write surface vtu: path is NULL");
  if (!s || s->n_points < 0 || s->n_tris < 0 || (s->n_points > 0 && !s->x) || (s->n_tris > 0 && !s->tris))
    return bs_error_set(err, BS_EINPUT, "write surface vtu '%s': no points or triangles", path);
  for (int64_t i = 0; i < 3 * (int64_t)s->n_tris; i++)
    if (s->tris[i] < 0 || s->tris[i] >= s->n_points)
      return bs_error_set(err, BS_EINPUT, "write surface vtu '%s': triangle %lld uses point %d of %d", path,
                          (long long)(i / 3), s->tris[i], s->n_points);
  ugrid g = {.n_points = s->n_points, .n_cells = s->n_tris, .compress = s->compress};
  g.buf = malloc(33u * (size_t)s->n_tris + 8);
  int st = g.buf ? 0 : bs_error_set(err, BS_ENOMEM, "out of memory (%d triangles)", s->n_tris);
  if (!st) st = ug_add_given(&g, SEC_POINT_DATA, s->n_point_data, s->point_data, s->n_points, err);
  if (!st) st = ug_add_given(&g, SEC_CELL_DATA, s->n_cell_data, s->cell_data, s->n_tris, err);
  if (!st) st = ug_add_topology(&g, s->x, 3, s->tris, VTK_TRIANGLE, g.buf, err);
  if (!st) st = ug_write(&g, "surface vtu", path, err);
  else bs_error_prefix(err, "write surface vtu '%s'", path);
  ug_free(&g);
  return st;
}

/* ---- collections ----------------------------------------------------------- */

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
                 bs__vtk_byte_order()) < 0;
  for (int i = 0; i < n && !bad; i++) {
    bad |= fprintf(fp, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"", times[i]) < 0;
    bad |= bs__vtk_put_escaped(fp, files[i]) < 0;
    bad |= fputs("\"/>\n", fp) < 0;
  }
  bad |= fputs("  </Collection>\n</VTKFile>\n", fp) < 0;
  return bs__vtk_close(fp, bad, "pvd", path, err);
}
