/* cad_assembly.c — a CAD assembly (STEP, IGES, BREP with several solids)
 * made conformal and grouped by part, inside the Gmsh session of
 * bs_mesh_read (gmsh_io.c holds the lock).
 *
 * Parts that touch or overlap are fragmented together by OpenCASCADE
 * (gmshModelOccFragment over all volumes, then synchronize): touching faces
 * become one shared face, so the tets of both parts share its nodes, and an
 * overlap becomes a piece of its own. Each input solid becomes the 3-D
 * physical group (3, n) with n = 1, 2, ... in the file's order, holding all
 * the pieces fragmentation split it into; a piece common to several parts
 * (an overlap) goes to the first of them only, so that every tet has one
 * material. A group is named after its part: the shortest trailing part of
 * the STEP label path (Gmsh's entity name, e.g. "Shapes/as1/PLATE/plate")
 * that no other part shares ("plate", "NUT::1/nut"); "part_<n>" where the
 * file names none. Every surface entity gets the 2-D group "surface_<tag>"
 * (as bs_mesh_read's default groups).
 *
 * At the file's own size (size <= 0) the mesh size follows the curvature
 * (Mesh.MeshSizeFromCurvature = 12 elements per 2 pi): at Gmsh's default
 * size the coarse triangles of a bolt and of the hole around it overlap
 * ("Invalid boundary mesh (overlapping facets)").
 *
 * An assembly meshed at its own size that stays under the quality gate is
 * meshed again whole by bs__cad_assembly_finer, with elements at most
 * BS_CAD_DIAG_FRACTION of the model's bounding-box diagonal
 * (Mesh.MeshSizeMax): a STEP file carries no sizes, and Gmsh's default
 * lets straight edges take triangles as long as a tenth of the diagonal,
 * which across a part thinner than them (a plate of 3 mm under triangles
 * of 10 to 25 mm) gives flat tets whose four vertices all lie on the
 * boundary, where no optimiser can move them. Not more elements per 2 pi:
 * where fragmentation imprints a circle tangent to an edge (a nut's outline
 * touching a bracket's edge) the face has a cusp, and the triangle at its
 * tip has an angle of about pi / N for N elements per 2 pi (15 degrees for
 * 12, 11 for 16), which bounds the tets there. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gmshc.h>

#include "mesh_internal.h"

#define BS_CAD_DIAG_FRACTION (1.0 / 40.0)

/* The trailing k components of a '/'-separated label (all of it if fewer). */
static const char *label_suffix(const char *s, int k) {
  const char *p = s + strlen(s);
  while (p > s) {
    if (p[-1] == '/' && --k == 0) return p;
    p--;
  }
  return s;
}

/* The shortest trailing part of names[i] that no other name ends with. */
static const char *unique_suffix(char *const *names, size_t n, size_t i) {
  for (int k = 1;; k++) {
    const char *si = label_suffix(names[i], k);
    int clash = 0;
    for (size_t j = 0; j < n && !clash; j++) {
      if (j == i || !names[j][0]) continue;
      const char *sj = label_suffix(names[j], k);
      clash = strcmp(si, sj) == 0;
    }
    if (!clash || si == names[i]) return si;
  }
}

static void free_names(char **names, size_t n) {
  for (size_t i = 0; names && i < n; i++) free(names[i]);
  free(names);
}

/* The label of every volume (dt: n dim/tag pairs), "" where there is none. */
static int read_names(const int *dt, size_t n, char ***out, bs_error *err) {
  char **names = calloc(n ? n : 1, sizeof *names);
  if (!names) return bs_error_set(err, BS_ENOMEM, "out of memory for %zu part names", n);
  for (size_t i = 0; i < n; i++) {
    char *name = NULL;
    int ierr = 0;
    gmshModelGetEntityName(3, dt[2 * i + 1], &name, &ierr);
    names[i] = bs__strdup(!ierr && name ? name : "");
    if (name) gmshFree(name);
    if (!names[i]) {
      free_names(names, n);
      return bs_error_set(err, BS_ENOMEM, "out of memory for %zu part names", n);
    }
  }
  *out = names;
  return BS_OK;
}

/* The physical groups: (3, i + 1) per part from the fragment map, then
 * (2, tag) "surface_<tag>" per surface entity. */
