/* study_compare.c — errors of a run against the reference, from their state
 * files (state.bin through bs_state_reader), at common frame times and
 * through the vertex blocks that refinement keeps (bs_study.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

/* Squared position and velocity differences summed over the blocks. */
static void block_sums(const bs_state_reader *a, const bs_state_reader *b, int n_blocks, const int64_t *off_a,
                       const int64_t *off_b, const int64_t *count, double *ex, double *ev) {
  *ex = *ev = 0;
  for (int q = 0; q < n_blocks; q++) {
    const double *xa = a->buf + 1 + 3 * off_a[q], *xb = b->buf + 1 + 3 * off_b[q];
    const double *va = a->buf + 1 + 3 * (size_t)a->n + 3 * off_a[q], *vb = b->buf + 1 + 3 * (size_t)b->n + 3 * off_b[q];
    for (int64_t i = 0; i < 3 * count[q]; i++) {
      double dx = xa[i] - xb[i], dv = va[i] - vb[i];
      *ex += dx * dx;
      *ev += dv * dv;
    }
  }
}

int bs__study_compare_states(bs_state_reader *a, bs_state_reader *b, int n_blocks, const int64_t *off_a,
                            const int64_t *off_b, const int64_t *count, double xscale, double vscale,
                            bs_study_errors *e) {
  e->pos_max = e->vel_max = e->pos_last = e->vel_last = NAN;
  e->n_common = 0;
  int64_t ncmp = 0;
  for (int q = 0; q < n_blocks; q++) {
    if (count[q] < 0 || off_a[q] < 0 || off_b[q] < 0 || off_a[q] + count[q] > a->n || off_b[q] + count[q] > b->n)
      return -1;
    ncmp += count[q];
  }
  int have_a = bs_state_next(a) == 0, have_b = bs_state_next(b) == 0;
  while (have_a && have_b) {
    double ta = a->buf[0], tb = b->buf[0], eps = 1e-9 * (1 + fabs(tb));
    if (fabs(ta - tb) <= eps) {
      double ex, ev;
      block_sums(a, b, n_blocks, off_a, off_b, count, &ex, &ev);
      double px = sqrt(ex / (double)ncmp) / xscale, pv = sqrt(ev / (double)ncmp) / vscale;
      if (!isfinite(px)) px = INFINITY;
      if (!isfinite(pv)) pv = INFINITY;
      e->pos_max = e->n_common ? fmax(e->pos_max, px) : px;
      e->vel_max = e->n_common ? fmax(e->vel_max, pv) : pv;
      e->pos_last = px;
      e->vel_last = pv;
      e->n_common++;
      have_a = bs_state_next(a) == 0;
      have_b = bs_state_next(b) == 0;
    } else if (ta < tb) have_a = bs_state_next(a) == 0;
    else have_b = bs_state_next(b) == 0;
  }
  return e->n_common ? 0 : -1;
}

/* Errors of run r against the folder ref_dir, whose body blocks start at
 * off_ref: into r's error fields (left as they are when a state file cannot
 * be opened; NAN when the vertices do not match or no frame time is common). */
int bs__study_compare_run(const bs_study *S, bs_study_run *r, const char *ref_dir, const int64_t *off_ref) {
  bs_state_reader a, b;
  bs_error e;
  if (bs_state_open(r->dir, &a, &e)) return -1;
  if (bs_state_open(ref_dir, &b, &e)) {
    bs_state_close(&a);
    return -1;
  }
  int64_t off_r[BS_STUDY_MAX_BODIES], zero = 0, all = a.n;
  int ok = S->direct ? a.n == b.n : bs__study_offsets(S, r->body_refine, off_r) == a.n;
  bs_study_errors er = {NAN, NAN, NAN, NAN, 0};
  int st = -1;
  if (ok && S->direct) st = bs__study_compare_states(&a, &b, 1, &zero, &zero, &all, S->xscale, S->vscale, &er);
  else if (ok) st = bs__study_compare_states(&a, &b, S->n_bodies, off_r, off_ref, S->cmp, S->xscale, S->vscale, &er);
  r->pos_max = er.pos_max;
  r->pos_last = er.pos_last;
  r->vel_max = er.vel_max;
  r->vel_last = er.vel_last;
  bs_state_close(&a);
  bs_state_close(&b);
  return st;
}

double bs__study_disp_scale(bs_state_reader *r, int n_blocks, const int64_t *off, const int64_t *count) {
  int64_t n = 0;
  for (int q = 0; q < n_blocks; q++) {
    if (count[q] < 0 || off[q] < 0 || off[q] + count[q] > r->n) return 0;
    n += count[q];
  }
  double *x0 = malloc(sizeof(double) * (size_t)(3 * n + 1)), m = 0;
  if (!x0 || bs_state_next(r)) {
    free(x0);
    return 0;
  }
  for (int q = 0, k = 0; q < n_blocks; k += 3 * (int)count[q], q++)
    memcpy(x0 + k, r->x + 3 * off[q], sizeof(double) * 3 * (size_t)count[q]);
  do {
    double s = 0;
    for (int q = 0, k = 0; q < n_blocks; k += 3 * (int)count[q], q++)
      for (int64_t i = 0; i < 3 * count[q]; i++) {
        double d = r->x[3 * off[q] + i] - x0[k + i];
        s += d * d;
      }
    double d = n > 0 ? sqrt(s / (double)n) : 0;
    if (d > m || !isfinite(d)) m = d;
  } while (bs_state_next(r) == 0);
  free(x0);
  return isfinite(m) ? m : 0;
}

