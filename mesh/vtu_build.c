/* vtu_build.c — a parsed VTU document (vtu_read.c) into a bs_vtu: which
 * array is which, the size each must have, points, tetrahedra, point and cell
 * data; and the bs_vtu object's accessors. See bs_vtu_read.h.
 *
 * Every array is decoded with the byte count its declaration and the Piece's
 * counts give (tuples x components x value size), and that count is checked
 * against the bytes in the file before anything is allocated for it. The
 * connectivity's length follows from the offsets (4 per tetrahedron). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vtu_internal.h"

enum { VTK_TETRA = 10, VTK_QUADRATIC_TETRA = 24 };

static const char *section_name(bs__vtu_section s) {
  switch (s) {
    case BS__VTU_POINTDATA: return "PointData";
    case BS__VTU_CELLDATA: return "CellData";
    case BS__VTU_POINTS: return "Points";
    case BS__VTU_CELLS: return "Cells";
    default: return "FieldData";
  }
}

/* The arrays by role. */
typedef struct roles {
  const bs__vtu_decl *pts, *conn, *offs, *types;
  int n_pd, n_cd;
} roles;

static int cells_role(const char *path, const bs__vtu_decl *a, roles *r, bs_error *err) {
  const bs__vtu_decl **slot = !strcmp(a->name, "connectivity") ? &r->conn
                              : !strcmp(a->name, "offsets")    ? &r->offs
                              : !strcmp(a->name, "types")      ? &r->types
                                                               : NULL;
  if (!slot) return BS_OK; /* faces, faceoffsets: not read */
  if (*slot) return bs_error_set(err, BS_EINPUT, "'%s': two Cells arrays named '%s'", path, a->name);
  if (bs__vtu_type_is_float(a->type))
    return bs_error_set(err, BS_EINPUT, "'%s': Cells array '%s' has type %s, expected an integer type", path,
                        a->name, bs__vtu_type_name(a->type));
  if (a->ncomp != 1)
    return bs_error_set(err, BS_EINPUT, "'%s': Cells array '%s' has %d components, expected 1", path, a->name,
                        a->ncomp);
  *slot = a;
  return BS_OK;
}

static int find_roles(const char *path, const bs__vtu_doc *d, roles *r, bs_error *err) {
  memset(r, 0, sizeof *r);
  if (d->n_piece == 0) return bs_error_set(err, BS_EINPUT, "'%s' has no <Piece>", path);
  for (int i = 0; i < d->n_arr; i++) {
    const bs__vtu_decl *a = &d->arr[i];
    int rc = BS_OK;
    if (a->section == BS__VTU_POINTDATA) r->n_pd++;
    else if (a->section == BS__VTU_CELLDATA) r->n_cd++;
    else if (a->section == BS__VTU_CELLS) rc = cells_role(path, a, r, err);
    else if (a->section == BS__VTU_POINTS && r->pts)
      rc = bs_error_set(err, BS_EINPUT, "'%s': <Points> holds more than one array", path);
    else if (a->section == BS__VTU_POINTS) r->pts = a;
    if (rc) return rc;
  }
  if (!r->pts && d->n_points > 0) return bs_error_set(err, BS_EINPUT, "'%s' has no Points array", path);
  if (r->pts && r->pts->ncomp != 3)
    return bs_error_set(err, BS_EINPUT, "'%s': the Points array has %d components, expected 3", path, r->pts->ncomp);
  if (d->n_cells > 0 && (!r->conn || !r->offs || !r->types))
    return bs_error_set(err, BS_EINPUT, "'%s': <Cells> lacks the '%s' array", path,
                        !r->conn ? "connectivity" : !r->offs ? "offsets" : "types");
  return BS_OK;
}

/* The values of array a, `tuples` tuples of its components; the message
 * names the file and the array. */
static int values(const char *path, const bs__vtu_doc *d, const bs__vtu_decl *a, int64_t tuples,
                  const unsigned char **data, unsigned char **owned, bs_error *err) {
  const uint64_t expect = (uint64_t)tuples * (uint64_t)a->ncomp * (uint64_t)bs__vtu_type_size(a->type);
  int rc = bs__vtu_array_bytes(d, a, expect, data, owned, err);
  if (rc)
    bs_error_prefix(err, "'%s': %s array '%s' (%lld x %d %s)", path, section_name(a->section), a->name,
                    (long long)tuples, a->ncomp, bs__vtu_type_name(a->type));
  return rc;
}

