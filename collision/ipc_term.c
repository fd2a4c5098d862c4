/* ipc_term.c — the barrier self-contact term and its CCD step bound
 * (bs_ipc_term.h): surface, candidate pairs through two swept-box
 * hierarchies, per-pair energies in parallel summed in list order. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "bs_bvh.h"
#include "bs_ipc.h"
#include "bs_ipc_term.h"
#include "ipc_internal.h"
#include "bs_shim.h"

#define PAR_MIN 64 /* pairs (triangles) below which loops run on one thread */

typedef bs_ipc_pair ipc_pair; /* bs_ipc_term.h */

/* One chunk's buffers (a contiguous range of triangles, one thread's at a
 * time): query results, the pairs of its triangles, and the candidates the
 * last max_step found for them (bs_ipc_term.h, "Candidates"). */
typedef struct tbuf {
  int32_t *qv, *qe;   /* n_sv, n_edges                               */
  ipc_pair *p;        /* its pairs (grown by doubling)               */
  int64_t n, cap;
  int32_t *cv, *ce;   /* max_step's candidates: surface vertices and edges,
                         triangle after triangle (grown by doubling) */
  int64_t ncv, cap_cv, nce, cap_ce;
  int64_t inter;      /* touching pairs and edge-triangle crossings  */
  double min_d2;      /* smallest candidate d^2                     */
  double tmin;        /* max_step: smallest safe t                   */
  int fail;           /* out of memory, or a CCD input error         */
  int cut;            /* max_step stopped early (t = 0): cv, ce partial */
} tbuf;

typedef struct ipc_data {
  const bs_mesh *mesh;
  double dhat, kappa, kappa_max, d2_eps, d2_prev;
  int adaptive;
  int project;         /* 1: each pair's Hessian PSD-projected      */
  int32_t nv, n_sv, n_faces, n_edges;
  int32_t *sv;         /* surface vertices, ascending              */
  int32_t *edges;      /* 2 per edge                               */
  int32_t *face_edge;  /* 3 per triangle: its edges                */
  int32_t *owner;      /* per edge: the lowest triangle that has it */
  int32_t *vt_elems, *et_elems; /* 4 per leaf simplex (see header) */
  bs_bvh vt, et;
  double cost_built;   /* the trees' cost at the last rebuild      */
  double *X2;          /* 6 nv: (x, x + d)                         */
  double *x_last;      /* 3 nv: the last detection's x             */
  int have_last, last_ok;
  int nthreads;        /* and chunks of triangles                  */
  tbuf *tb;            /* nthreads chunks                          */
  int64_t *cv_end, *ce_end; /* per triangle: the end of its candidates in
                               its chunk's cv, ce                 */
  double *sweep;       /* 6 n_sv: each surface vertex's box over max_step's
                          motion (lo[3], hi[3])                   */
  int sweep_ok;        /* 1: the candidates above are usable       */
  ipc_pair *pairs;     /* the active pairs of the last detection   */
  int64_t n_pairs, cap_pairs;
  double *pe, *pg, *ph; /* per pair: energy, gradient (12), Hessian (144) */
  int64_t cap_e, cap_g, cap_h;
  bs_ipc_stats st;
} ipc_data;

/* Chunk c of n's triangles: [*f0, *f1). */
static void chunk_range(const ipc_data *d, int c, int32_t *f0, int32_t *f1) {
  *f0 = (int32_t)((int64_t)d->n_faces * c / d->nthreads);
  *f1 = (int32_t)((int64_t)d->n_faces * (c + 1) / d->nthreads);
}

/* ---- geometry ------------------------------------------------------------ */

/* 1 when segment pq crosses triangle abc (touching counts; a segment in the
 * triangle's plane does not: it touches an edge first, a zero distance).
 * Exact orientations (bs_shim_orient3d): with rounded ones, a segment and a
 * triangle of one flat face that is not axis-aligned (a rotated box) were
 * seen to cross, the signs of orientations near zero being noise. */
static int seg_tri_cross(const double *p, const double *q, const double *a, const double *b, const double *c) {
  const int s1 = bs_shim_orient3d(a, b, c, p), s2 = bs_shim_orient3d(a, b, c, q);
  if (s1 == s2) return 0; /* both on one side, or both in the plane */
  const int o1 = bs_shim_orient3d(p, q, a, b), o2 = bs_shim_orient3d(p, q, b, c), o3 = bs_shim_orient3d(p, q, c, a);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

/* The box of n vertices vs (of X2's first half; with swept, also the second
 * half's), grown by pad. Positions are finite here (checked by the callers). */
static void box_of(const double *X2, int32_t nv, const int32_t *vs, int n, int swept, double pad, double lo[3],
                   double hi[3]) {
  for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
  for (int h = 0; h <= swept; h++)
    for (int i = 0; i < n; i++) {
      const double *p = X2 + 3 * ((size_t)vs[i] + (size_t)h * (size_t)nv);
      for (int k = 0; k < 3; k++) {
        lo[k] = p[k] < lo[k] ? p[k] : lo[k];
        hi[k] = p[k] > hi[k] ? p[k] : hi[k];
      }
    }
  for (int k = 0; k < 3; k++) lo[k] -= pad, hi[k] += pad;
}

/* The box of the points p and q (coordinates finite). */
static inline void box2(const double *p, const double *q, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; k++) {
    const int o = p[k] < q[k];
    lo[k] = o ? p[k] : q[k];
    hi[k] = o ? q[k] : p[k];
  }
}