/* The displacement scale of the reference folder dir over the compared blocks. */
static double reference_disp(const char *dir, int n_blocks, const int64_t *off, const int64_t *count) {
  bs_state_reader s;
  bs_error e;
  if (bs_state_open(dir, &s, &e)) return 0;
  double d = bs__study_disp_scale(&s, n_blocks, off, count);
  bs_state_close(&s);
  return d;
}

double bs__study_max_speed(const char *dir) {
  bs_state_reader s;
  bs_error e;
  if (bs_state_open(dir, &s, &e)) return 0;
  double m = 0;
  while (bs_state_next(&s) == 0)
    for (int32_t i = 0; i < s.n; i++) {
      const double *v = s.v + 3 * (size_t)i;
      double q = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      if (q > m) m = q;
    }
  bs_state_close(&s);
  return sqrt(m);
}

/* A given reference folder: the uniform refinement level (0..10, else the
 * first run's levels) that explains its vertex count; 0 when none does. */
static int given_levels(const bs_study *S, int *ref_refine, int64_t *off_ref) {
  bs_state_reader sf;
  bs_error e;
  int found = 0;
  if (bs_state_open(S->ref_dir, &sf, &e)) return 0;
  for (int lvl = 0; lvl <= 10 && !found; lvl++) {
    for (int b = 0; b < S->n_bodies; b++) ref_refine[b] = lvl;
    if (bs__study_offsets(S, ref_refine, off_ref) == sf.n) found = 1;
  }
  if (!found) {
    for (int b = 0; b < S->n_bodies; b++) ref_refine[b] = S->runs[0].body_refine[b];
    found = bs__study_offsets(S, ref_refine, off_ref) == sf.n;
  }
  bs_state_close(&sf);
  return found;
}

/* The compared blocks (per body, its vertex count at the coarsest level in
 * the study and in the reference), the reference's offsets, the velocity scale. */
static void reference_blocks(bs_study *S, int64_t *off_ref) {
  int ref_refine[BS_STUDY_MAX_BODIES];
  for (int b = 0; b < S->n_bodies; b++) {
    int mn = S->runs[0].body_refine[b];
    for (int i = 1; i < S->n_runs; i++)
      if (S->runs[i].body_refine[b] < mn) mn = S->runs[i].body_refine[b];
    ref_refine[b] = S->ref_dir[0] ? 0 : S->runs[S->ref].body_refine[b];
    S->cmp[b] = bs__study_body_vertices(S->counts[b], mn);
  }
  S->direct = 0;
  if (S->ref_dir[0]) {
    int found = given_levels(S, ref_refine, off_ref);
    if (!found) S->direct = 1; /* no refinement relation: same vertex count required */
    for (int b = 0; found && b < S->n_bodies; b++) {
      int64_t nv = bs__study_body_vertices(S->counts[b], ref_refine[b]);
      if (S->cmp[b] > nv) S->cmp[b] = nv;
    }
  }
  bs__study_offsets(S, ref_refine, off_ref);
  const char *ref_dir = S->ref_dir[0] ? S->ref_dir : S->runs[S->ref].dir;
  S->vscale = bs__study_max_speed(ref_dir);
  if (!(S->vscale > 0)) S->vscale = 1.0;
  int64_t zero = 0, all = 0;
  if (S->direct) {
    bs_state_reader sf;
    bs_error e;
    if (bs_state_open(ref_dir, &sf, &e) == 0) {
      all = sf.n;
      bs_state_close(&sf);
    }
    S->disp = reference_disp(ref_dir, 1, &zero, &all);
  } else {
    S->disp = reference_disp(ref_dir, S->n_bodies, off_ref, S->cmp);
  }
  S->xscale = S->disp > 1e-12 * S->size ? S->disp : S->size; /* nothing moved: the body size */
}

int bs__study_compare(bs_study *S) {
  int64_t off_ref[BS_STUDY_MAX_BODIES];
  reference_blocks(S, off_ref);
  const char *ref_dir = S->ref_dir[0] ? S->ref_dir : S->runs[S->ref].dir;
  if (!S->ref_dir[0] && (S->runs[S->ref].exit_code != 0 || S->runs[S->ref].timed_out)) {
    /* a failed or stopped reference: its frames are no reference */
    for (int i = 0; i < S->n_runs; i++) {
      bs_study_run *r = &S->runs[i];
      r->pos_max = r->pos_last = r->vel_max = r->vel_last = NAN;
    }
    return S->n_runs;
  }
  int n_bad = 0;
  for (int i = 0; i < S->n_runs; i++)
    if (bs__study_compare_run(S, &S->runs[i], ref_dir, off_ref)) n_bad++;
  return n_bad;
}
