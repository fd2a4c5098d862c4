/* obstacles.c — collisions with scripted obstacles: constraint projection
 * hooks (paper 3.2, 5.1), penalty terms (5.2), the post-process baseline
 * (Figure 10) and Coulomb friction after the solve. See bs_obstacles.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_obstacles.h"
#include "bs_penalty.h"
#include "bs_vec3.h"

typedef struct obstacle {
  bs_levelset *ls;
  bs_collide_mode mode;
  double k, mu;
  double size;        /* largest shape parameter (for the touching tolerance) */
  bs_term *term;      /* penalty mode                                        */
  uint8_t *active;    /* constraint mode: n_vertices labels                  */
  uint8_t *projected; /* constraint mode: the pairs J_P uses: those moved by  */
                      /* the last project, or the active ones after           */
                      /* register_active (released pairs are neither)         */
  float *nreg;        /* constraint mode: 3 per vertex, the normal of an      */
                      /* active pair at its registration                      */
} obstacle;

/* An active pair is projected back onto the obstacle at a trial point outside
 * it only while the obstacle's normal there stays within 45 degrees of its
 * normal at registration (the paper's curved path over a smooth surface);
 * past an edge or a corner of a box the normal turns by up to 90 degrees, and
 * projecting would pull a vertex sliding off the face back onto the edge,
 * where it stays stuck (the failing steps of the paper-scale figure 13: a
 * vertex at a cube's bottom edge, the descent direction down along the face). */
#define RELEASE_COS 0.70710678118654752

struct bs_obstacles {
  const bs_fem *fem;
  const bs_step_data *step;
  int32_t nv;
  uint8_t *mask;
  double scale;       /* L: scene size from the rest mesh                     */
  int n, cap;
  obstacle *obs;
  int n_terms;
  bs_term **terms;
  int n_constraint;
  double *J, *C;      /* 9 per vertex: composite Jacobian and curvature block  */
  uint8_t *vact;      /* per vertex: any active pair                          */
  double last_time;
  int have_time;
  int32_t n_active;
  double *friction_dv; /* 3 per vertex, the caller's: friction's velocity change */
  uint8_t *owned;     /* NULL, or per vertex: 1 counted here (set_owned)       */
  int32_t n_owned;
  int32_t *own_idx;   /* the owned vertices (penalty terms' vertex subset)     */
  int allow_barrier;  /* bs_obstacles_allow_barrier was called                */
};

/* Whether vertex p is counted by this process (bs_obstacles_set_owned). */
static inline int counted(const bs_obstacles *o, int32_t p) { return !o->owned || o->owned[p]; }

static const char *mode_names[] = {"constraint", "penalty", "postprocess", "barrier"};

int bs_collide_mode_parse(const char *name, bs_collide_mode *out, bs_error *err) {
  for (int i = 0; i < 4; i++)
    if (name && strcmp(name, mode_names[i]) == 0) {
      *out = (bs_collide_mode)i;
      return 0;
    }
  return bs_error_set(err, BS_EINPUT, "unknown collision mode '%s' (constraint, penalty, postprocess, barrier)",
                      name ? name : "(null)");
}

const char *bs_collide_mode_name(bs_collide_mode mode) { return (unsigned)mode < 4 ? mode_names[mode] : "?"; }

/* ---- small vector helpers ------------------------------------------------ */

static inline void mat3_mul(const double *A, const double *B, double *AB) {
  double R[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) R[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
  memcpy(AB, R, sizeof R);
}

/* R = A^T B */
static inline void mat3_tmul(const double *A, const double *B, double *R) {
  double T[9];
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) T[3 * i + j] = A[i] * B[j] + A[3 + i] * B[3 + j] + A[6 + i] * B[6 + j];
  memcpy(R, T, sizeof T);
}

/* ---- create / destroy / add ------------------------------------------------ */

void bs_obstacles_destroy(bs_obstacles **po) {
  if (!po || !*po) return;
  bs_obstacles *o = *po;
  for (int i = 0; i < o->n; i++) {
    bs_term_destroy(&o->obs[i].term);
    bs_levelset_destroy(&o->obs[i].ls);
    free(o->obs[i].active);
    free(o->obs[i].projected);
    free(o->obs[i].nreg);
  }
  free(o->obs);
  free(o->terms);
  free(o->mask);
  free(o->J);
  free(o->C);
  free(o->vact);
  free(o->owned);
  free(o->own_idx);
  free(o);
  *po = NULL;
}