static int read_points(const char *path, const bs__vtu_doc *d, const bs__vtu_decl *a, bs_vtu *v, bs_error *err) {
  const size_t n = 3 * (size_t)d->n_points;
  const unsigned char *data = NULL;
  unsigned char *owned = NULL;
  int rc = n ? values(path, d, a, d->n_points, &data, &owned, err) : BS_OK;
  if (rc) return rc;
  v->x = malloc(n * sizeof(double) + 1);
  if (!v->x) {
    free(owned);
    return bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory for %zu points", path, n / 3);
  }
  v->n_points = (int32_t)d->n_points;
  if (n) bs__vtu_to_doubles(data, a->type, n, v->x);
  free(owned);
  for (int32_t i = 0; i < v->n_points; i++) {
    const double *q = v->x + 3 * (size_t)i;
    if (!isfinite(q[0]) || !isfinite(q[1]) || !isfinite(q[2]))
      return bs_error_set(err, BS_ENUMERIC, "'%s': point %d has a non-finite coordinate (%g, %g, %g)", path, i, q[0],
                          q[1], q[2]);
  }
  return BS_OK;
}

/* Every cell a tetrahedron, all of one kind: types all 10 (4 nodes) or all
 * 24 (VTK_QUADRATIC_TETRA, 10 nodes); offsets k, 2k, 3k, ... Sets *nodes. */
static int check_cells(const char *path, const bs__vtu_doc *d, const roles *r, int *nodes, bs_error *err) {
  const int64_t nc = d->n_cells;
  const unsigned char *data;
  unsigned char *owned;
  int rc = values(path, d, r->types, nc, &data, &owned, err);
  int64_t first = 0;
  for (int64_t c = 0; c < nc && !rc; c++) {
    int64_t ty;
    if (bs__vtu_get_int(data, r->types->type, (size_t)c, &ty) || (ty != VTK_TETRA && ty != VTK_QUADRATIC_TETRA))
      rc = bs_error_set(err, BS_EINPUT, "'%s': cell %lld has VTK type %g; only tetrahedra (10) and quadratic tetrahedra (24) are read", path,
                        (long long)c, bs__vtu_get_double(data, r->types->type, (size_t)c));
    else if (c == 0)
      first = ty;
    else if (ty != first)
      rc = bs_error_set(err, BS_EINPUT, "'%s': cell %lld has VTK type %lld but cell 0 has type %lld: a mesh of one kind of tetrahedron is read",
                        path, (long long)c, (long long)ty, (long long)first);
  }
  free(owned);
  if (rc) return rc;
  const int k = first == VTK_QUADRATIC_TETRA ? 10 : 4;
  *nodes = k;
  rc = values(path, d, r->offs, nc, &data, &owned, err);
  for (int64_t c = 0; c < nc && !rc; c++) {
    int64_t o;
    if (bs__vtu_get_int(data, r->offs->type, (size_t)c, &o) || o != k * (c + 1))
      rc = bs_error_set(err, BS_EINPUT, "'%s': cell %lld ends at connectivity offset %g, expected %lld (%d nodes per %s)",
                        path, (long long)c, bs__vtu_get_double(data, r->offs->type, (size_t)c),
                        (long long)(k * (c + 1)), k, k == 10 ? "quadratic tetrahedron" : "tetrahedron");
  }
  free(owned);
  return rc;
}

/* The connectivity (k nodes per cell) into conn, range-checked. */
static int read_conn(const char *path, const bs__vtu_doc *d, const roles *r, int k, int32_t *conn, bs_error *err) {
  const int64_t nc = d->n_cells;
  const unsigned char *data;
  unsigned char *owned;
  int rc = values(path, d, r->conn, k * nc, &data, &owned, err);
  if (rc) return rc;
  for (int64_t i = 0; i < k * nc && !rc; i++) {
    int64_t id;
    if (bs__vtu_get_int(data, r->conn->type, (size_t)i, &id) || id < 0 || id >= d->n_points)
      rc = bs_error_set(err, BS_EINPUT, "'%s': cell %lld %s %d is %g, outside [0, %lld)", path, (long long)(i / k),
                        k == 10 ? "node" : "vertex", (int)(i % k), bs__vtu_get_double(data, r->conn->type, (size_t)i), (long long)d->n_points);
    else
      conn[i] = (int32_t)id;
  }
  free(owned);
  return rc;
}

static int read_cells(const char *path, const bs__vtu_doc *d, const roles *r, bs_vtu *v, bs_error *err) {
  const int64_t nc = d->n_cells;
  int k = 4;
  int rc = nc ? check_cells(path, d, r, &k, err) : BS_OK; /* the types hold nc cells: nc is not a bare count */
  if (rc) return rc;
  v->tets = malloc(4 * (size_t)nc * sizeof(int32_t) + 1);
  if (k == 10) v->tets10 = malloc(10 * (size_t)nc * sizeof(int32_t) + 1);
  if (!v->tets || (k == 10 && !v->tets10))
    return bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory for %lld cells", path, (long long)nc);
  v->n_cells = (int32_t)nc;
  if (nc == 0) return BS_OK;
  if ((rc = read_conn(path, d, r, k, k == 10 ? v->tets10 : v->tets, err))) return rc;
  if (k == 10)
    for (int64_t c = 0; c < nc; c++) memcpy(v->tets + 4 * c, v->tets10 + 10 * c, 4 * sizeof(int32_t));
  return BS_OK;
}