static int add_groups(const char *path, char *const *names, size_t n, int **map, const size_t *map_n,
                      bs_error *err) {
  int *ents = NULL, *taken = NULL, *sdt = NULL, ierr = 0, rc = BS_OK;
  size_t cap = 0, nsdt = 0;
  for (size_t i = 0; i < n; i++) cap += map_n[i] / 2;
  ents = malloc((cap + 1) * sizeof *ents);
  taken = calloc(cap + 1, sizeof *taken); /* piece tags already given to a part */
  if (!ents || !taken) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the part groups", path);
    goto done;
  }
  size_t n_taken = 0;
  for (size_t i = 0; i < n && !ierr; i++) {
    size_t ne = 0;
    for (size_t k = 0; k + 1 < map_n[i]; k += 2) {
      int tag = map[i][k + 1], dup = 0;
      for (size_t j = 0; j < n_taken && !dup; j++) dup = taken[j] == tag;
      if (map[i][k] != 3 || dup) continue;
      ents[ne++] = taken[n_taken++] = tag;
    }
    if (ne == 0) continue; /* wholly inside earlier parts */
    char fallback[32];
    snprintf(fallback, sizeof fallback, "part_%zu", i + 1);
    const char *name = names[i][0] ? unique_suffix(names, n, i) : fallback;
    gmshModelAddPhysicalGroup(3, ents, ne, (int)i + 1, &ierr);
    if (!ierr) gmshModelSetPhysicalName(3, (int)i + 1, name, &ierr);
  }
  if (!ierr) gmshModelGetEntities(&sdt, &nsdt, 2, &ierr);
  for (size_t j = 0; !ierr && j + 1 < nsdt; j += 2) {
    char name[32];
    snprintf(name, sizeof name, "surface_%d", sdt[j + 1]);
    gmshModelAddPhysicalGroup(2, &sdt[j + 1], 1, sdt[j + 1], &ierr);
    if (!ierr) gmshModelSetPhysicalName(2, sdt[j + 1], name, &ierr);
  }
  if (ierr) rc = bs__gmsh_fail(err, BS_EGMSH, path, "name the parts of the assembly");
done:
  free(ents);
  free(taken);
  if (sdt) gmshFree(sdt);
  return rc;
}

int bs__cad_assembly_finer(const char *path, int *done, bs_error *err) {
  double lo[3], hi[3], hmax = 0;
  int ierr = 0;
  *done = 0;
  gmshModelGetBoundingBox(-1, -1, &lo[0], &lo[1], &lo[2], &hi[0], &hi[1], &hi[2], &ierr);
  if (!ierr) gmshOptionGetNumber("Mesh.MeshSizeMax", &hmax, &ierr);
  if (ierr) return bs__gmsh_fail(err, BS_EGMSH, path, "measure the assembly's bounding box");
  double d2 = 0;
  for (int k = 0; k < 3; k++) d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
  double h = BS_CAD_DIAG_FRACTION * sqrt(d2);
  if (!(h > 0 && h < hmax)) return BS_OK; /* the sizes are already that fine */
  gmshOptionSetNumber("Mesh.MeshSizeMax", h, &ierr);
  if (!ierr) gmshOptionSetNumber("Mesh.Algorithm3D", 1, &ierr); /* Gmsh's default Delaunay, as the first time */
  if (!ierr) gmshModelMeshClear(NULL, 0, &ierr);
  if (!ierr) gmshModelMeshGenerate(3, &ierr);
  if (ierr) return bs__gmsh_fail(err, BS_EGMSH, path, "mesh the assembly again with smaller elements");
  *done = 1;
  return BS_OK;
}

int bs__cad_assembly(const char *path, double size, int *assembly, bs_error *err) {
  int *dt = NULL, *out = NULL, **map = NULL, ierr = 0, rc = BS_OK, *pg = NULL;
  *assembly = 0;
  size_t ndt = 0, nout = 0, *map_n = NULL, nmap = 0, npg = 0;
  char **names = NULL;
  gmshModelGetEntities(&dt, &ndt, 3, &ierr);
  if (!ierr) gmshModelGetPhysicalGroups(&pg, &npg, -1, &ierr);
  if (ierr) {
    rc = bs__gmsh_fail(err, BS_EGMSH, path, "list the volumes");
    goto done;
  }
  size_t n = ndt / 2;
  if (n < 2 || npg > 0) goto done; /* one solid, or the file groups its parts itself */
  if ((rc = read_names(dt, n, &names, err))) goto done;
  gmshModelOccFragment(dt, ndt, NULL, 0, &out, &nout, &map, &map_n, &nmap, -1, 1, 1, &ierr);
  if (!ierr) gmshModelOccSynchronize(&ierr);
  if (ierr || nmap < n) {
    rc = bs__gmsh_fail(err, BS_EGMSH, path, "fragment the assembly's parts (OpenCASCADE)");
    goto done;
  }
  if ((rc = add_groups(path, names, n, map, map_n, err))) goto done;
  if (size <= 0) gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 12, &ierr);
  *assembly = 1;
done:
  free_names(names, ndt / 2);
  if (dt) gmshFree(dt);
  if (pg) gmshFree(pg);
  if (out) gmshFree(out);
  for (size_t i = 0; map && i < nmap; i++) gmshFree(map[i]);
  if (map) gmshFree(map);
  if (map_n) gmshFree(map_n);
  return rc;
}