/* L of the touching tolerance: the box's diagonal plus its largest coordinate. */
static double scene_scale(const double lo[3], const double hi[3]) {
  double big = 0;
  for (int k = 0; k < 3; k++) big = fmax(big, fmax(fabs(lo[k]), fabs(hi[k])));
  return bs_bbox_diagonal(lo, hi) + big;
}

int bs_obstacles_create(const bs_fem *fem, const bs_step_data *step, const uint8_t *mask, bs_obstacles **out,
                        bs_error *err) {
  *out = NULL;
  if (!fem || !step) return bs_error_set(err, BS_EINPUT, "obstacles: the fem and the step data are required");
  bs_obstacles *o = bs_calloc(1, sizeof *o, "the obstacles", err);
  if (!o) return BS_ENOMEM;
  o->fem = fem;
  o->step = step;
  o->nv = fem->n_vertices;
  size_t nv = (size_t)o->nv;
  o->mask = malloc(nv ? nv : 1);
  if (!o->mask) {
    bs_obstacles_destroy(&o);
    return bs_error_set(err, BS_ENOMEM, "out of memory creating the obstacles (%zu vertices)", nv);
  }
  if (mask) memcpy(o->mask, mask, nv);
  else memset(o->mask, 1, nv);
  /* Scene size: bounding-box diagonal plus the largest coordinate of the rest mesh. */
  double lo[3], hi[3];
  bs_bbox((int64_t)nv, fem->mesh->x, lo, hi);
  o->scale = scene_scale(lo, hi);
  *out = o;
  return 0;
}

void bs_obstacles_set_bounds(bs_obstacles *o, const double lo[3], const double hi[3]) {
  o->scale = scene_scale(lo, hi);
}

int bs_obstacles_set_owned(bs_obstacles *o, const uint8_t *owned, bs_error *err) {
  if (o->n > 0)
    return bs_error_set(err, BS_EINPUT, "obstacles: the owned vertices are set before the first obstacle (%d added)",
                        o->n);
  free(o->owned);
  free(o->own_idx);
  o->owned = NULL, o->own_idx = NULL, o->n_owned = 0;
  if (!owned) return 0;
  const size_t nv = (size_t)o->nv;
  o->owned = malloc(nv ? nv : 1);
  o->own_idx = malloc(sizeof *o->own_idx * (nv ? nv : 1));
  if (!o->owned || !o->own_idx)
    return bs_error_set(err, BS_ENOMEM, "out of memory marking the owned vertices (%zu vertices)", nv);
  memcpy(o->owned, owned, nv);
  for (int32_t p = 0; p < o->nv; p++)
    if (owned[p]) o->own_idx[o->n_owned++] = p;
  return 0;
}

int bs_obstacles_count(const bs_obstacles *o) { return o ? o->n : 0; }
void bs_obstacles_allow_barrier(bs_obstacles *o) { o->allow_barrier = 1; }
bs_collide_mode bs_obstacles_mode(const bs_obstacles *o, int i) {
  return o && i >= 0 && i < o->n ? o->obs[i].mode : BS_COLLIDE_CONSTRAINT;
}
double bs_obstacles_friction(const bs_obstacles *o, int i) { return o && i >= 0 && i < o->n ? o->obs[i].mu : 0; }

const bs_levelset *bs_obstacles_levelset(const bs_obstacles *o, int i) {
  return o && i >= 0 && i < o->n ? o->obs[i].ls : NULL;
}