/* Point and cell data, in file order (takes the names out of d). */
static int read_data(const char *path, bs__vtu_doc *d, bs_vtu *v, bs_error *err) {
  for (int i = 0; i < d->n_arr; i++) {
    bs__vtu_decl *a = &d->arr[i];
    if (a->section != BS__VTU_POINTDATA && a->section != BS__VTU_CELLDATA) continue;
    const int pd = a->section == BS__VTU_POINTDATA;
    const int64_t tuples = pd ? d->n_points : d->n_cells;
    const unsigned char *data;
    unsigned char *owned;
    int rc = values(path, d, a, tuples, &data, &owned, err);
    if (rc) return rc;
    bs_vtu_array *o = pd ? &v->point_data[v->n_point_data] : &v->cell_data[v->n_cell_data];
    const size_t n = (size_t)tuples * (size_t)a->ncomp;
    o->data = malloc(n * sizeof(double) + 1);
    if (!o->data) {
      free(owned);
      return bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory for array '%s'", path, a->name);
    }
    bs__vtu_to_doubles(data, a->type, n, o->data);
    free(owned);
    o->name = a->name;
    a->name = NULL;
    snprintf(o->type, sizeof o->type, "%s", bs__vtu_type_name(a->type));
    o->ncomp = a->ncomp;
    o->n_tuples = tuples;
    if (pd) v->n_point_data++;
    else v->n_cell_data++;
  }
  return BS_OK;
}

int bs__vtu_build(const char *path, bs__vtu_doc *d, bs_vtu **out, bs_error *err) {
  roles r;
  int rc = find_roles(path, d, &r, err);
  if (rc) return rc;
  bs_vtu *v = calloc(1, sizeof *v);
  if (v) v->point_data = calloc((size_t)r.n_pd + 1, sizeof *v->point_data);
  if (v) v->cell_data = calloc((size_t)r.n_cd + 1, sizeof *v->cell_data);
  if (!v || !v->point_data || !v->cell_data) rc = bs_error_set(err, BS_ENOMEM, "reading '%s': out of memory", path);
  if (!rc) rc = read_points(path, d, r.pts, v, err);
  if (!rc) rc = read_cells(path, d, &r, v, err);
  if (!rc) rc = read_data(path, d, v, err);
  if (rc) {
    bs_vtu_destroy(&v);
    return rc;
  }
  const bs_vtu_array *disp = bs_vtu_point_array(v, "displacement");
  v->displacement = disp && disp->ncomp == 3 ? disp->data : NULL;
  *out = v;
  return BS_OK;
}

/* ---- the bs_vtu object ------------------------------------------------------- */

void bs_vtu_destroy(bs_vtu **pv) {
  if (!pv || !*pv) return;
  bs_vtu *v = *pv;
  free(v->x);
  free(v->tets);
  free(v->tets10);
  for (int i = 0; i < v->n_point_data; i++) {
    free(v->point_data[i].name);
    free(v->point_data[i].data);
  }
  for (int i = 0; i < v->n_cell_data; i++) {
    free(v->cell_data[i].name);
    free(v->cell_data[i].data);
  }
  free(v->point_data);
  free(v->cell_data);
  free(v);
  *pv = NULL;
}

static const bs_vtu_array *find_array(const bs_vtu_array *a, int n, const char *name) {
  if (!name) return NULL;
  for (int i = 0; i < n; i++)
    if (!strcmp(a[i].name, name)) return &a[i];
  return NULL;
}

const bs_vtu_array *bs_vtu_point_array(const bs_vtu *v, const char *name) {
  return v ? find_array(v->point_data, v->n_point_data, name) : NULL;
}

const bs_vtu_array *bs_vtu_cell_array(const bs_vtu *v, const char *name) {
  return v ? find_array(v->cell_data, v->n_cell_data, name) : NULL;
}

int bs_vtu_rest(const bs_vtu *v, const char *path, double *rest, bs_error *err) {
  const char *f = path ? path : "vtu";
  if (!v || !rest) return bs_error_set(err, BS_EINPUT, "'%s': rest positions: NULL argument", f);
  if (!v->displacement)
    return bs_error_set(err, BS_EINPUT,
                        "'%s' has no 3-component 'displacement' point data: the rest shape cannot be recovered", f);
  for (int32_t i = 0; i < v->n_points; i++)
    for (int k = 0; k < 3; k++) {
      double r = v->x[3 * (size_t)i + k] - v->displacement[3 * (size_t)i + k];
      if (!isfinite(r))
        return bs_error_set(err, BS_ENUMERIC, "'%s': point %d has a non-finite displacement or rest coordinate", f,
                            i);
      rest[3 * (size_t)i + k] = r;
    }
  return BS_OK;
}
