/* sim_bodies.c — the scene's bodies as one mesh: read or build each body's
 * mesh, transform it, merge them, and give every tet its material, every
 * scripted group its vertices and every vertex its initial state. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_tet10.h"
#include "sim_internal.h"

/* Rotation matrix from an axis-angle vector given in degrees. */
static void axis_angle(const double r[3], double R[9]) {
  double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) * M_PI / 180.0;
  for (int i = 0; i < 9; i++) R[i] = (i % 4 == 0);
  if (th == 0) return;
  double n = th * 180.0 / M_PI, k[3] = {r[0] / n, r[1] / n, r[2] / n};
  double c = cos(th), s = sin(th), C = 1 - c;
  R[0] = c + k[0] * k[0] * C;
  R[1] = k[0] * k[1] * C - k[2] * s;
  R[2] = k[0] * k[2] * C + k[1] * s;
  R[3] = k[1] * k[0] * C + k[2] * s;
  R[4] = c + k[1] * k[1] * C;
  R[5] = k[1] * k[2] * C - k[0] * s;
  R[6] = k[2] * k[0] * C - k[1] * s;
  R[7] = k[2] * k[1] * C + k[0] * s;
  R[8] = c + k[2] * k[2] * C;
}

/* Uniform random in [0,1) from a 64-bit xorshift (repeatable across platforms). */
static double rnd(uint64_t *s) {
  *s ^= *s << 13;
  *s ^= *s >> 7;
  *s ^= *s << 17;
  return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

/* p scaled, rotated by R and translated as the body asks. */
static void place(const bs_scene_body *bd, const double R[9], double *p) {
  double q[3];
  for (int k = 0; k < 3; k++) q[k] = p[k] * bd->scale[k];
  for (int k = 0; k < 3; k++) p[k] = R[3 * k] * q[0] + R[3 * k + 1] * q[1] + R[3 * k + 2] * q[2] + bd->translate[k];
}

int bs_sim_body_mesh(const bs_scene *sc, int b, bs_mesh **out, bs_error *err) {
  const bs_scene_body *bd = &sc->bodies[b];
  int st;
  if (!strcmp(bd->mesh, "box")) st = bs_mesh_create_box_refined(bd->box_size, bd->box_cells, bd->refine, out, err);
  else {
    bs_mesh_read_opts o = {.size = bd->mesh_size, .refine = bd->refine, .max_tets = bs_memory_max_tets(sc),
                           .close_holes = bd->close_holes, .surface_mesher = bd->mesher,
                           .min_dihedral = bd->min_dihedral > 0 ? bd->min_dihedral : -1,
                           .element_order = bd->element == BS_ELEMENT_TET10 ? 2 : 1};
    st = bs_mesh_read(bd->mesh, &o, out, err);
  }
  if (!st && bd->reorder != BS_ORDER_NONE) st = bs_mesh_reorder(*out, bd->reorder, NULL, err);
  if (st) {
    bs_mesh_destroy(out);
    bs_error_prefix(err, "%s: bodies.%d", sc->path, b);
    return st;
  }
  double R[9];
  axis_angle(bd->rotate, R);
  bs_mesh *m = *out;
  for (int32_t v = 0; v < m->n_vertices; v++) place(bd, R, m->x + 3 * (size_t)v);
  for (int32_t i = 0; i < m->n_midside; i++) place(bd, R, m->midside_x + 3 * (size_t)i); /* a file's curved nodes */
  if (bd->element == BS_ELEMENT_TET10 && !m->tets10 && (st = bs_tet10_mesh(m, err))) {
    bs_mesh_destroy(out);
    bs_error_prefix(err, "%s: bodies.%d (element tet10)", sc->path, b);
    return st;
  }
  return 0;
}

/* The merged mesh of nb meshes (a single body is used as is: meshes[0] moves). */
static int merge(int nb, bs_mesh **meshes, const int32_t *voff, const int32_t *toff, bs_mesh **out, bs_error *err) {
  if (nb == 1) {
    *out = meshes[0];
    meshes[0] = NULL;
    return 0;
  }
  double *x = calloc(3 * (size_t)voff[nb], sizeof(double));
  int32_t *tets = calloc(4 * (size_t)toff[nb], sizeof(int32_t));
  if (!x || !tets) {
    free(x);
    free(tets);
    return bs_error_set(err, BS_ENOMEM, "out of memory merging bodies");
  }
  for (int b = 0; b < nb; b++) {
    memcpy(x + 3 * (size_t)voff[b], meshes[b]->x, sizeof(double) * 3 * (size_t)meshes[b]->n_vertices);
    for (int64_t i = 0; i < 4 * (int64_t)meshes[b]->n_tets; i++) tets[4 * (size_t)toff[b] + i] = meshes[b]->tets[i] + voff[b];
  }
  int st = bs_mesh_create(voff[nb], x, toff[nb], tets, 0, NULL, out, err);
  free(x);
  free(tets);
  if (!st && (*out)->n_vertices != voff[nb]) st = bs_error_set(err, BS_EINTERNAL, "merging bodies changed the vertex count");
  return st;
}

/* Body b's materials: initialised, and given to the tets of their groups. */
static int body_materials(bs_sim *s, int b, const bs_mesh *bm, int moff, int32_t toff, bs_error *err) {
  const bs_scene *sc = s->scene;
  const bs_scene_body *bd = &sc->bodies[b];
  for (int i = 0; i < bd->n_materials; i++) {
    const bs_scene_material *sm = &bd->materials[i];
    int st = bs_material_init(sm->model, sm->youngs, sm->poisson, sm->density, &s->materials[moff + i], err);
    if (st) {
      bs_error_prefix(err, "%s: bodies.%d.material%s%s", sc->path, b, sm->group[0] ? "s." : "", sm->group);
      return st;
    }
    if (i == 0) continue;
    const bs_group *g = bs_mesh_group(bm, sm->group);
    if (!g || g->dim != 3)
      return bs_error_set(err, BS_EINPUT, "%s: bodies.%d.materials.%s: the mesh has no 3-D physical group named '%s'",
                          sc->path, b, sm->group, sm->group);
    for (int32_t e = 0; e < g->n_elems; e++) s->tet_material[toff + g->elems[e]] = moff + i;
  }
  for (int32_t t = 0; t < bm->n_tets; t++)
    if (s->tet_material[toff + t] == 0 && b > 0) s->tet_material[toff + t] = moff;
  return 0;
}

/* Body b's scripted groups: their vertices, masked out of the unknowns. */
static int body_scripts(bs_sim *s, int b, const bs_mesh *bm, bs_error *err) {
  const bs_scene *sc = s->scene;
  const bs_scene_body *bd = &sc->bodies[b];
  int32_t voff = s->vertex_offset[b];
  for (int i = 0; i < bd->n_scripts; i++) {
    const bs_scene_script *ss = &bd->scripts[i];
    const bs_group *g = bs_mesh_group(bm, ss->group);
    if (!g)
      return bs_error_set(err, BS_EINPUT, "%s: bodies.%d.scripted.%d.group: the mesh has no physical group named '%s'",
                          sc->path, b, i, ss->group);
    bs_sim_script *q = &s->scripts[s->n_scripts++];
    q->script = ss;
    q->n = g->n_vertices;
    q->vertices = malloc(sizeof(int32_t) * (size_t)(g->n_vertices ? g->n_vertices : 1));
    if (!q->vertices) return bs_error_set(err, BS_ENOMEM, "out of memory");
    for (int32_t k = 0; k < g->n_vertices; k++) {
      q->vertices[k] = g->vertices[k] + voff;
      s->mask[q->vertices[k]] = 0;
    }
  }
  return 0;
}

/* Body b's initial velocity v + w x (x - centroid) and, for a random or
 * point initial state, its free vertices' positions. */
static void body_initial_state(bs_sim *s, int b) {
  const bs_scene_body *bd = &s->scene->bodies[b];
  int32_t v0 = s->vertex_offset[b], v1 = s->vertex_offset[b + 1];
  double cen[3] = {0, 0, 0};
  for (int32_t v = v0; v < v1; v++)
    for (int k = 0; k < 3; k++) cen[k] += s->x0[3 * v + k] / (v1 - v0);
  const double *w = bd->angular_velocity;
  for (int32_t v = v0; v < v1; v++) {
    const double *p = s->x0 + 3 * v;
    double r[3] = {p[0] - cen[0], p[1] - cen[1], p[2] - cen[2]};
    s->v[3 * v + 0] = bd->velocity[0] + w[1] * r[2] - w[2] * r[1];
    s->v[3 * v + 1] = bd->velocity[1] + w[2] * r[0] - w[0] * r[2];
    s->v[3 * v + 2] = bd->velocity[2] + w[0] * r[1] - w[1] * r[0];
  }
  uint64_t seed = 0x9E3779B97F4A7C15ull ^ ((uint64_t)bd->init_seed * 2654435761u + 1);
  for (int32_t v = v0; v < v1; v++) {
    if (!s->mask[v]) continue;
    for (int k = 0; k < 3; k++) {
      if (bd->init == BS_INIT_RANDOM) s->x[3 * v + k] = bd->init_lo[k] + (bd->init_hi[k] - bd->init_lo[k]) * rnd(&seed);
      else if (bd->init == BS_INIT_POINT) s->x[3 * v + k] = bd->init_lo[k];
    }
  }
}

/* The per-vertex and per-tet arrays of the merged mesh. */
static int alloc_state(bs_sim *s, int n_materials, int n_scripts, bs_error *err) {
  int32_t nv = s->mesh->n_vertices, nt = s->mesh->n_tets;
  size_t n3 = 3 * (size_t)nv;
  s->x0 = malloc(sizeof(double) * n3);
  s->x = malloc(sizeof(double) * n3);
  s->v = calloc(n3, sizeof(double));
  s->mask = malloc((size_t)nv);
  s->tet_material = calloc((size_t)nt, sizeof(int32_t));
  s->materials = calloc((size_t)n_materials, sizeof(bs_material));
  s->scripts = calloc((size_t)(n_scripts ? n_scripts : 1), sizeof(bs_sim_script));
  if (!s->x0 || !s->x || !s->v || !s->mask || !s->tet_material || !s->materials || !s->scripts)
    return bs_error_set(err, BS_ENOMEM, "out of memory (%d vertices)", nv);
  memcpy(s->x0, s->mesh->x, sizeof(double) * n3);
  memset(s->mask, 1, (size_t)nv);
  s->n_materials = n_materials;
  return 0;
}

/* Materials, scripts and initial state of every body (in body order). */
static int per_body(bs_sim *s, bs_mesh **meshes, const int32_t *toff, const int *moff, bs_error *err) {
  int st = 0;
  for (int b = 0; !st && b < s->n_bodies; b++) {
    const bs_mesh *bm = meshes[b] ? meshes[b] : s->mesh;
    if (!(st = body_materials(s, b, bm, moff[b], toff[b], err))) st = body_scripts(s, b, bm, err);
  }
  if (st) return st;
  memcpy(s->x, s->x0, sizeof(double) * 3 * (size_t)s->mesh->n_vertices);
  for (int b = 0; b < s->n_bodies; b++) body_initial_state(s, b);
  s->n_free = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) s->n_free += s->mask[v];
  return 0;
}

