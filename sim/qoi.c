/* qoi.c — quantities of interest resolved and evaluated (bs_qoi.h). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_forces.h"
#include "bs_qoi.h"

typedef struct qoi_item {
  int32_t n;                   /* vertices (kinematic kinds)                  */
  int32_t *vertices;
  const bs_sim_script *script; /* reaction                                   */
} qoi_item;

struct bs_qoi {
  int n;
  qoi_item *items;
  double *work;                /* 3n: contact forces                          */
};

/* Copies group `name` of body b (from its own mesh: the merged one keeps no
 * groups when there are several bodies). */
static int group_vertices(const bs_sim *s, const bs_scene_qoi *d, int i, qoi_item *it, bs_error *err) {
  bs_mesh *bm = NULL;
  const bs_mesh *m = s->mesh;
  int st = 0;
  if (s->n_bodies > 1 && (st = bs_sim_body_mesh(s->scene, d->body, &bm, err))) return st;
  if (bm) m = bm;
  const bs_group *g = bs_mesh_group(m, d->group);
  if (!g) st = bs_error_set(err, BS_EINPUT, "%s: qoi.%d.group: body %d has no physical group '%s'", s->scene->path, i,
                            d->body, d->group);
  else if (!(it->vertices = malloc(sizeof(int32_t) * (size_t)(g->n_vertices ? g->n_vertices : 1))))
    st = bs_error_set(err, BS_ENOMEM, "out of memory");
  for (int32_t k = 0; !st && k < g->n_vertices; k++) it->vertices[it->n++] = g->vertices[k] + s->vertex_offset[d->body];
  bs_mesh_destroy(&bm);
  return st;
}

/* The body's vertex nearest d->at in x0. */
static int nearest_vertex(const bs_sim *s, const bs_scene_qoi *d, qoi_item *it, bs_error *err) {
  if (!(it->vertices = malloc(sizeof(int32_t)))) return bs_error_set(err, BS_ENOMEM, "out of memory");
  double best = DBL_MAX;
  for (int32_t v = s->vertex_offset[d->body]; v < s->vertex_offset[d->body + 1]; v++) {
    double dd = 0;
    for (int k = 0; k < 3; k++) dd += (s->x0[3 * v + k] - d->at[k]) * (s->x0[3 * v + k] - d->at[k]);
    if (dd < best) best = dd, it->vertices[0] = v;
  }
  it->n = 1;
  return 0;
}

/* The scripted group d->group of body d->body. */
static int find_script(const bs_sim *s, const bs_scene_qoi *d, int i, qoi_item *it, bs_error *err) {
  const bs_scene_body *b = &s->scene->bodies[d->body];
  for (int k = 0; k < s->n_scripts; k++) {
    const bs_scene_script *sc = s->scripts[k].script;
    if (sc >= b->scripts && sc < b->scripts + b->n_scripts && !strcmp(sc->group, d->group)) {
      it->script = &s->scripts[k];
      return 0;
    }
  }
  return bs_error_set(err, BS_EINPUT, "%s: qoi.%d.group: '%s' is not a scripted group of body %d (a reaction is the "
                      "force on a scripted group)", s->scene->path, i, d->group, d->body);
}

static int resolve(const bs_sim *s, int i, qoi_item *it, bs_error *err) {
  const bs_scene_qoi *d = &s->scene->qoi[i];
  const char *path = s->scene->path;
  if (d->body < 0 || d->body >= s->n_bodies)
    return bs_error_set(err, BS_EINPUT, "%s: qoi.%d.body: %d, but the scene has %d bodies", path, i, d->body, s->n_bodies);
  if (d->kind == BS_QOI_CONTACT && (d->obstacle < 0 || d->obstacle >= s->scene->n_obstacles))
    return bs_error_set(err, BS_EINPUT, "%s: qoi.%d.obstacle: %d, but the scene has %d obstacles", path, i, d->obstacle,
                        s->scene->n_obstacles);
  if (d->kind == BS_QOI_REACTION) return find_script(s, d, i, it, err);
  if (d->kind > BS_QOI_VELOCITY) return 0;
  return d->group[0] ? group_vertices(s, d, i, it, err) : nearest_vertex(s, d, it, err);
}

