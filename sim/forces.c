/* forces.c — per-vertex forces of a simulation's state (bs_forces.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_forces.h"
#include "bs_levelset.h"

/* Which terms a sum takes. */
typedef enum { PICK_ELASTIC, PICK_ALL, PICK_NOT_CONTACT, PICK_CONTACT } pick;

/* The penalty obstacle whose term t is (its scene index), or -1; -2 for
 * contact between the bodies (the self-collision or barrier contact term,
 * and the barrier's friction);
 * -3 for the barrier obstacles' term (all of them, with their friction). */
static int contact_owner(const bs_sim *s, const bs_term *t) {
  if (t == s->self || t == s->barrier || (t && t == s->barrier_friction)) return -2;
  if (t && t == s->obstacle_barrier) return -3;
  if (!s->obstacles) return -1;
  bs_term *const *pt = NULL;
  int np = bs_obstacles_terms(s->obstacles, &pt);
  for (int j = 0, k = 0; j < s->scene->n_obstacles; j++) {
    if (s->scene->obstacles[j].collision != BS_COLLIDE_PENALTY) continue;
    if (k < np && pt[k] == t) return j;
    k++;
  }
  return -1;
}

static int picked(const bs_sim *s, const bs_term *t, pick p, int obstacle) {
  if (t->dynamic_only && s->scene->mode == BS_MODE_STATIC) return 0;
  int owner = contact_owner(s, t), contact = owner != -1;
  switch (p) {
    case PICK_ELASTIC: return t->kind == BS_TERM_ELASTICITY;
    case PICK_ALL: return 1;
    case PICK_NOT_CONTACT: return !contact;
    case PICK_CONTACT: return contact && (obstacle < 0 || owner == obstacle);
  }
  return 0;
}

/* g = the sum of the picked terms' gradients at s->x (N). */
static int gradient_sum(const bs_sim *s, pick p, int obstacle, double *g, bs_error *err) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  memset(g, 0, sizeof(double) * n3);
  for (int i = 0; i < s->n_terms; i++) {
    const bs_term *t = s->terms[i];
    if (!picked(s, t, p, obstacle)) continue;
    double E = 0;
    if (t->ops->gradient(t, s->x, &E, g) != BS_TERM_OK)
      return bs_error_set(err, BS_ENUMERIC, "forces: the %s term is not evaluable at the current state", t->name);
  }
  return 0;
}

int bs_sim_force_elastic(const bs_sim *s, double *f, bs_error *err) {
  int st = gradient_sum(s, PICK_ELASTIC, -1, f, err);
  for (size_t i = 0; !st && i < 3 * (size_t)s->mesh->n_vertices; i++) f[i] = -f[i];
  return st;
}

int bs_sim_force_residual(const bs_sim *s, double *r, bs_error *err) { return gradient_sum(s, PICK_ALL, -1, r, err); }

/* Adds constraint obstacle b's force at the free vertices touching it, from
 * r (the residual without the contact terms). */
static void add_constraint(const bs_sim *s, int b, const double *r, double *f) {
  const bs_levelset *ls = bs_obstacles_levelset(s->obstacles, b);
  if (!ls) return;
  const double tol = 1e-8 * s->size;
  for (int32_t p = 0; p < s->mesh->n_vertices; p++) {
    if (!s->mask[p]) continue;
    double gr[3], phi = bs_levelset_eval(ls, s->time, s->x + 3 * p, gr, NULL);
    double nn = gr[0] * gr[0] + gr[1] * gr[1] + gr[2] * gr[2];
    if (!(fabs(phi) <= tol) || !(nn > 0)) continue;
    double lam = (r[3 * p] * gr[0] + r[3 * p + 1] * gr[1] + r[3 * p + 2] * gr[2]) / nn;
    if (lam > 0)
      for (int k = 0; k < 3; k++) f[3 * p + k] += lam * gr[k];
  }
}

int bs_sim_force_contact(const bs_sim *s, int obstacle, double *f, bs_error *err) {
  int st = gradient_sum(s, PICK_CONTACT, obstacle, f, err);
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  for (size_t i = 0; !st && i < n3; i++) f[i] = -f[i];
  int any = 0;
  for (int b = 0; s->obstacles && b < s->scene->n_obstacles; b++)
    any |= s->scene->obstacles[b].collision == BS_COLLIDE_CONSTRAINT && (obstacle < 0 || obstacle == b);
  if (st || !any) return st;
  double *r = malloc(sizeof(double) * n3);
  if (!r) return bs_error_set(err, BS_ENOMEM, "out of memory (contact forces)");
  st = gradient_sum(s, PICK_NOT_CONTACT, -1, r, err);
  for (int b = 0; !st && b < s->scene->n_obstacles; b++)
    if (s->scene->obstacles[b].collision == BS_COLLIDE_CONSTRAINT && (obstacle < 0 || obstacle == b))
      add_constraint(s, b, r, f);
  free(r);
  return st;
}

int bs_sim_reaction(const bs_sim *s, const bs_sim_script *group, double R[3], bs_error *err) {
  R[0] = R[1] = R[2] = 0;
  double *r = malloc(sizeof(double) * 3 * (size_t)s->mesh->n_vertices);
  if (!r) return bs_error_set(err, BS_ENOMEM, "out of memory (reaction force)");
  int st = bs_sim_force_residual(s, r, err);
  for (int32_t q = 0; !st && q < group->n; q++)
    for (int k = 0; k < 3; k++) R[k] += r[3 * (size_t)group->vertices[q] + k];
  free(r);
  return st;
}