/* The box of the points p, q, r, s. */
static inline void box4(const double *p, const double *q, const double *r, const double *s, double lo[3],
                        double hi[3]) {
  double l2[3], h2[3];
  box2(p, q, lo, hi);
  box2(r, s, l2, h2);
  for (int k = 0; k < 3; k++) {
    lo[k] = l2[k] < lo[k] ? l2[k] : lo[k];
    hi[k] = h2[k] > hi[k] ? h2[k] : hi[k];
  }
}

/* The closed boxes meet (bs_bvh_within's test, so that a filter with it
 * keeps what a query would have found). */
static int boxes_meet(const double *alo, const double *ahi, const double *blo, const double *bhi) {
  return !(alo[0] > bhi[0] || ahi[0] < blo[0] || alo[1] > bhi[1] || ahi[1] < blo[1] || alo[2] > bhi[2] ||
           ahi[2] < blo[2]);
}

static int has_vertex(const int32_t *vs, int n, int32_t v) {
  for (int i = 0; i < n; i++)
    if (vs[i] == v) return 1;
  return 0;
}

/* ---- detection ----------------------------------------------------------- */

static void push(tbuf *b, const int32_t v[4], int ee) {
  if (bs__ipc_grow((void **)&b->p, &b->cap, b->n + 1, sizeof(ipc_pair))) {
    b->fail = 1;
    return;
  }
  ipc_pair *p = &b->p[b->n++];
  memcpy(p->v, v, sizeof p->v);
  p->ee = ee;
}

/* Point-triangle candidates of triangle f (vertices F) in b->qv[0..nq). */
static void pt_candidates(const ipc_data *d, const double *x, const int32_t *F, int64_t nq, tbuf *b) {
  const double dh2 = d->dhat * d->dhat;
  for (int64_t j = 0; j < nq; j++) {
    const int32_t v = d->sv[b->qv[j]];
    if (has_vertex(F, 3, v)) continue;
    const int32_t pv[4] = {v, F[0], F[1], F[2]};
    double y[12];
    bs__ipc_gather(x, pv, y);
    const double d2 = bs_ipc_pt_d2_full(y, y + 3, y + 6, y + 9, NULL, NULL, NULL);
    if (d2 < b->min_d2) b->min_d2 = d2;
    if (!(d2 > 0)) b->inter++;
    else if (d2 < dh2) push(b, pv, 0);
  }
}

/* Edge candidates of triangle f in b->qe[0..nq): crossings of f, and the
 * edge-edge pairs of the edges f owns. */
static void ee_candidates(const ipc_data *d, const double *x, int32_t f, int64_t nq, tbuf *b) {
  const double dh2 = d->dhat * d->dhat;
  const int32_t *F = d->mesh->faces + 3 * (size_t)f;
  for (int64_t j = 0; j < nq; j++) {
    const int32_t eb = b->qe[j], *EB = d->edges + 2 * (size_t)eb;
    if (!has_vertex(F, 3, EB[0]) && !has_vertex(F, 3, EB[1]) &&
        seg_tri_cross(x + 3 * (size_t)EB[0], x + 3 * (size_t)EB[1], x + 3 * (size_t)F[0], x + 3 * (size_t)F[1],
                      x + 3 * (size_t)F[2]))
      b->inter++;
    for (int k = 0; k < 3; k++) {
      const int32_t ea = d->face_edge[3 * (size_t)f + k], *EA = d->edges + 2 * (size_t)ea;
      if (d->owner[ea] != f || eb <= ea || has_vertex(EA, 2, EB[0]) || has_vertex(EA, 2, EB[1])) continue;
      const int32_t pv[4] = {EA[0], EA[1], EB[0], EB[1]};
      double y[12];
      bs__ipc_gather(x, pv, y);
      const double d2 = bs_ipc_ee_d2_full(y, y + 3, y + 6, y + 9, NULL, NULL, NULL);
      if (d2 < b->min_d2) b->min_d2 = d2;
      if (!(d2 > 0)) b->inter++;
      else if (d2 < dh2) push(b, pv, 1);
    }
  }
}

/* The candidates of triangles [f0, f1) at x (trees refit to (x, x)). */
static void detect_range(ipc_data *d, const double *x, int32_t f0, int32_t f1, tbuf *b) {
  for (int32_t f = f0; f < f1; f++) {
    const int32_t *F = d->mesh->faces + 3 * (size_t)f;
    double lo[3], hi[3];
    box_of(d->X2, d->nv, F, 3, 0, d->dhat, lo, hi);
    pt_candidates(d, x, F, bs_bvh_within(&d->vt, lo, hi, b->qv, d->n_sv), b);
    ee_candidates(d, x, f, bs_bvh_within(&d->et, lo, hi, b->qe, d->n_edges), b);
  }
}

/* detect_range on the last max_step's candidates (x in its sweep): each
 * triangle's list filtered by the box test a query of the trees refit to
 * (x, x) makes, so the same vertices and edges in the same (leaf) order. */
