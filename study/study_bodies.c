/* study_bodies.c — what a study needs of its bodies: the body size L (the
 * diagonal of the bounding box of all bodies at rest) and each body's vertex,
 * edge, face and tet counts at refine 0, from which the vertex blocks of any
 * refinement level follow (bs_study.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_sim.h"
#include "study_internal.h"

/* Vertex count after r uniform refinements: V' = V + E, E' = 2E + 3F + T,
 * F' = 4F + 8T, T' = 8T (F counts every triangle). */
int64_t bs__study_body_vertices(const int64_t c[4], int r) {
  int64_t V = c[0], E = c[1], F = c[2], T = c[3];
  for (int i = 0; i < r; i++) {
    int64_t V1 = V + E, E1 = 2 * E + 3 * F + T, F1 = 4 * F + 8 * T, T1 = 8 * T;
    V = V1;
    E = E1;
    F = F1;
    T = T1;
  }
  return V;
}

int64_t bs__study_offsets(const bs_study *S, const int *refine, int64_t *off) {
  int64_t o = 0;
  for (int b = 0; b < S->n_bodies; b++) {
    off[b] = o;
    o += bs__study_body_vertices(S->counts[b], refine[b]);
  }
  return o;
}

/* The diagonal of the bounding box of the simulation's rest positions (1 if 0). */
static double rest_size(const bs_sim *sim) { return sim->size > 0 ? sim->size : 1.0; }

/* V, E, F, T of body b's mesh (the scene has every body at refine 0). */
static int body_counts(const bs_scene *sc, int b, int64_t c[4], bs_error *err) {
  bs_mesh *m = NULL;
  int st = bs_sim_body_mesh(sc, b, &m, err);
  int32_t *ptr = NULL, *adj = NULL;
  if (!st) st = bs_mesh_vertex_graph(m, &ptr, &adj, err);
  if (!st) {
    c[0] = m->n_vertices;
    c[1] = ptr[m->n_vertices] / 2;
    c[2] = (4 * (int64_t)m->n_tets + m->n_faces) / 2;
    c[3] = m->n_tets;
  }
  free(ptr);
  free(adj);
  bs_mesh_destroy(&m);
  return st;
}

int bs_study_measure_bodies(bs_study *S, bs_error *err) {
  int n = S->n_user + S->n_bodies, st = 0;
  const char **sets = calloc((size_t)n + 1, sizeof(char *));
  char (*own)[64] = calloc((size_t)S->n_bodies + 1, sizeof *own);
  free(S->counts);
  S->counts = calloc((size_t)S->n_bodies + 1, sizeof *S->counts);
  if (!sets || !own || !S->counts) st = bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  for (int i = 0; !st && i < S->n_user; i++) sets[i] = S->user_sets[i];
  for (int b = 0; !st && b < S->n_bodies; b++) {
    snprintf(own[b], sizeof own[b], "bodies.%d.refine=0", b);
    sets[S->n_user + b] = own[b];
  }
  bs_scene *sc = NULL;
  bs_sim *sim = NULL;
  if (!st) st = bs_scene_load(S->scene_path, n, sets, &sc, err);
  if (!st) st = bs_sim_create(sc, &sim, err);
  if (!st) S->size = rest_size(sim);
  for (int b = 0; !st && b < S->n_bodies; b++) st = body_counts(sc, b, S->counts[b], err);
  bs_sim_destroy(&sim);
  bs_scene_destroy(&sc);
  free(own);
  free(sets);
  return st;
}