int bs_obstacles_add(bs_obstacles *o, bs_levelset *ls, bs_collide_mode mode, double stiffness, double friction,
                     bs_error *err) {
  int idx = o->n, rc = 0;
  if (!ls) return bs_error_set(err, BS_EINPUT, "obstacle %d: no level set", idx);
  const char *kind = bs_levelset_kind_name(bs_levelset_kind(ls));
  if ((unsigned)mode > BS_COLLIDE_BARRIER) {
    rc = bs_error_set(err, BS_EINPUT, "obstacle %d (%s): unknown collision mode %d", idx, kind, (int)mode);
    goto fail;
  }
  if (mode == BS_COLLIDE_BARRIER && !o->allow_barrier) {
    rc = bs_error_set(err, BS_EINPUT,
                      "obstacle %d (%s): collision \"barrier\" is not available here (no barrier term is built: "
                      "this backend runs constraint, penalty and postprocess obstacles)",
                      idx, kind);
    goto fail;
  }
  if (!(friction >= 0) || !isfinite(friction)) {
    rc = bs_error_set(err, BS_EINPUT, "obstacle %d (%s): friction = %g must be finite and >= 0", idx, kind, friction);
    goto fail;
  }
  if (mode == BS_COLLIDE_CONSTRAINT && !bs_levelset_is_analytic(ls)) {
    rc = bs_error_set(err, BS_EINPUT,
                      "obstacle %d (%s): constraint collisions need an analytic level set (the projection of a "
                      "grid is neither exact nor idempotent, paper 5.1); use \"penalty\"",
                      idx, kind);
    goto fail;
  }
  if (o->n == o->cap) {
    int cap = o->cap ? 2 * o->cap : 4;
    obstacle *no = realloc(o->obs, sizeof *no * (size_t)cap);
    if (!no) {
      rc = bs_error_set(err, BS_ENOMEM, "obstacle %d (%s): out of memory", idx, kind);
      goto fail;
    }
    o->obs = no;
    o->cap = cap;
  }
  obstacle ob;
  memset(&ob, 0, sizeof ob);
  ob.ls = ls;
  ob.mode = mode;
  ob.k = stiffness;
  ob.mu = friction;
  ob.size = fmax(fabs(ls->param[0]), fmax(fabs(ls->param[1]), fabs(ls->param[2])));
  size_t nv = (size_t)o->nv;
  if (mode == BS_COLLIDE_PENALTY) {
    bs_term **nt = realloc(o->terms, sizeof *nt * (size_t)(o->n_terms + 1));
    if (!nt) {
      rc = bs_error_set(err, BS_ENOMEM, "obstacle %d (%s): out of memory", idx, kind);
      goto fail;
    }
    o->terms = nt;
    rc = o->owned ? bs_term_penalty_create_subset(o->fem, o->step, ls, stiffness, o->n_owned, o->own_idx, &ob.term, err)
                  : bs_term_penalty_create(o->fem, o->step, ls, stiffness, &ob.term, err);
    if (rc) {
      bs_error_prefix(err, "obstacle %d (%s)", idx, kind);
      goto fail;
    }
    o->terms[o->n_terms++] = ob.term;
  } else if (mode == BS_COLLIDE_CONSTRAINT) {
    ob.active = calloc(nv ? nv : 1, 1);
    ob.projected = calloc(nv ? nv : 1, 1);
    ob.nreg = malloc(sizeof(float) * 3 * (nv ? nv : 1));
    if (!o->J) {
      o->J = malloc(sizeof(double) * 9 * (nv ? nv : 1));
      o->C = malloc(sizeof(double) * 9 * (nv ? nv : 1));
      o->vact = calloc(nv ? nv : 1, 1);
    }
    if (!ob.active || !ob.projected || !ob.nreg || !o->J || !o->C || !o->vact) {
      free(ob.active);
      free(ob.projected);
      free(ob.nreg);
      rc = bs_error_set(err, BS_ENOMEM, "obstacle %d (%s): out of memory (%zu vertices)", idx, kind, nv);
      goto fail;
    }
    o->n_constraint++;
  }
  o->obs[o->n++] = ob;
  return 0;
fail:
  bs_levelset_destroy(&ls);
  return rc;
}

int bs_obstacles_terms(const bs_obstacles *o, bs_term *const **terms) {
  *terms = o->terms;
  return o->n_terms;
}

void bs_obstacles_hooks(bs_obstacles *o, bs_step_hooks *hooks) {
  memset(hooks, 0, sizeof *hooks);
  if (o->n_constraint > 0) {
    hooks->project = bs_obstacles_project;
    hooks->register_active = bs_obstacles_register_active;
    hooks->project_gradient = bs_obstacles_project_gradient;
    hooks->project_hessian = bs_obstacles_project_hessian;
  }
  if (o->n > 0) hooks->post_solve = bs_obstacles_post_solve;
  hooks->ctx = o;
}

int32_t bs_obstacles_active_count(const bs_obstacles *o) { return o->n_active; }

/* ---- the active set ---------------------------------------------------------- */

static void clear_labels(bs_obstacles *o) {
  for (int b = 0; b < o->n; b++)
    if (o->obs[b].mode == BS_COLLIDE_CONSTRAINT) {
      memset(o->obs[b].active, 0, (size_t)o->nv);
      memset(o->obs[b].projected, 0, (size_t)o->nv);
    }
  o->n_active = 0;
}