static void detect_swept(ipc_data *d, const double *x, int32_t f0, int32_t f1, tbuf *b) {
  int64_t jv = 0, je = 0;
  for (int32_t f = f0; f < f1; f++) {
    const int32_t *F = d->mesh->faces + 3 * (size_t)f;
    double lo[3], hi[3], blo[3], bhi[3];
    box_of(x, d->nv, F, 3, 0, d->dhat, lo, hi);
    int64_t nq = 0;
    for (; jv < d->cv_end[f]; jv++) {
      const double *p = x + 3 * (size_t)d->sv[b->cv[jv]];
      if (boxes_meet(p, p, lo, hi)) b->qv[nq++] = b->cv[jv];
    }
    pt_candidates(d, x, F, nq, b);
    nq = 0;
    for (; je < d->ce_end[f]; je++) {
      const int32_t *E = d->edges + 2 * (size_t)b->ce[je];
      box2(x + 3 * (size_t)E[0], x + 3 * (size_t)E[1], blo, bhi);
      if (boxes_meet(blo, bhi, lo, hi)) b->qe[nq++] = b->ce[je];
    }
    ee_candidates(d, x, f, nq, b);
  }
}

/* X2 = (x, x + s d) (d NULL: (x, x)), the trees refit to it. */
static void refit(ipc_data *d, const double *x, const double *dx) {
  const size_t n3 = 3 * (size_t)d->nv;
  memcpy(d->X2, x, sizeof(double) * n3);
  for (size_t i = 0; i < n3; i++) d->X2[n3 + i] = dx ? x[i] + dx[i] : x[i];
  bs_bvh_refit(&d->vt, d->X2, d->nthreads);
  bs_bvh_refit(&d->et, d->X2, d->nthreads);
}

static int finite_all(const double *a, size_t n) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(a[i])) return 0;
  return 1;
}

/* 1 when every surface vertex of x is inside its box over the last
 * max_step's motion (d->sweep): then every primitive's box at x is inside
 * its swept box, and a pair within dhat at x is among that max_step's
 * candidates (queried with the swept boxes grown by dhat). */
static int in_sweep(const ipc_data *d, const double *x) {
  if (!d->sweep_ok) return 0;
  for (int32_t i = 0; i < d->n_sv; i++) {
    const double *p = x + 3 * (size_t)d->sv[i], *s = d->sweep + 6 * (size_t)i;
    if (p[0] < s[0] || p[1] < s[1] || p[2] < s[2] || p[0] > s[3] || p[1] > s[4] || p[2] > s[5]) return 0;
  }
  return 1;
}

/* The chunks' pairs concatenated in triangle order into d->pairs. */
static int merge(ipc_data *d) {
  int64_t n = 0, inter = 0;
  double m = INFINITY;
  for (int t = 0; t < d->nthreads; t++) {
    if (d->tb[t].fail) return BS_ENOMEM;
    n += d->tb[t].n, inter += d->tb[t].inter, m = fmin(m, d->tb[t].min_d2);
  }
  if (bs__ipc_grow((void **)&d->pairs, &d->cap_pairs, n, sizeof(ipc_pair))) return BS_ENOMEM;
  d->n_pairs = 0;
  for (int t = 0; t < d->nthreads; t++) {
    if (d->tb[t].n == 0) continue; /* no pairs (and maybe no buffers) */
    memcpy(d->pairs + d->n_pairs, d->tb[t].p, sizeof(ipc_pair) * (size_t)d->tb[t].n);
    d->n_pairs += d->tb[t].n;
  }
  d->st.pairs_pt = d->st.pairs_ee = 0;
  for (int64_t i = 0; i < n; i++) {
    if (d->pairs[i].ee) d->st.pairs_ee++;
    else d->st.pairs_pt++;
  }
  d->st.intersecting = inter;
  d->st.min_distance = m < INFINITY ? sqrt(fmax(m, 0)) : INFINITY;
  return 0;
}

/* The pairs at x (reused when x is bitwise the last detection's): 0 when
 * the term is evaluable there, 1 when not (non-finite x, touching or
 * crossing surfaces, or no memory for the pair list). Inside the last
 * max_step's sweep only the narrow phase runs, on its candidates; else the
 * trees are refit to x and queried. Either way the same pairs. */
static int detect(ipc_data *d, const double *x) {
  const size_t n3 = 3 * (size_t)d->nv;
  if (d->have_last && memcmp(x, d->x_last, sizeof(double) * n3) == 0) return !d->last_ok;
  d->have_last = 0;
  if (!finite_all(x, n3)) return 1;
  const int swept = in_sweep(d, x);
  if (!swept) refit(d, x, NULL);
#pragma omp parallel for schedule(static) num_threads(d->nthreads) if (d->n_faces >= PAR_MIN)
  for (int c = 0; c < d->nthreads; c++) {
    tbuf *b = &d->tb[c];
    int32_t f0, f1;
    chunk_range(d, c, &f0, &f1);
    b->n = 0, b->inter = 0, b->min_d2 = INFINITY, b->fail = 0;
    if (swept) detect_swept(d, x, f0, f1, b);
    else detect_range(d, x, f0, f1, b);
  }
  d->st.detections++;
  d->st.detections_swept += swept;
  if (merge(d)) return 1;
  memcpy(d->x_last, x, sizeof(double) * n3);
  d->have_last = 1;
  d->last_ok = d->st.intersecting == 0;
  return !d->last_ok;
}

/* ---- energy -------------------------------------------------------------- */

/* Pair p's energy with kappa (and g[12], H[144] when non-NULL). */
static int pair_energy(const ipc_data *d, const double *x, const ipc_pair *p, double kappa, double *E, double *g,
                       double *H) {
  double y[12];
  bs__ipc_gather(x, p->v, y);
  if (!p->ee) return bs_ipc_pt_energy(y, y + 3, y + 6, y + 9, d->dhat, kappa, d->project, E, g, H, NULL);
  double r[12];
  bs__ipc_gather(d->mesh->x, p->v, r);
  const double eps = bs_ipc_mollifier_eps(r, r + 3, r + 6, r + 9);
  return bs_ipc_ee_energy(y, y + 3, y + 6, y + 9, eps, d->dhat, kappa, d->project, E, g, H, NULL);
}

