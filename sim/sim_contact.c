/* sim_contact.c — the barrier contact models: self-contact
 * (self_collision.model "barrier", bs_ipc_term.h, with its friction,
 * bs_ipc_friction.h) and obstacles
 * (obstacles[].collision "barrier", bs_ipc_obstacle.h): their terms from the
 * scene's contact keys, the refusal of a start in contact, and kappa as IPC
 * chooses it. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_ipc.h"
#include "bs_ipc_friction.h"
#include "bs_ipc_obstacle.h"
#include "bs_ipc_term.h"
#include "bs_obstacles.h"
#include "bs_shim.h"
#include "sim_internal.h"

/* The body of vertex v (s->vertex_offset). */
static int body_of(const bs_sim *s, int32_t v) {
  int b = 0;
  while (b + 1 < s->n_bodies && v >= s->vertex_offset[b + 1]) b++;
  return b;
}

/* BS_EINPUT naming the bodies and the count when the surfaces at x0
 * intersect (exact, CGAL): the barrier needs a start without contact. */
static int refuse_intersecting(const bs_sim *s, bs_error *err) {
  const bs_mesh *m = s->mesh;
  int32_t *pairs = NULL;
  int64_t n = 0;
  int st = bs_shim_self_intersections(s->x, m->n_vertices, m->faces, m->n_faces, &pairs, &n, err);
  if (st) return st;
  if (n == 0) return 0;
  int b0 = body_of(s, m->faces[3 * (size_t)pairs[0]]), b1 = body_of(s, m->faces[3 * (size_t)pairs[1]]);
  int64_t same = 0; /* pairs between the same two bodies as the first */
  for (int64_t i = 0; i < n; i++) {
    const int c0 = body_of(s, m->faces[3 * (size_t)pairs[2 * i]]), c1 = body_of(s, m->faces[3 * (size_t)pairs[2 * i + 1]]);
    same += (c0 == b0 && c1 == b1) || (c0 == b1 && c1 == b0);
  }
  bs_shim_free(pairs);
  if (b0 > b1) {
    const int t = b0;
    b0 = b1, b1 = t;
  }
  char which[96];
  if (b0 == b1) snprintf(which, sizeof which, "body %d with itself", b0);
  else snprintf(which, sizeof which, "bodies %d and %d", b0, b1);
  return bs_error_set(err, BS_EINPUT,
                      "%s: self_collision.model \"barrier\" needs a start without intersections: %lld pairs of "
                      "boundary triangles intersect at t = 0 (%lld of them between %s)",
                      s->scene->path, (long long)n, (long long)same, which);
}

/* kappa as IPC chooses it (bs_ipc.h): the bounds from the mean vertex mass
 * (per dt^2: bigstep's objective is IPC's divided by dt^2), the initial value
 * from the other terms' gradient at x0 (those that need no step: gravity,
 * elasticity, obstacles), then adapted per step. obstacles: t is the
 * obstacles' barrier term (bs_ipc_obstacle.h), else the self-contact's. */
static int auto_kappa(bs_sim *s, bs_term *t, int obstacles, double dhat, bs_error *err) {
  const bs_fem *fem = s->fem;
  const double dt = s->scene->dt > 0 ? s->scene->dt : 1.0;
  const double avg = fem->total_mass / (fem->n_vertices > 0 ? fem->n_vertices : 1);
  double kmin, kmax;
  int st = bs_ipc_kappa_bounds(avg / (dt * dt), dhat, s->size, 1e11, &kmin, &kmax, err);
  if (st) return st;
  const size_t n3 = 3 * (size_t)fem->n_vertices;
  double *ge = bs_calloc(n3 + 1, sizeof(double), "the initial kappa", err);
  if (!ge) return BS_ENOMEM;
  for (int i = 0; i < s->n_terms && !st; i++) {
    const bs_term *o = s->terms[i];
    double e;
    if (!o->dynamic_only && o->ops->gradient(o, s->x, &e, ge))
      st = bs_error_set(err, BS_ENUMERIC, "%s: the %s term is not evaluable at t = 0", s->scene->path, o->name);
  }
  for (int32_t v = 0; v < fem->n_vertices && !st; v++)
    if (!s->mask[v]) ge[3 * v] = ge[3 * v + 1] = ge[3 * v + 2] = 0;
  double k = 0;
  if (!st)
    st = obstacles ? bs_term_ipc_obstacle_kappa_init(t, s->x, ge, kmin, kmax, &k, err)
                   : bs_term_ipc_kappa_init(t, s->x, ge, kmin, kmax, &k, err);
  free(ge);
  if (!st)
    st = obstacles ? bs_term_ipc_obstacle_set_adaptive(t, kmax, bs_ipc_kappa_d2_eps(s->size), err)
                   : bs_term_ipc_set_adaptive(t, kmax, bs_ipc_kappa_d2_eps(s->size), err);
  return st;
}