/* A new step (or a statics at another time) starts from no active pair. */
static void sync_time(bs_obstacles *o) {
  if (!o->have_time || o->step->time != o->last_time) {
    clear_labels(o);
    o->last_time = o->step->time;
    o->have_time = 1;
  }
}

static double touch_tol(const bs_obstacles *o, const obstacle *ob, const bs_levelset_frame *f) {
  return 1e-12 * (o->scale + sqrt(bs_dot3(f->c, f->c)) + ob->size);
}

void bs_obstacles_project(double *x, void *ctx) {
  bs_obstacles *o = ctx;
  sync_time(o);
  const double t = o->step->time;
  const int32_t nv = o->nv;
  for (int b = 0; b < o->n; b++) {
    obstacle *ob = &o->obs[b];
    if (ob->mode != BS_COLLIDE_CONSTRAINT) continue;
    bs_levelset_frame f;
    bs_levelset_frame_at(ob->ls, t, &f);
#pragma omp parallel for schedule(static) if (nv > 4096)
    for (int32_t p = 0; p < nv; p++) {
      ob->projected[p] = 0;
      if (!o->mask[p]) continue;
      double *xp = x + 3 * (size_t)p, g[3];
      double phi = bs_levelset_eval_frame(ob->ls, &f, xp, g, NULL);
      int proj = phi < 0;
      if (!proj && ob->active[p]) {
        const float *nr = ob->nreg + 3 * (size_t)p;
        proj = g[0] * nr[0] + g[1] * nr[1] + g[2] * nr[2] >= RELEASE_COS; /* else released */
      }
      if (proj) {
        for (int k = 0; k < 3; k++) xp[k] -= phi * g[k];
        ob->projected[p] = 1;
      }
    }
  }
}

void bs_obstacles_register_active(const double *x, const double *g, void *ctx) {
  bs_obstacles *o = ctx;
  sync_time(o);
  const double t = o->step->time;
  const int32_t nv = o->nv;
  int32_t count = 0;
  for (int b = 0; b < o->n; b++) {
    obstacle *ob = &o->obs[b];
    if (ob->mode != BS_COLLIDE_CONSTRAINT) continue;
    bs_levelset_frame f;
    bs_levelset_frame_at(ob->ls, t, &f);
    const double tol = touch_tol(o, ob, &f);
#pragma omp parallel for schedule(static) reduction(+ : count) if (nv > 4096)
    for (int32_t p = 0; p < nv; p++) {
      ob->projected[p] = 0;
      ob->active[p] = 0;
      if (!o->mask[p]) continue;
      double n[3];
      double phi = bs_levelset_eval_frame(ob->ls, &f, x + 3 * (size_t)p, n, NULL);
      if (fabs(phi) <= tol && bs_dot3(g + 3 * (size_t)p, n) >= 0) {
        ob->active[p] = ob->projected[p] = 1;
        for (int k = 0; k < 3; k++) ob->nreg[3 * (size_t)p + k] = (float)n[k];
        count += counted(o, p);
      }
    }
  }
  o->n_active = count;
}

void bs_obstacles_project_gradient(const double *x, double *g, void *ctx) {
  bs_obstacles *o = ctx;
  const double t = o->step->time;
  const int32_t nv = o->nv;
  /* J^T = J_1^T ... J_B^T: the last obstacle first. */
  for (int b = o->n - 1; b >= 0; b--) {
    obstacle *ob = &o->obs[b];
    if (ob->mode != BS_COLLIDE_CONSTRAINT) continue;
    bs_levelset_frame f;
    bs_levelset_frame_at(ob->ls, t, &f);
#pragma omp parallel for schedule(static) if (nv > 4096)
    for (int32_t p = 0; p < nv; p++) {
      if (!o->mask[p] || !ob->projected[p]) continue;
      double n[3], *gp = g + 3 * (size_t)p;
      bs_levelset_eval_frame(ob->ls, &f, x + 3 * (size_t)p, n, NULL);
      double s = bs_dot3(gp, n);
      for (int k = 0; k < 3; k++) gp[k] -= s * n[k];
    }
  }
}