/* Every pair's energy (gradient, Hessian with want 1, 2) into d->pe, pg, ph,
 * in parallel; 0, or 1 when a pair is not evaluable. */
static int pair_loop(ipc_data *d, const double *x, double kappa, int want) {
  const int64_t n = d->n_pairs;
  if (bs__ipc_grow((void **)&d->pe, &d->cap_e, n, sizeof(double)) ||
      (want >= 1 && bs__ipc_grow((void **)&d->pg, &d->cap_g, 12 * n, sizeof(double))) ||
      (want >= 2 && bs__ipc_grow((void **)&d->ph, &d->cap_h, 144 * n, sizeof(double))))
    return 1;
  int bad = 0;
#pragma omp parallel for schedule(static) num_threads(d->nthreads) reduction(| : bad) if (n >= PAR_MIN)
  for (int64_t i = 0; i < n; i++)
    bad |= pair_energy(d, x, &d->pairs[i], kappa, &d->pe[i], want >= 1 ? d->pg + 12 * i : NULL,
                       want >= 2 ? d->ph + 144 * i : NULL) < 0;
  return bad;
}

static double energy_sum(const ipc_data *d) {
  double s = 0;
  for (int64_t i = 0; i < d->n_pairs; i++) s += d->pe[i];
  return s;
}

static int ipc_value(const bs_term *t, const double *x, double *E) {
  ipc_data *d = t->data;
  if (detect(d, x) || pair_loop(d, x, d->kappa, 0)) return BS_TERM_NOT_EVALUABLE;
  *E = energy_sum(d);
  return BS_TERM_OK;
}

static int ipc_gradient(const bs_term *t, const double *x, double *E, double *g) {
  ipc_data *d = t->data;
  if (detect(d, x) || pair_loop(d, x, d->kappa, 1)) return BS_TERM_NOT_EVALUABLE;
  *E = energy_sum(d);
  for (int64_t i = 0; i < d->n_pairs; i++)
    for (int a = 0; a < 4; a++)
      for (int k = 0; k < 3; k++) g[3 * (size_t)d->pairs[i].v[a] + k] += d->pg[12 * i + 3 * a + k];
  return BS_TERM_OK;
}

static int ipc_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  ipc_data *d = t->data;
  if (detect(d, x) || pair_loop(d, x, d->kappa, 2)) return BS_TERM_NOT_EVALUABLE;
  int64_t missing = 0;
  for (int64_t i = 0; i < d->n_pairs; i++) {
    const double *Hl = d->ph + 144 * i;
    for (int a = 0; a < 4; a++)
      for (int b = 0; b < 4; b++) {
        double B[9];
        for (int r = 0; r < 3; r++)
          for (int q = 0; q < 3; q++) B[3 * r + q] = Hl[(3 * a + r) * 12 + 3 * b + q];
        missing += bs_bsr_add_block(H, d->pairs[i].v[a], d->pairs[i].v[b], B) == BS_BSR_DROPPED;
      }
  }
  d->st.missing_blocks = missing;
  return BS_TERM_OK;
}

/* ---- continuous collision detection ---------------------------------------- */

/* One pair's safe fraction of the motion in X2 (x0: first half, x1:
 * second): into b->tmin. */
static void ccd_pair(const ipc_data *d, const int32_t v[4], int ee, tbuf *b) {
  double x0[12], x1[12], t = 1;
  bs__ipc_gather(d->X2, v, x0);
  bs__ipc_gather(d->X2 + 3 * (size_t)d->nv, v, x1);
  const int rc = ee ? bs_ccd_ee(x0, x1, BS_IPC_CCD_S, BS_IPC_CCD_ITER, &t, NULL)
                    : bs_ccd_pt(x0, x1, BS_IPC_CCD_S, BS_IPC_CCD_ITER, &t, NULL);
  if (rc == BS_EINPUT) b->fail = 1;
  b->tmin = fmin(b->tmin, rc < 0 ? 0.0 : t);
}

/* Appends the n entries of q to *list (grown by doubling); 0 or 1 (no memory). */
static int append(int32_t **list, int64_t *len, int64_t *cap, const int32_t *q, int64_t n) {
  if (bs__ipc_grow((void **)list, cap, *len + n, sizeof(int32_t))) return 1;
  memcpy(*list + *len, q, sizeof(int32_t) * (size_t)n);
  *len += n;
  return 0;
}

/* Triangle f's edge candidates b->qe[0..ne) whose swept boxes meet its own
 * (lo, hi): the edge-edge pairs of the edges f owns, through the CCD. */
