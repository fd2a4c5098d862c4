/* vti.c — a scalar field on a regular grid as VTK XML ImageData (.vti): one
 * Float64 point data array, raw appended (UInt64 byte count, then the
 * values, i fastest), with Origin, Spacing and Direction (VTK 9: the grid
 * axes in world coordinates, row-major) so that ParaView places a moved
 * grid where it is. See bs_mesh.h. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "bs_mesh.h"
#include "vtk_xml.h"

static int check_grid(const bs_vti_grid *g, const char *path, bs_error *err) {
  if (!path) return bs_error_set(err, BS_EINPUT, "write vti: path is NULL");
  if (!g || !g->values || !g->name || !g->name[0])
    return bs_error_set(err, BS_EINPUT, "write vti '%s': no grid, values or array name", path);
  for (int k = 0; k < 3; k++)
    if (g->n[k] < 1 || !isfinite(g->origin[k]))
      return bs_error_set(err, BS_EINPUT, "write vti '%s': axis %d: %d nodes, origin %g", path, k, g->n[k], g->origin[k]);
  if (!(g->h > 0) || !isfinite(g->h))
    return bs_error_set(err, BS_EINPUT, "write vti '%s': spacing h = %g must be > 0 and finite", path, g->h);
  return 0;
}

int bs_vti_write(const bs_vti_grid *g, const char *path, bs_error *err) {
  int st = check_grid(g, path, err);
  if (st) return st;
  static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double *D = g->direction ? g->direction : I;
  const uint64_t count = (uint64_t)g->n[0] * (uint64_t)g->n[1] * (uint64_t)g->n[2];
  bs_vtk_blob b;
  bs__vtk_blob_encode(&b, g->values, 8 * count, 0, g->name, err);
  FILE *fp = fopen(path, "wb");
  if (!fp) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "write vti: cannot open '%s' for writing: %s", path, strerror(e));
  }
  char ext[96];
  snprintf(ext, sizeof ext, "0 %d 0 %d 0 %d", g->n[0] - 1, g->n[1] - 1, g->n[2] - 1);
  int bad = fprintf(fp,
                    "<?xml version=\"1.0\"?>\n"
                    "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"%s\" header_type=\"UInt64\">\n"
                    "  <ImageData WholeExtent=\"%s\" Origin=\"%.17g %.17g %.17g\" Spacing=\"%.17g %.17g %.17g\"\n"
                    "             Direction=\"%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\">\n"
                    "    <Piece Extent=\"%s\">\n      <PointData Scalars=\"",
                    bs__vtk_byte_order(), ext, g->origin[0], g->origin[1], g->origin[2], g->h, g->h, g->h, D[0],
                    D[1], D[2], D[3], D[4], D[5], D[6], D[7], D[8], ext) < 0;
  bad |= bs__vtk_put_escaped(fp, g->name) < 0;
  bad |= fputs("\">\n        <DataArray type=\"Float64\" Name=\"", fp) < 0;
  bad |= bs__vtk_put_escaped(fp, g->name) < 0;
  bad |= fputs("\" format=\"appended\" offset=\"0\"/>\n      </PointData>\n      <CellData>\n      </CellData>\n"
               "    </Piece>\n  </ImageData>\n  <AppendedData encoding=\"raw\">\n",
               fp) < 0;
  bad |= bs__vtk_start_appended(fp) < 0;
  bad |= bs__vtk_blob_write(fp, &b) < 0;
  bad |= fputs("\n  </AppendedData>\n</VTKFile>\n", fp) < 0;
  return bs__vtk_close(fp, bad, "vti", path, err);
}
