/* pvtu.c — ParaView's parallel unstructured grid (.pvtu): one file that
 * names the pieces (.vtu files, one per process) and declares the arrays
 * they hold, so that ParaView opens the pieces as one data set. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "bs_mesh.h"
#include "vtk_xml.h"

static const char *type_name(bs_vtu_type t) {
  return t == BS_VTU_FLOAT64 ? "Float64" : t == BS_VTU_INT32 ? "Int32" : t == BS_VTU_UINT8 ? "UInt8" : NULL;
}

static int check_arrays(const char *path, int n, const bs_pvtu_array *a, bs_error *err) {
  for (int i = 0; i < n; i++)
    if (!a[i].name || !type_name(a[i].type) || a[i].ncomp < 1)
      return bs_error_set(err, BS_EINPUT, "write pvtu '%s': array %d (%s) has no name, an unknown type or ncomp < 1",
                          path, i, a[i].name ? a[i].name : "unnamed");
  return BS_OK;
}

static int put_arrays(FILE *fp, const char *tag, int n, const bs_pvtu_array *a) {
  int bad = fprintf(fp, "    <%s>\n", tag) < 0;
  for (int i = 0; i < n; i++) {
    bad |= fprintf(fp, "      <PDataArray type=\"%s\" Name=\"", type_name(a[i].type)) < 0;
    bad |= bs__vtk_put_escaped(fp, a[i].name) < 0;
    bad |= fprintf(fp, "\" NumberOfComponents=\"%d\"/>\n", a[i].ncomp) < 0;
  }
  bad |= fprintf(fp, "    </%s>\n", tag) < 0;
  return bad;
}

int bs_pvtu_write(const char *path, int n_point, const bs_pvtu_array *point, int n_cell, const bs_pvtu_array *cell,
                  int n_pieces, const char *const *pieces, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "write pvtu: path is NULL");
  if (n_pieces < 1 || !pieces) return bs_error_set(err, BS_EINPUT, "write pvtu '%s': no pieces", path);
  int rc = check_arrays(path, n_point, point, err);
  if (!rc) rc = check_arrays(path, n_cell, cell, err);
  for (int i = 0; !rc && i < n_pieces; i++)
    if (!pieces[i]) rc = bs_error_set(err, BS_EINPUT, "write pvtu '%s': piece %d is NULL", path, i);
  if (rc) return rc;
  FILE *fp = fopen(path, "w");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "write pvtu: cannot open '%s' for writing: %s", path, strerror(e));
  }
  int bad = fprintf(fp,
                    "<?xml version=\"1.0\"?>\n"
                    "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" header_type=\"UInt64\">\n"
                    "  <PUnstructuredGrid GhostLevel=\"0\">\n",
                    bs__vtk_byte_order()) < 0;
  bad |= put_arrays(fp, "PPointData", n_point, point);
  bad |= put_arrays(fp, "PCellData", n_cell, cell);
  bad |= fputs("    <PPoints>\n      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
               "    </PPoints>\n", fp) < 0;
  for (int i = 0; i < n_pieces && !bad; i++) {
    bad |= fputs("    <Piece Source=\"", fp) < 0;
    bad |= bs__vtk_put_escaped(fp, pieces[i]) < 0;
    bad |= fputs("\"/>\n", fp) < 0;
  }
  bad |= fputs("  </PUnstructuredGrid>\n</VTKFile>\n", fp) < 0;
  return bs__vtk_close(fp, bad, "pvtu", path, err);
}