static void ccd_edges(ipc_data *d, int32_t f, const double lo[3], const double hi[3], int64_t ne, tbuf *b) {
  const double *X0 = d->X2, *X1 = d->X2 + 3 * (size_t)d->nv;
  int32_t own[3], n_own = 0;
  double alo[3][3], ahi[3][3];
  for (int k = 0; k < 3; k++) {
    const int32_t ea = d->face_edge[3 * (size_t)f + k], *EA = d->edges + 2 * (size_t)ea;
    if (d->owner[ea] != f) continue;
    box4(X0 + 3 * (size_t)EA[0], X0 + 3 * (size_t)EA[1], X1 + 3 * (size_t)EA[0], X1 + 3 * (size_t)EA[1],
         alo[n_own], ahi[n_own]);
    own[n_own++] = ea;
  }
  for (int64_t j = 0; j < ne && n_own > 0; j++) {
    const int32_t eb = b->qe[j], *EB = d->edges + 2 * (size_t)eb;
    double blo[3], bhi[3];
    box4(X0 + 3 * (size_t)EB[0], X0 + 3 * (size_t)EB[1], X1 + 3 * (size_t)EB[0], X1 + 3 * (size_t)EB[1], blo, bhi);
    if (!boxes_meet(blo, bhi, lo, hi)) continue;
    for (int k = 0; k < n_own; k++) {
      const int32_t ea = own[k], *EA = d->edges + 2 * (size_t)ea;
      if (eb <= ea || has_vertex(EA, 2, EB[0]) || has_vertex(EA, 2, EB[1])) continue;
      const int32_t pv[4] = {EA[0], EA[1], EB[0], EB[1]};
      if (boxes_meet(alo[k], ahi[k], blo, bhi)) ccd_pair(d, pv, 1, b);
    }
  }
}

/* The CCD of triangles [f0, f1)'s pairs over the motion in X2 (trees refit
 * to it): the smallest t into b->tmin. Each triangle's trees are queried
 * once, with its swept box grown by dhat: those candidates are kept (b->cv,
 * b->ce, their ends in d->cv_end, d->ce_end) for the detections along the
 * motion, and the CCD takes those whose boxes meet the triangle's own. */
static void ccd_range(ipc_data *d, int32_t f0, int32_t f1, tbuf *b) {
  b->tmin = 1, b->fail = 0, b->cut = 0, b->ncv = 0, b->nce = 0;
  for (int32_t f = f0; f < f1; f++) {
    if (!(b->tmin > 0)) {
      b->cut = 1; /* no step: the rest would not be used */
      return;
    }
    const int32_t *F = d->mesh->faces + 3 * (size_t)f;
    double lo[3], hi[3], plo[3], phi[3], vlo[3], vhi[3];
    box_of(d->X2, d->nv, F, 3, 1, 0.0, lo, hi);
    for (int k = 0; k < 3; k++) plo[k] = lo[k] - d->dhat, phi[k] = hi[k] + d->dhat;
    const int64_t nq = bs_bvh_within(&d->vt, plo, phi, b->qv, d->n_sv);
    const int64_t ne = bs_bvh_within(&d->et, plo, phi, b->qe, d->n_edges);
    if (append(&b->cv, &b->ncv, &b->cap_cv, b->qv, nq) || append(&b->ce, &b->nce, &b->cap_ce, b->qe, ne)) {
      b->fail = 1;
      return;
    }
    d->cv_end[f] = b->ncv, d->ce_end[f] = b->nce;
    for (int64_t j = 0; j < nq; j++) {
      const int32_t v = d->sv[b->qv[j]], pv[4] = {v, F[0], F[1], F[2]};
      box2(d->X2 + 3 * (size_t)v, d->X2 + 3 * ((size_t)v + (size_t)d->nv), vlo, vhi);
      if (!has_vertex(F, 3, v) && boxes_meet(vlo, vhi, lo, hi)) ccd_pair(d, pv, 0, b);
    }
    ccd_edges(d, f, lo, hi, ne, b);
  }
}

/* Each surface vertex's box over the motion in X2 into d->sweep. */
static void set_sweep(ipc_data *d) {
  for (int32_t i = 0; i < d->n_sv; i++) {
    double *s = d->sweep + 6 * (size_t)i;
    const size_t v = (size_t)d->sv[i];
    box2(d->X2 + 3 * v, d->X2 + 3 * (v + (size_t)d->nv), s, s + 3);
  }
}

/* The smallest safe fraction of x -> x + dx: 0 ok, 1 not evaluable. */
static int max_step_impl(ipc_data *d, const double *x, const double *dx, double *alpha) {
  const size_t n3 = 3 * (size_t)d->nv;
  *alpha = 0;
  d->sweep_ok = 0;
  if (!finite_all(x, n3) || !finite_all(dx, n3)) return 1;
  refit(d, x, dx);
#pragma omp parallel for schedule(static) num_threads(d->nthreads) if (d->n_faces >= PAR_MIN)
  for (int c = 0; c < d->nthreads; c++) {
    int32_t f0, f1;
    chunk_range(d, c, &f0, &f1);
    ccd_range(d, f0, f1, &d->tb[c]);
  }
  double a = 1;
  int cut = 0;
  for (int t = 0; t < d->nthreads; t++) {
    if (d->tb[t].fail) return 1;
    a = fmin(a, d->tb[t].tmin);
    cut |= d->tb[t].cut;
  }
  if (!cut && finite_all(d->X2 + n3, n3)) {
    set_sweep(d);
    d->sweep_ok = 1;
  }
  d->st.ccd_calls++;
  d->st.ccd_limited += a < 1;
  *alpha = a;
  return 0;
}

static int ipc_max_step(const bs_term *t, const double *x, const double *dx, double *alpha) {
  return max_step_impl(t->data, x, dx, alpha) ? BS_TERM_NOT_EVALUABLE : BS_TERM_OK;
}

/* The sweep's predictor (bs_terms.h, carry): each vertex of an active pair
 * at x that has a carried vertex is carried with the first of them, in
 * pair order (deterministic). */