void bs_obstacles_project_hessian(const double *x, const double *g, bs_bsr *H, void *ctx) {
  bs_obstacles *o = ctx;
  const double t = o->step->time;
  const int32_t nv = o->nv;
  bs_levelset_frame frames[64];
  /* Frames of up to 64 constraint obstacles are cached; more are recomputed. */
  for (int b = 0; b < o->n && b < 64; b++)
    if (o->obs[b].mode == BS_COLLIDE_CONSTRAINT) bs_levelset_frame_at(o->obs[b].ls, t, &frames[b]);
  /* Per vertex: J_p = J_B ... J_1 and the curvature block C_p (header). */
#pragma omp parallel for schedule(static) if (nv > 4096)
  for (int32_t p = 0; p < nv; p++) {
    o->vact[p] = 0;
    if (!o->mask[p]) continue;
    double J[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, C[9] = {0}, gg[3];
    const double *xp = x + 3 * (size_t)p;
    memcpy(gg, g + 3 * (size_t)p, sizeof gg);
    int any = 0;
    for (int b = o->n - 1; b >= 0; b--) {
      const obstacle *ob = &o->obs[b];
      if (ob->mode != BS_COLLIDE_CONSTRAINT || !ob->active[p]) continue;
      bs_levelset_frame fl;
      const bs_levelset_frame *f = &frames[b];
      if (b >= 64) {
        bs_levelset_frame_at(ob->ls, t, &fl);
        f = &fl;
      }
      double n[3], A[9], Jb[9], Cb[9], Ag[3];
      bs_levelset_eval_frame(ob->ls, f, xp, n, A);
      for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Jb[3 * i + j] = (i == j) - n[i] * n[j];
      for (int i = 0; i < 3; i++) Ag[i] = bs_dot3(A + 3 * i, gg);
      double gn = bs_dot3(gg, n);
      for (int j = 0; j < 3; j++)
        for (int k = 0; k < 3; k++) Cb[3 * j + k] = -(gn * A[3 * j + k] + n[j] * Ag[k] + Ag[j] * n[k]);
      /* C <- J_b C J_b + C_b(g_b); g <- J_b g; J <- J J_b */
      mat3_mul(C, Jb, C);
      mat3_mul(Jb, C, C);
      for (int i = 0; i < 9; i++) C[i] += Cb[i];
      double s = gn;
      for (int k = 0; k < 3; k++) gg[k] -= s * n[k];
      mat3_mul(J, Jb, J);
      any = 1;
    }
    if (any) {
      /* C <- J^T C J: the Hessian on the tangent space (header). */
      mat3_mul(C, J, C);
      mat3_tmul(J, C, C);
      o->vact[p] = 1;
      memcpy(o->J + 9 * (size_t)p, J, sizeof J);
      memcpy(o->C + 9 * (size_t)p, C, sizeof C);
    }
  }
  /* H_pq <- J_p^T H_pq J_q, then H_pp += C_p. */
#pragma omp parallel for schedule(static) if (nv > 4096)
  for (int32_t i = 0; i < nv; i++) {
    for (int32_t s = H->row_ptr[i]; s < H->row_ptr[i + 1]; s++) {
      int32_t j = H->col[s];
      if (!o->vact[i] && !o->vact[j]) continue;
      double *B = H->val + 9 * (size_t)s;
      if (o->vact[j]) mat3_mul(B, o->J + 9 * (size_t)j, B);
      if (o->vact[i]) mat3_tmul(o->J + 9 * (size_t)i, B, B);
    }
    if (o->vact[i] && counted(o, i)) { /* C once over the processes */
      double *D = H->val + 9 * (size_t)H->diag[i];
      const double *C = o->C + 9 * (size_t)i;
      for (int k = 0; k < 9; k++) D[k] += C[k];
    }
  }
  /* The same for the blocks outside the pattern (self-collision couplings). */
  for (int64_t e = 0; e < H->n_extra; e++) {
    int32_t i = H->extra_ij[2 * e], j = H->extra_ij[2 * e + 1];
    double *B = H->extra_val + 9 * (size_t)e;
    if (o->vact[j]) mat3_mul(B, o->J + 9 * (size_t)j, B);
    if (o->vact[i]) mat3_tmul(o->J + 9 * (size_t)i, B, B);
  }
}

/* ---- after the solve: postprocess push and friction --------------------------- */

/* Coulomb friction on vertex p: the tangential velocity relative to the
 * obstacle (normal n) drops by dv = mu |f| dt / m, clamped at zero. */
static void apply_friction(const obstacle *ob, double t, const double *xp, const double n[3], double dv, double *vp,
                           double *dvp) {
  if (!(dv > 0)) return;
  double vo[3], vr[3];
  bs_levelset_velocity(ob->ls, t, xp, vo);
  for (int k = 0; k < 3; k++) vr[k] = vp[k] - vo[k];
  double vn = bs_dot3(vr, n), vt[3];
  for (int k = 0; k < 3; k++) vt[k] = vr[k] - vn * n[k];
  double st = sqrt(bs_dot3(vt, vt));
  if (!(st > 0)) return;
  double s = dv >= st ? 1.0 : dv / st;
  for (int k = 0; k < 3; k++) vp[k] -= s * vt[k];
  if (dvp)
    for (int k = 0; k < 3; k++) dvp[k] -= s * vt[k];
}

void bs_obstacles_friction_output(bs_obstacles *o, double *dv) { o->friction_dv = dv; }

int bs_obstacles_post_solve(const double *x_n, double *x, const double *g, double *v, double dt, void *ctx,
                            bs_error *err) {
  (void)x_n;
  bs_obstacles *o = ctx;
  if (!(dt > 0)) return bs_error_set(err, BS_EINPUT, "obstacles: post-solve time step must be positive, got %g", dt);
  const double t = o->step->time;
  const int32_t nv = o->nv;
  const double *mass = o->fem->mass;
  if (o->friction_dv) memset(o->friction_dv, 0, sizeof(double) * 3 * (size_t)nv);
  for (int b = 0; b < o->n; b++) {
    const obstacle *ob = &o->obs[b];
    bs_levelset_frame f;
    bs_levelset_frame_at(ob->ls, t, &f);
    const double tol = touch_tol(o, ob, &f);
#pragma omp parallel for schedule(static) if (nv > 4096)
    for (int32_t p = 0; p < nv; p++) {
      if (!o->mask[p]) continue;
      double *xp = x + 3 * (size_t)p, *vp = v + 3 * (size_t)p, n[3];
      double *dvp = o->friction_dv ? o->friction_dv + 3 * (size_t)p : NULL;
      const double m = mass[p];
      if (ob->mode == BS_COLLIDE_BARRIER) continue; /* its friction is in the barrier term */
      double phi = bs_levelset_eval_frame(ob->ls, &f, xp, n, NULL);
      if (ob->mode == BS_COLLIDE_CONSTRAINT) {
        /* active at x^{n+1}: collision force n (g'.n), g'.n >= 0 */
        double gn = bs_dot3(g + 3 * (size_t)p, n);
        if (fabs(phi) <= tol && gn >= 0 && m > 0) apply_friction(ob, t, xp, n, ob->mu * gn * dt / m, vp, dvp);
      } else if (ob->mode == BS_COLLIDE_PENALTY) {
        if (phi < 0 && m > 0) {
          double fmag = 3 * ob->k * phi * phi;
          apply_friction(ob, t, xp, n, ob->mu * fmag * dt / m, vp, dvp);
        }
      } else if (phi < 0) { /* postprocess: push out, no inward velocity, friction m d / dt^2 */
        const double d = -phi;
        for (int k = 0; k < 3; k++) xp[k] -= phi * n[k];
        double vo[3], vr[3];
        bs_levelset_velocity(ob->ls, t, xp, vo);
        for (int k = 0; k < 3; k++) vr[k] = vp[k] - vo[k];
        double vn = bs_dot3(vr, n);
        if (vn < 0)
          for (int k = 0; k < 3; k++) vp[k] -= vn * n[k];
        /* mu |f| dt / m with |f| = m d / dt^2 */
        apply_friction(ob, t, xp, n, ob->mu * d / dt, vp, dvp);
      }
    }
  }
  clear_labels(o);
  return 0;
}

/* ---- audit ------------------------------------------------------------------ */

void bs_obstacles_penetration(const bs_obstacles *o, double t, const double *x, double tol, int32_t *count,
                              double *max_depth) {
  int32_t c = 0;
  double dmax = 0;
  for (int32_t p = 0; p < o->nv; p++) {
    if (!o->mask[p]) continue;
    int inside = 0;
    for (int b = 0; b < o->n; b++) {
      double phi = bs_levelset_eval(o->obs[b].ls, t, x + 3 * (size_t)p, NULL, NULL);
      if (phi < -tol) inside = 1;
      if (-phi > dmax) dmax = -phi;
    }
    c += inside && counted(o, p);
  }
  if (count) *count = c;
  if (max_depth) *max_depth = dmax;
}
