/* gmsh_optimize.c — Gmsh's tet optimisers run towards the quality gate
 * (bs__gmsh_optimize_to_gate, see mesh_internal.h), inside the caller's Gmsh
 * session (gmsh_io.c holds the lock).
 *
 * Each round runs gmshModelMeshOptimize with "" (Gmsh's own optimiser) then
 * "Netgen" (when Gmsh has it and it succeeds), with Mesh.OptimizeThreshold (the gamma quality under which a tet
 * is worked on) raised from 0.3 by 0.1 a round, and stops when the smallest
 * dihedral angle of the model's tets reaches the gate, or a round improves
 * it by less than 0.01 degree, or after BS_GMSH_ROUNDS rounds. A mesh still
 * under the gate then has its volume meshed again by HXT (Mesh.Algorithm3D
 * 10), its surfaces' triangles kept, and optimised the same way: on
 * data/geo, Gmsh's default Delaunay left a 2.8 degree tet in beam.geo and 1.5
 * in bracket.geo that no optimiser moved (all four vertices on the
 * boundary); HXT gives 18.6 and 16.6, and 13.7 to 16.2 on the others.
 */
#include <float.h>
#include <stdlib.h>

#include <gmshc.h>

#include "mesh_internal.h"

#define BS_GMSH_ROUNDS 4
enum { GMSH_TET4 = 4 };

/* Smallest dihedral angle (degrees) of the model's 4-node tets; DBL_MAX when
 * there are none; -1 when the node tags are too sparse for a table. */
static double model_min_dihedral(const char *path, bs_error *err, int *rc) {
  size_t *ntags = NULL, nn = 0, nc = 0, np = 0, *et = NULL, ne = 0, *en = NULL, nen = 0, max_tag = 0;
  double *coord = NULL, *par = NULL, worst = DBL_MAX;
  int ierr = 0;
  int64_t *row = NULL;
  *rc = BS_OK;
  gmshModelMeshGetNodes(&ntags, &nn, &coord, &nc, &par, &np, -1, -1, 0, 0, &ierr);
  if (!ierr) gmshModelMeshGetElementsByType(GMSH_TET4, &et, &ne, &en, &nen, -1, 0, 1, &ierr);
  if (ierr) {
    *rc = bs_error_set(err, BS_EGMSH, "%s: Gmsh could not list the mesh to measure it", path);
    goto done;
  }
  for (size_t i = 0; i < nn; i++)
    if (ntags[i] > max_tag) max_tag = ntags[i];
  if (max_tag > 8 * nn + 1024) {
    worst = -1;
    goto done;
  }
  row = malloc((max_tag + 1) * sizeof *row);
  if (!row) {
    *rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the node table", path);
    goto done;
  }
  for (size_t i = 0; i <= max_tag; i++) row[i] = -1;
  for (size_t i = 0; i < nn; i++) row[ntags[i]] = (int64_t)i;
  for (size_t e = 0; e < ne && nen == 4 * ne; e++) {
    const double *p[4];
    for (int k = 0; k < 4; k++) {
      size_t tag = en[4 * e + k];
      p[k] = tag <= max_tag && row[tag] >= 0 ? coord + 3 * row[tag] : coord;
    }
    bs__tet_measures q;
    bs__tet_quality(p, &q);
    if (q.dihedral_min < worst) worst = q.dihedral_min;
  }
done:
  free(row);
  if (ntags) gmshFree(ntags);
  if (coord) gmshFree(coord);
  if (par) gmshFree(par);
  if (et) gmshFree(et);
  if (en) gmshFree(en);
  return worst;
}

/* The optimiser rounds from the mesh's smallest angle *best on; *best is
 * the angle of the mesh they leave (a round that made it worse ends the
 * rounds and is not undone, so the angle is the mesh's, not the best seen). */
static int optimise_rounds(const char *path, double gate, double *best, bs_error *err) {
  int rc = BS_OK, ierr = 0, netgen = 1;
  for (int r = 0; !rc && *best >= 0 && *best < gate && r < BS_GMSH_ROUNDS; r++) {
    gmshOptionSetNumber("Mesh.OptimizeThreshold", 0.3 + 0.1 * r, &ierr);
    gmshModelMeshOptimize("", 0, 1, NULL, 0, &ierr);
    if (ierr) return bs_error_set(err, BS_EGMSH, "%s: Gmsh could not optimise the mesh", path);
    if (netgen) gmshModelMeshOptimize("Netgen", 0, 1, NULL, 0, &ierr);
    if (ierr) netgen = 0, ierr = 0; /* Gmsh built without Netgen, or it gave up: Gmsh's own optimiser goes on */
    double now = model_min_dihedral(path, err, &rc);
    int stalled = now < *best + 0.01;
    *best = now;
    if (rc || stalled) break;
  }
  return rc;
}

int bs__gmsh_optimize_to_gate(const char *path, double gate, double *achieved, bs_error *err) {
  int rc = BS_OK, ierr = 0;
  double best = model_min_dihedral(path, err, &rc);
  if (!rc) rc = optimise_rounds(path, gate, &best, err);
  /* Still under the gate: the volume again with HXT (the surfaces' mesh is kept). */
  if (!rc && best >= 0 && best < gate) {
    int *dt = NULL;
    size_t n = 0;
    gmshModelGetEntities(&dt, &n, 3, &ierr);
    if (!ierr && n > 0) gmshModelMeshClear(dt, n, &ierr);
    if (dt) gmshFree(dt);
    gmshOptionSetNumber("Mesh.Algorithm3D", 10, &ierr);
    if (!ierr) gmshModelMeshGenerate(3, &ierr);
    if (ierr) return bs_error_set(err, BS_EGMSH, "%s: Gmsh could not mesh the volume again with HXT", path);
    best = model_min_dihedral(path, err, &rc);
    if (!rc) rc = optimise_rounds(path, gate, &best, err);
  }
  if (achieved) *achieved = best;
  return rc;
}