static int ipc_carry(const bs_term *t, const double *x, double t0, double t1, double *z, uint8_t *carried) {
  (void)t0, (void)t1;
  ipc_data *d = t->data;
  if (detect(d, x)) return BS_TERM_NOT_EVALUABLE;
  for (int64_t i = 0; i < d->n_pairs; i++) {
    const int32_t *v = d->pairs[i].v;
    int src = -1;
    for (int k = 0; k < 4 && src < 0; k++)
      if (carried[v[k]]) src = k;
    for (int k = 0; k < 4 && src >= 0; k++)
      if (!carried[v[k]]) {
        carried[v[k]] = 1;
        memcpy(z + 3 * (size_t)v[k], z + 3 * (size_t)v[src], 3 * sizeof *z);
      }
  }
  return BS_TERM_OK;
}

/* ---- step start ------------------------------------------------------------ */

static void rebuild(ipc_data *d, const double *x) {
  refit(d, x, NULL);
  bs_bvh_build(&d->vt, d->X2, d->nthreads);
  bs_bvh_build(&d->et, d->X2, d->nthreads);
  bs_bvh_refit(&d->vt, d->X2, d->nthreads);
  bs_bvh_refit(&d->et, d->X2, d->nthreads);
  d->cost_built = bs_bvh_cost(&d->vt) + bs_bvh_cost(&d->et);
  d->st.rebuilds++;
  d->have_last = 0;
  d->sweep_ok = 0; /* the candidates are in the old trees' leaf order */
}

/* At xⁿ: the trees rebuilt when their cost grew (bs_ipc_term.h), then the
 * adaptive kappa from the smallest d^2 of this step and the last. */
static int ipc_begin_step(bs_term *t, bs_error *err) {
  ipc_data *d = t->data;
  if (!t->step || !t->step->x_n) return 0;
  const double *xn = t->step->x_n;
  if (!finite_all(xn, 3 * (size_t)d->nv)) return bs_error_set(err, BS_ENUMERIC, "barrier contact: x^n is not finite");
  refit(d, xn, NULL);
  d->have_last = 0;
  if (bs_bvh_cost(&d->vt) + bs_bvh_cost(&d->et) > BS_IPC_REBUILD_GROWTH * d->cost_built) rebuild(d, xn);
  if (!d->adaptive) return 0;
  if (detect(d, xn))
    return bs_error_set(err, BS_ENUMERIC,
                        "barrier contact: the surfaces touch or cross at the step's start (%lld pairs)",
                        (long long)d->st.intersecting);
  const double dh2 = d->dhat * d->dhat, m = d->st.min_distance;
  const double d2 = d->n_pairs > 0 ? fmin(m * m, dh2) : dh2;
  d->kappa = bs_ipc_kappa_update(d->kappa, d->kappa_max, d->d2_prev, d2, d->d2_eps);
  d->d2_prev = d2;
  return 0;
}

/* ---- creation -------------------------------------------------------------- */

static void ipc_free(void *p) {
  ipc_data *d = p;
  if (!d) return;
  bs_bvh_free(&d->vt);
  bs_bvh_free(&d->et);
  for (int t = 0; d->tb && t < d->nthreads; t++) {
    free(d->tb[t].qv);
    free(d->tb[t].qe);
    free(d->tb[t].p);
    free(d->tb[t].cv);
    free(d->tb[t].ce);
  }
  free(d->tb);
  free(d->sv);
  free(d->edges);
  free(d->face_edge);
  free(d->owner);
  free(d->vt_elems);
  free(d->et_elems);
  free(d->X2);
  free(d->x_last);
  free(d->cv_end);
  free(d->ce_end);
  free(d->sweep);
  free(d->pairs);
  free(d->pe);
  free(d->pg);
  free(d->ph);
  free(d);
}

/* The convexified Hessian: every pair's projected, whatever d->project. */
static int ipc_hessian_convex(const bs_term *t, const double *x, bs_bsr *H) {
  ipc_data *d = t->data;
  const int keep = d->project;
  d->project = 1;
  const int rc = ipc_hessian(t, x, H);
  d->project = keep;
  return rc;
}

static const bs_term_ops ipc_ops = {ipc_value, ipc_gradient, ipc_hessian, ipc_begin_step, ipc_free,
                                    ipc_hessian_convex, NULL, ipc_max_step, NULL, ipc_carry};

typedef struct edge_key {
  int32_t a, b, f, k; /* a < b; triangle f's k-th edge */
} edge_key;

static int cmp_edge_key(const void *p, const void *q) {
  const edge_key *u = p, *v = q;
  if (u->a != v->a) return u->a < v->a ? -1 : 1;
  if (u->b != v->b) return u->b < v->b ? -1 : 1;
  return (u->f > v->f) - (u->f < v->f);
}

/* The edges of the boundary triangles, each once (sorted by vertices), the
 * triangles' edges and each edge's owner (its lowest triangle). */
static int build_edges(ipc_data *d, bs_error *err) {
  const int32_t nf = d->n_faces, *F = d->mesh->faces;
  edge_key *k = bs_calloc(3 * (size_t)nf + 1, sizeof *k, "the barrier's edges", err);
  d->face_edge = bs_calloc(3 * (size_t)nf + 1, sizeof(int32_t), "the barrier's edges", err);
  d->edges = bs_calloc(6 * (size_t)nf + 2, sizeof(int32_t), "the barrier's edges", err);
  d->owner = bs_calloc(3 * (size_t)nf + 1, sizeof(int32_t), "the barrier's edges", err);
  if (!k || !d->face_edge || !d->edges || !d->owner) {
    free(k);
    return BS_ENOMEM;
  }
  for (int32_t f = 0; f < nf; f++)
    for (int j = 0; j < 3; j++) {
      const int32_t a = F[3 * f + j], b = F[3 * f + (j + 1) % 3];
      k[3 * f + j] = (edge_key){a < b ? a : b, a < b ? b : a, f, j};
    }
  qsort(k, 3 * (size_t)nf, sizeof *k, cmp_edge_key);
  int32_t ne = 0;
  for (size_t i = 0; i < 3 * (size_t)nf; i++) {
    if (i == 0 || k[i].a != k[i - 1].a || k[i].b != k[i - 1].b) {
      d->edges[2 * ne] = k[i].a, d->edges[2 * ne + 1] = k[i].b;
      d->owner[ne++] = k[i].f; /* the lowest triangle: sorted by f last */
    }
    d->face_edge[3 * k[i].f + k[i].k] = ne - 1;
  }
  d->n_edges = ne;
  free(k);
  return 0;
}