/* contact.dhat, or its default; BS_EINPUT naming it when not > 0. */
static int contact_dhat(const bs_sim *s, double *dhat, bs_error *err) {
  const bs_scene *sc = s->scene;
  *dhat = sc->contact_dhat > 0 ? sc->contact_dhat : BS_SIM_DHAT_FRACTION * s->size;
  if (!(*dhat > 0) || !isfinite(*dhat))
    return bs_error_set(err, BS_EINPUT, "%s: contact.dhat: must be > 0 (m), got %g", sc->path, *dhat);
  return 0;
}

/* The obstacles' barrier term with every barrier obstacle (scene order). */
static int obstacle_barrier_term(bs_sim *s, double dhat, bs_term **out, bs_error *err) {
  const bs_scene *sc = s->scene;
  int st = bs_term_ipc_obstacle_create(s->fem, &s->step, s->mask, dhat, sc->contact_kappa, out, err);
  if (!st) st = bs_term_ipc_obstacle_set_friction(*out, sc->contact_eps_v, err);
  for (int i = 0; i < sc->n_obstacles && !st; i++) {
    if (sc->obstacles[i].collision != BS_COLLIDE_BARRIER) continue;
    if ((st = bs_term_ipc_obstacle_add(*out, bs_obstacles_levelset(s->obstacles, i), sc->obstacles[i].friction, i,
                                       err)))
      bs_error_prefix(err, "%s: obstacles.%d.collision", sc->path, i);
  }
  bs_ipc_obstacle_stats os;
  if (!st && !(st = bs_term_ipc_obstacle_detect(*out, s->x, &os, err)) && os.inside > 0)
    st = bs_error_set(err, BS_EINPUT,
                      "%s: obstacles[].collision \"barrier\" needs a start without contact: %lld free surface "
                      "vertices are inside or on a barrier obstacle at t = 0 (smallest distance %g m)",
                      sc->path, (long long)os.inside, os.min_distance);
  return st;
}

int bs__sim_make_obstacle_barrier(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  int any = 0;
  for (int i = 0; i < sc->n_obstacles; i++) any |= sc->obstacles[i].collision == BS_COLLIDE_BARRIER;
  if (!any) return 0;
  double dhat;
  int st = contact_dhat(s, &dhat, err);
  if (st) return st;
  if (s->n_terms >= BS_SIM_MAX_TERMS) return bs_error_set(err, BS_EINPUT, "%s: too many terms", sc->path);
  bs_term *t = NULL;
  st = obstacle_barrier_term(s, dhat, &t, err);
  if (!st && !(sc->contact_kappa > 0)) st = auto_kappa(s, t, 1, dhat, err);
  if (st) {
    bs_term_destroy(&t);
    return st;
  }
  s->obstacle_barrier = t;
  s->terms[s->n_terms++] = t;
  return 0;
}

/* The barrier's friction term (self_collision.friction > 0), after it. */
static int barrier_friction(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  if (!(sc->self_friction > 0)) return 0;
  if (s->n_terms >= BS_SIM_MAX_TERMS) return bs_error_set(err, BS_EINPUT, "%s: too many terms", sc->path);
  bs_term *t = NULL;
  int st = bs_term_ipc_friction_create(s->barrier, sc->self_friction, sc->contact_eps_v, &t, err);
  if (st) {
    bs_error_prefix(err, "%s: self_collision.friction", sc->path);
    return st;
  }
  s->barrier_friction = t;
  s->terms[s->n_terms++] = t;
  return 0;
}

int bs__sim_make_barrier(bs_sim *s, bs_error *err) {
  const bs_scene *sc = s->scene;
  double dhat;
  int st = contact_dhat(s, &dhat, err);
  if (!st) st = refuse_intersecting(s, err);
  if (st) return st;
  if (s->n_terms >= BS_SIM_MAX_TERMS) return bs_error_set(err, BS_EINPUT, "%s: too many terms", sc->path);
  bs_term *t = NULL;
  if ((st = bs_term_ipc_create(s->fem, &s->step, dhat, sc->contact_kappa, &t, err))) {
    bs_error_prefix(err, "%s: contact", sc->path);
    return st;
  }
  bs_ipc_stats is;
  if (!(st = bs_term_ipc_detect(t, s->x, &is, err)) && is.intersecting > 0)
    st = bs_error_set(err, BS_EINPUT,
                      "%s: self_collision.model \"barrier\" needs a start without contact: %lld pairs of surface "
                      "primitives touch at t = 0",
                      sc->path, (long long)is.intersecting);
  if (!st && !(sc->contact_kappa > 0)) st = auto_kappa(s, t, 0, dhat, err);
  if (st) {
    bs_term_destroy(&t);
    return st;
  }
  s->barrier = t;
  s->terms[s->n_terms++] = t;
  return barrier_friction(s, err);
}