/* What tet10 bodies do not run yet: self-collision (penalty or barrier:
 * their contact pairs are linear triangles) and scenes of several bodies. */
static int refuse_tet10(const bs_scene *sc, bs_error *err) {
  for (int b = 0; b < sc->n_bodies; b++) {
    if (sc->bodies[b].element != BS_ELEMENT_TET10) continue;
    if (sc->self_collision)
      return bs_error_set(err, BS_EINPUT, "%s: self_collision is not supported with bodies[].element tet10 (bodies.%d; model %s)",
                          sc->path, b, sc->self_model == BS_SELF_MODEL_BARRIER ? "barrier" : "penalty");
    if (sc->n_bodies > 1)
      return bs_error_set(err, BS_EINPUT, "%s: bodies.%d.element: tet10 is supported in a scene of one body only (%d bodies)",
                          sc->path, b, sc->n_bodies);
  }
  return 0;
}

int bs__sim_make_bodies(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  int nb = sc->n_bodies, st = refuse_tet10(sc, err), n_scripts = 0;
  if (st) return st;
  s->n_bodies = nb;
  bs_mesh **meshes = calloc((size_t)nb, sizeof(bs_mesh *));
  int32_t *toff = calloc((size_t)nb + 1, sizeof(int32_t));
  int *moff = calloc((size_t)nb + 1, sizeof(int));
  s->vertex_offset = calloc((size_t)nb + 1, sizeof(int32_t));
  if (!meshes || !toff || !moff || !s->vertex_offset) st = bs_error_set(err, BS_ENOMEM, "out of memory");
  for (int b = 0; !st && b < nb; b++) {
    if ((st = bs_sim_body_mesh(sc, b, &meshes[b], err))) break;
    s->vertex_offset[b + 1] = s->vertex_offset[b] + meshes[b]->n_vertices;
    toff[b + 1] = toff[b] + meshes[b]->n_tets;
    moff[b + 1] = moff[b] + sc->bodies[b].n_materials;
    n_scripts += sc->bodies[b].n_scripts;
  }
  if (!st) st = merge(nb, meshes, s->vertex_offset, toff, &s->mesh, err);
  if (!st) st = alloc_state(s, moff[nb], n_scripts, err);
  if (!st) st = per_body(s, meshes, toff, moff, err);
  if (!st) {
    double lo[3], hi[3];
    bs_bbox(s->mesh->n_vertices, s->x0, lo, hi);
    s->size = bs_bbox_diagonal(lo, hi);
  }
  for (int b = 0; meshes && b < nb; b++) bs_mesh_destroy(&meshes[b]);
  free(meshes);
  free(toff);
  free(moff);
  return st;
}