/* Surface vertices, the trees' leaf simplices and the buffers. */
static int build_surface(ipc_data *d, bs_error *err) {
  const bs_mesh *m = d->mesh;
  uint8_t *is = bs_calloc((size_t)m->n_vertices + 1, 1, "the barrier's surface", err);
  if (!is) return BS_ENOMEM;
  for (int32_t i = 0; i < 3 * m->n_faces; i++) is[m->faces[i]] = 1;
  for (int32_t v = 0; v < m->n_vertices; v++) d->n_sv += is[v];
  d->sv = bs_calloc((size_t)d->n_sv + 1, sizeof(int32_t), "the barrier's surface", err);
  d->vt_elems = bs_calloc(4 * (size_t)d->n_sv + 1, sizeof(int32_t), "the barrier's trees", err);
  d->et_elems = bs_calloc(4 * (size_t)d->n_edges + 1, sizeof(int32_t), "the barrier's trees", err);
  d->X2 = bs_calloc(6 * (size_t)d->nv + 1, sizeof(double), "the barrier's positions", err);
  d->x_last = bs_calloc(3 * (size_t)d->nv + 1, sizeof(double), "the barrier's positions", err);
  d->tb = bs_calloc((size_t)d->nthreads, sizeof(tbuf), "the barrier's thread buffers", err);
  d->cv_end = bs_calloc((size_t)d->n_faces + 1, sizeof(int64_t), "the barrier's candidates", err);
  d->ce_end = bs_calloc((size_t)d->n_faces + 1, sizeof(int64_t), "the barrier's candidates", err);
  d->sweep = bs_calloc(6 * (size_t)d->n_sv + 1, sizeof(double), "the barrier's candidates", err);
  int st = !d->sv || !d->vt_elems || !d->et_elems || !d->X2 || !d->x_last || !d->tb || !d->cv_end || !d->ce_end ||
                   !d->sweep
               ? BS_ENOMEM
               : 0;
  for (int t = 0; !st && t < d->nthreads; t++) {
    d->tb[t].qv = bs_calloc((size_t)d->n_sv + 1, sizeof(int32_t), "the barrier's query buffers", err);
    d->tb[t].qe = bs_calloc((size_t)d->n_edges + 1, sizeof(int32_t), "the barrier's query buffers", err);
    if (!d->tb[t].qv || !d->tb[t].qe) st = BS_ENOMEM;
  }
  if (!st) {
    const int32_t n = d->nv;
    for (int32_t v = 0, j = 0; v < m->n_vertices; v++)
      if (is[v]) {
        d->sv[j] = v;
        const int32_t e4[4] = {v, v + n, v, v + n};
        memcpy(d->vt_elems + 4 * (size_t)j++, e4, sizeof e4);
      }
    for (int32_t e = 0; e < d->n_edges; e++) {
      const int32_t a = d->edges[2 * e], b = d->edges[2 * e + 1], e4[4] = {a, b, a + n, b + n};
      memcpy(d->et_elems + 4 * (size_t)e, e4, sizeof e4);
    }
  }
  free(is);
  if (!st) st = bs_bvh_init(&d->vt, d->vt_elems, 4, d->n_sv, err);
  if (!st) st = bs_bvh_init(&d->et, d->et_elems, 4, d->n_edges, err);
  return st;
}

int bs_term_ipc_create(const bs_fem *fem, const bs_step_data *step, double dhat, double kappa, bs_term **out,
                       bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "barrier contact: out is NULL");
  *out = NULL;
  if (!fem || !fem->mesh) return bs_error_set(err, BS_EINPUT, "barrier contact: no fem");
  if (!(dhat > 0) || !isfinite(dhat))
    return bs_error_set(err, BS_EINPUT, "barrier contact: dhat must be finite and > 0 (m), got %g", dhat);
  if (!(kappa >= 0) || !isfinite(kappa))
    return bs_error_set(err, BS_EINPUT, "barrier contact: kappa must be finite and >= 0, got %g", kappa);
  const bs_mesh *m = fem->mesh;
  if (m->n_faces < 1) return bs_error_set(err, BS_EINPUT, "barrier contact: the mesh has no boundary triangles");
  if (m->n_vertices > INT32_MAX / 2)
    return bs_error_set(err, BS_EINPUT, "barrier contact: %d vertices, at most %d", (int)m->n_vertices, INT32_MAX / 2);
  ipc_data *d = bs_calloc(1, sizeof *d, "the barrier contact term", err);
  if (!d) return BS_ENOMEM;
  d->mesh = m;
  d->nv = m->n_vertices;
  d->n_faces = m->n_faces;
  d->dhat = dhat;
  d->kappa = kappa;
  d->d2_prev = dhat * dhat;
  d->project = 1;
  d->nthreads = 1;
