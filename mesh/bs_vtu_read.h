/* bs_vtu_read.h — reading VTU and PVD files: those bigstep writes and those
 * ParaView (VTK) and meshio write (for `bigstep check`, the study and tests).
 *
 * Scope: VTK XML UnstructuredGrid files (VTKFile type="UnstructuredGrid")
 * with one Piece, parsed with expat. DataArrays in any of VTK's forms:
 * format="ascii" (whitespace-separated numbers), format="binary" (inline
 * base64) and format="appended" in an <AppendedData> block of encoding "raw"
 * or "base64"; uncompressed, or compressor="vtkZLibDataCompressor" (VTK's
 * zlib blocks); header_type UInt32 (VTK's default) or UInt64; either
 * byte_order (swapped when it differs from the machine's). Array types Int8
 * ... UInt64, Float32, Float64 (and the legacy names Float, Double, Int, Char,
 * UChar). Read: Points (3 components), the Cells arrays connectivity, offsets
 * and types, every PointData and CellData array; FieldData and other
 * elements are skipped. Cells must all be tetrahedra (VTK type 10) or all
 * quadratic tetrahedra (VTK type 24, VTK_QUADRATIC_TETRA: 10 nodes, the
 * order of bs_tet10.h): a file with other cells (a mesh exported with its
 * surface triangles, say) or a mix of the two is an error naming the first
 * such cell and its type, because a bs_vtu is a tet mesh whose cell data has
 * one tuple per tet. For quadratic cells, tets holds their corners (nodes
 * 0..3) and tets10 all 10 nodes.
 *
 * Every size in a file is checked before it sizes an allocation: an array
 * must hold exactly NumberOfPoints (or NumberOfCells) x NumberOfComponents
 * values, and its header's byte count must fit in the bytes that are there
 * (a zlib block may not claim more than deflate can expand), so a corrupt
 * count gives an error, not a huge allocation. Errors name the file and the
 * array, cell or attribute at fault: not VTK XML, malformed or truncated
 * XML, an unknown type, format or compressor, bad base64, a zlib error, a
 * block that runs past the end of the data, a size that does not match the
 * counts, a connectivity index outside [0, NumberOfPoints), a non-tet cell,
 * a non-finite point.
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
 *
 * Usage:
 *   bs_vtu *v = NULL;
 *   bs_error err;
 *   if (bs_vtu_read("out/frame_00010.vtu", &v, &err)) { report(err.msg); return; }
 *   const bs_vtu_array *detF = bs_vtu_cell_array(v, "detF"); // NULL if absent
 *   ... v->x[3 * i + k], v->tets[4 * t + j], detF->data[t] ...
 *   bs_vtu_destroy(&v);
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
  char type[16];       /* the VTK type: "Float64", "Int32", ... (a legacy
                          name as its modern one: "Float" is "Float32")       */
  int ncomp;           /* NumberOfComponents (1 when absent)                 */
  int64_t n_tuples;    /* n_points or n_cells                                */
  double *data;        /* ncomp * n_tuples values, tuple-major               */
} bs_vtu_array;

typedef struct bs_vtu {
  int32_t n_points;
  double *x;                   /* 3 * n_points: Points (current positions)    */
  int32_t n_cells;
  int32_t *tets;               /* 4 * n_cells: connectivity, as stored (the
                                  corners of quadratic cells)                 */
  int32_t *tets10;             /* 10 * n_cells: quadratic cells' nodes, as
                                  stored; NULL when the cells are linear      */
  const double *displacement;  /* 3 * n_points: the "displacement" point data
                                  (x - rest) when present with 3 components,
                                  else NULL; points into point_data           */
  int n_point_data;
  bs_vtu_array *point_data;
  int n_cell_data;
  bs_vtu_array *cell_data;
} bs_vtu;

/* Reads a VTU file of the scope above. */
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
