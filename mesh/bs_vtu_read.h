/* bs_vtu_read.h — reading back the VTU and PVD files bigstep writes (for
 * `bigstep check` and for tests).
 *
 * Scope: VTK XML UnstructuredGrid files with one Piece whose DataArrays are
 * all format="appended" in an <AppendedData encoding="raw"> block (the shape
 * bs_mesh_write_vtu writes): header_type UInt64 (or UInt32, VTK's default),
 * either byte order (swapped when it differs from the machine's), no
 * compressor. Array types Int8 ... UInt64, Float32, Float64. Cells must all be
 * tetrahedra (VTK type 10, four vertices each). Anything else (inline ascii or
 * base64 arrays, compressed data, other cell types, a block that runs past
 * the end of the file, a missing closing tag) is an error naming the file and
 * the array, cell or attribute at fault.
 *
 * Values: Points and the arrays are converted to double (exact for every
 * Float32/Float64 value and every integer up to 2^53 in magnitude); a Float64
 * array is copied bit for bit. Connectivity is converted to int32_t with a
 * range check. Units are those of the file (metres for bigstep's output).
 *
 * Ownership: bs_vtu_read and bs_pvd_read return objects the caller frees with
 * bs_vtu_destroy / bs_pvd_destroy; every array inside is owned by them. The
 * look-up functions return pointers into the object (valid until destroy).
 *
 * Status: BS_OK, or BS_EIO (missing or unreadable file), BS_EINPUT (not a
 * VTU/PVD file, or malformed), BS_ENUMERIC (a non-finite point coordinate),
 * BS_ENOMEM; the message names the file and what is malformed.
 */
#ifndef BS_VTU_READ_H
#define BS_VTU_READ_H

#include <stdint.h>

#include "bs_base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One PointData or CellData array. */
typedef struct bs_vtu_array {
  char *name;          /* the Name attribute (never NULL, may be "")          */
  char type[16];       /* the VTK type as written: "Float64", "Int32", ...   */
  int ncomp;           /* NumberOfComponents (1 when absent)                 */
  int64_t n_tuples;    /* n_points or n_cells                                */
  double *data;        /* ncomp * n_tuples values, tuple-major               */
} bs_vtu_array;

typedef struct bs_vtu {
  int32_t n_points;
  double *x;                   /* 3 * n_points: Points (current positions)    */
  int32_t n_cells;
  int32_t *tets;               /* 4 * n_cells: connectivity, as stored        */
  const double *displacement;  /* 3 * n_points: the "displacement" point data
                                  (x - rest) when present with 3 components,
                                  else NULL; points into point_data           */
  int n_point_data;
  bs_vtu_array *point_data;
  int n_cell_data;
  bs_vtu_array *cell_data;
} bs_vtu;

/* Reads a VTU file written by bs_mesh_write_vtu (or of the shape above). */
int bs_vtu_read(const char *path, bs_vtu **out, bs_error *err);

/* Frees a VTU (NULL or *v == NULL is fine) and sets *v = NULL. */
void bs_vtu_destroy(bs_vtu **v);

/* The point / cell data array with this name, or NULL. */
const bs_vtu_array *bs_vtu_point_array(const bs_vtu *v, const char *name);
const bs_vtu_array *bs_vtu_cell_array(const bs_vtu *v, const char *name);

/* Rest positions rest = x - displacement (3 * n_points doubles, caller's
 * buffer). BS_EINPUT when the file has no 3-component "displacement" point
 * data; BS_ENUMERIC when a rest coordinate is not finite (names the point).
 * `path` only names the file in messages (may be NULL). */
int bs_vtu_rest(const bs_vtu *v, const char *path, double *rest, bs_error *err);

/* A PVD collection: the DataSet entries in file order. */
typedef struct bs_pvd {
  int n;
  double *times;   /* the timestep attribute (0 when absent)                 */
  char **files;    /* the file attribute, XML entities decoded, resolved
                      against the PVD's folder unless absolute                */
} bs_pvd;

/* Reads a PVD (VTKFile type="Collection") file. */
int bs_pvd_read(const char *path, bs_pvd **out, bs_error *err);

/* Frees a PVD (NULL or *p == NULL is fine) and sets *p = NULL. */
void bs_pvd_destroy(bs_pvd **p);

#ifdef __cplusplus
}
#endif
#endif