#ifdef _OPENMP
  d->nthreads = omp_get_max_threads();
#endif
  int st = build_edges(d, err);
  if (!st) st = build_surface(d, err);
  bs_term *t = NULL;
  if (!st) {
    rebuild(d, m->x);
    t = calloc(1, sizeof *t);
    if (!t) st = bs_error_set(err, BS_ENOMEM, "out of memory creating the barrier contact term");
  }
  if (st) {
    ipc_free(d);
    return st;
  }
  t->name = "barrier_contact";
  t->kind = BS_TERM_BARRIER_CONTACT;
  t->ops = &ipc_ops;
  t->fem = fem;
  t->step = step;
  t->hessian_extra = BS_IPC_EXTRA_PER_VERTEX * (int64_t)d->n_sv;
  t->data = d;
  d->st.min_distance = INFINITY;
  *out = t;
  return 0;
}

int bs_term_is_ipc(const bs_term *t) { return t && t->kind == BS_TERM_BARRIER_CONTACT && t->ops == &ipc_ops; }

static int not_ipc(const bs_term *t, bs_error *err) {
  return bs_term_is_ipc(t) ? 0 : bs_error_set(err, BS_EINPUT, "not a barrier contact term");
}

int bs_term_ipc_set_kappa(bs_term *t, double kappa, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  if (!(kappa >= 0) || !isfinite(kappa))
    return bs_error_set(err, BS_EINPUT, "barrier contact: kappa must be finite and >= 0, got %g", kappa);
  ((ipc_data *)t->data)->kappa = kappa;
  return 0;
}

int bs_term_ipc_set_project(bs_term *t, int on, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  ((ipc_data *)t->data)->project = on != 0;
  return 0;
}

int bs_term_ipc_set_adaptive(bs_term *t, double kappa_max, double d2_eps, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  if (!(kappa_max >= 0) || !isfinite(kappa_max) || !(d2_eps > 0) || !isfinite(d2_eps))
    return bs_error_set(err, BS_EINPUT,
                        "barrier contact: adaptive kappa needs kappa_max >= 0 and d2_eps > 0 finite, got %g and %g",
                        kappa_max, d2_eps);
  ipc_data *d = t->data;
  d->adaptive = kappa_max > 0;
  d->kappa_max = kappa_max;
  d->d2_eps = d2_eps;
  return 0;
}

int bs_term_ipc_kappa_init(bs_term *t, const double *x, const double *grad_energy, double kappa_min,
                           double kappa_max, double *kappa, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  ipc_data *d = t->data;
  const size_t n3 = 3 * (size_t)d->nv;
  if (detect(d, x) || pair_loop(d, x, 1.0, 1))
    return bs_error_set(err, BS_ENUMERIC, "barrier contact: not evaluable at the initial positions (%lld touching "
                        "or crossing pairs)", (long long)d->st.intersecting);
  double *gb = bs_calloc(n3 + 1, sizeof(double), "the barrier gradient", err);
  if (!gb) return BS_ENOMEM;
  for (int64_t i = 0; i < d->n_pairs; i++)
    for (int a = 0; a < 4; a++)
      for (int k = 0; k < 3; k++) gb[3 * (size_t)d->pairs[i].v[a] + k] += d->pg[12 * i + 3 * a + k];
  d->kappa = bs_ipc_kappa_initial(n3, grad_energy, gb, kappa_min, kappa_max);
  free(gb);
  if (kappa) *kappa = d->kappa;
  return 0;
}

int bs_term_ipc_stats(const bs_term *t, bs_ipc_stats *out, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  const ipc_data *d = t->data;
  *out = d->st;
  out->kappa = d->kappa;
  out->dhat = d->dhat;
  return 0;
}

int bs_term_ipc_detect(bs_term *t, const double *x, bs_ipc_stats *out, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  ipc_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv)) return bs_error_set(err, BS_ENUMERIC, "barrier contact: x is not finite");
  if (detect(d, x) && d->st.intersecting == 0)
    return bs_error_set(err, BS_ENOMEM, "barrier contact: out of memory listing the pairs");
  if (out) bs_term_ipc_stats(t, out, err);
  return 0;
}

int bs_term_ipc_max_step(bs_term *t, const double *x, const double *dx, double *alpha, bs_error *err) {
  if (not_ipc(t, err)) return BS_EINPUT;
  if (max_step_impl(t->data, x, dx, alpha))
    return bs_error_set(err, BS_ENUMERIC, "barrier contact: CCD on non-finite positions or motion");
  return 0;
}

int bs_term_ipc_pairs(bs_term *t, const double *x, const bs_ipc_pair **pairs, int64_t *n, bs_error *err) {
  if (pairs) *pairs = NULL;
  if (n) *n = 0;
  if (not_ipc(t, err)) return BS_EINPUT;
  if (!pairs || !n) return bs_error_set(err, BS_EINPUT, "barrier contact: pairs or n is NULL");
  ipc_data *d = t->data;
  if (!finite_all(x, 3 * (size_t)d->nv)) return bs_error_set(err, BS_ENUMERIC, "barrier contact: x is not finite");
  if (detect(d, x))
    return d->st.intersecting > 0
               ? bs_error_set(err, BS_ENUMERIC, "barrier contact: %lld pairs touch or cross",
                              (long long)d->st.intersecting)
               : bs_error_set(err, BS_ENOMEM, "barrier contact: out of memory listing the pairs");
  *pairs = d->pairs;
  *n = d->n_pairs;
  return 0;
}