int bs_qoi_create(const bs_sim *s, bs_qoi **out, bs_error *err) {
  *out = NULL;
  bs_qoi *q = calloc(1, sizeof *q);
  if (!q) return bs_error_set(err, BS_ENOMEM, "out of memory");
  q->n = s->scene->n_qoi;
  q->items = calloc((size_t)(q->n ? q->n : 1), sizeof(qoi_item));
  q->work = malloc(sizeof(double) * 3 * (size_t)s->mesh->n_vertices);
  int st = q->items && q->work ? 0 : bs_error_set(err, BS_ENOMEM, "out of memory");
  for (int i = 0; !st && i < q->n; i++) st = resolve(s, i, &q->items[i], err);
  if (st) bs_qoi_destroy(&q);
  *out = q;
  return st;
}

void bs_qoi_destroy(bs_qoi **pq) {
  if (!pq || !*pq) return;
  bs_qoi *q = *pq;
  for (int i = 0; q->items && i < q->n; i++) free(q->items[i].vertices);
  free(q->items);
  free(q->work);
  free(q);
  *pq = NULL;
}

/* Component c of a 3-vector (3: its length). */
static double component(const double *v, int c) { return c < 3 ? v[c] : sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* Mean, max or min over the item's vertices of the kinematic quantity. */
static double kinematic(const bs_sim *s, const bs_scene_qoi *d, const qoi_item *it) {
  double acc = d->reduce == BS_QOI_MEAN ? 0 : d->reduce == BS_QOI_MAX ? -INFINITY : INFINITY;
  for (int32_t k = 0; k < it->n; k++) {
    int32_t v = it->vertices[k];
    double w[3];
    for (int j = 0; j < 3; j++)
      w[j] = d->kind == BS_QOI_VELOCITY ? s->v[3 * v + j]
             : d->kind == BS_QOI_POSITION ? s->x[3 * v + j] : s->x[3 * v + j] - s->x0[3 * v + j];
    double c = component(w, d->component);
    acc = d->reduce == BS_QOI_MEAN ? acc + c / it->n : d->reduce == BS_QOI_MAX ? fmax(acc, c) : fmin(acc, c);
  }
  return it->n ? acc : NAN;
}

static int one(bs_qoi *q, const bs_sim *s, int i, double *out, bs_error *err) {
  const bs_scene_qoi *d = &s->scene->qoi[i];
  double R[3] = {0, 0, 0};
  int st = 0;
  if (d->kind <= BS_QOI_VELOCITY) *out = kinematic(s, d, &q->items[i]);
  else if (d->kind == BS_QOI_REACTION) {
    if (!(st = bs_sim_reaction(s, q->items[i].script, R, err))) *out = component(R, d->component);
  } else if (d->kind == BS_QOI_CONTACT) {
    if (!(st = bs_sim_force_contact(s, d->obstacle, q->work, err))) {
      for (int32_t v = 0; v < s->mesh->n_vertices; v++)
        for (int k = 0; k < 3; k++) R[k] += q->work[3 * v + k];
      *out = component(R, d->component);
    }
  } else {
    bs_sim_measures m;
    bs_sim_measure(s, 0, &m);
    const double e[4] = {m.kinetic, m.elastic, m.gravity, m.total};
    *out = e[d->energy];
  }
  return st;
}

int bs_qoi_eval(bs_qoi *q, const bs_sim *s, double *values, bs_error *err) {
  int st = 0;
  for (int i = 0; !st && i < q->n; i++) st = one(q, s, i, &values[i], err);
  return st;
}
