/* sim_util.h — running a scene from a test through the library (bs_scene.h,
 * bs_sim.h) instead of `bigstep run`: load with overrides, create, run with a
 * callback that records per frame and per step what the tests assert on. */
#ifndef BS_TEST_SIM_UTIL_H
#define BS_TEST_SIM_UTIL_H

#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_minimize.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"

/* What a run recorded (frames >= 1 unless said otherwise). */
typedef struct sim_rec {
  int calls;               /* callback calls (frame 0 included)                        */
  int frames;              /* last frame number seen                                    */
  long steps, failed;      /* steps; steps whose reason is not BS_MIN_CONVERGED        */
  long failed_flag;        /* steps with st.failed set                                  */
  long newton;             /* Newton iterations summed over the steps                   */
  long from_xn;            /* steps whose guess was x^n (BS_GUESS_XN)                   */
  double max_grad;         /* largest final |grad E| of a step (NaN wins)               */
  int bad_reason;          /* a step whose reason is not a bs_min_reason / has no text  */
  char bad_reason_msg[256];
  int nonfinite;           /* a frame whose x, v or measures hold NaN/Inf               */
  char nonfinite_msg[256];
  int last_inverted, max_inverted, max_penetrating, first_clean;
  double last_min_detF, max_depth;
  char reason[256];        /* first failure's reason text, else the last step's         */
  bs_runfolder *folder;    /* not NULL: every frame is also written there               */
} sim_rec;

static inline int sim_finite(const double *a, size_t n, size_t *bad) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(a[i])) {
      *bad = i;
      return 0;
    }
  return 1;
}

/* The scene text parsed (name starts its messages) and its simulation
 * created, both asserted; *sc gets the scene (destroy it after the sim). */
static inline bs_sim *sim_from_text(const char *text, const char *name, bs_scene **sc) {
  bs_sim *s = NULL;
  bs_error err;
  bs_error_clear(&err);
  *sc = NULL;
  cr_assert_eq(bs_scene_parse(text, name, 0, NULL, sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(*sc, &s, &err), 0, "%s", err.msg);
  return s;
}

/* A bs_frame_fn recording into a sim_rec (ctx). */
static inline int sim_rec_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  sim_rec *r = ctx;
  if (r->folder) {
    int st = bs_runfolder_frame(s, fs, r->folder, err);
    if (st) return st;
  }
  r->calls++;
  size_t n3 = 3 * (size_t)s->mesh->n_vertices, bad = 0;
  bs_sim_measures m;
  bs_sim_measure(s, 0, &m);
  if (!r->nonfinite) {
    if (!sim_finite(s->x, n3, &bad))
      snprintf(r->nonfinite_msg, sizeof r->nonfinite_msg, "frame %d: x[%zu] = %g", fs->frame, bad, s->x[bad]);
    else if (!sim_finite(s->v, n3, &bad))
      snprintf(r->nonfinite_msg, sizeof r->nonfinite_msg, "frame %d: v[%zu] = %g", fs->frame, bad, s->v[bad]);
    else if (!isfinite(m.kinetic) || !isfinite(m.elastic) || !isfinite(m.gravity) || !isfinite(m.total) ||
             !isfinite(m.min_detF) || !isfinite(m.max_depth) || !isfinite(s->time))
      snprintf(r->nonfinite_msg, sizeof r->nonfinite_msg,
               "frame %d: measures not finite: kinetic %g elastic %g gravity %g min det F %g depth %g time %g",
               fs->frame, m.kinetic, m.elastic, m.gravity, m.min_detF, m.max_depth, s->time);
    r->nonfinite = r->nonfinite_msg[0] != '\0';
  }
  if (fs->frame == 0) return 0;
  for (int k = 0; k < fs->n_steps; k++) {
    const bs_step_stats *st = &fs->steps[k].st;
    const char *text = st->min.reason_text;
    int known = (int)st->min.reason >= BS_MIN_CONVERGED && (int)st->min.reason <= BS_MIN_FLOOR;
    /* each step keeps its own reason text (bs_sim_step.reason), which must
     * start with the name of that step's reason */
    if (known) {
      const char *name = bs_min_reason_name(st->min.reason);
      known = text && !strncmp(text, name, strlen(name)) && text[strlen(name)] == ':';
    }
    if (!known && !r->bad_reason)
      snprintf(r->bad_reason_msg, sizeof r->bad_reason_msg, "frame %d step %d: reason %d text '%s'", fs->frame, k,
               (int)st->min.reason, text ? text : "(null)");
    r->bad_reason |= !known;
    double g = st->min.grad_norm;
    if (g > r->max_grad || !isfinite(g)) r->max_grad = g;
    r->newton += st->min.iterations;
    r->failed_flag += st->failed != 0;
    r->from_xn += st->guess == BS_GUESS_XN;
    int conv = st->min.reason == BS_MIN_CONVERGED;
    if (!conv) r->failed++;
    if ((!conv && r->failed == 1) || r->failed == 0)
      snprintf(r->reason, sizeof r->reason, "%s", text ? text : bs_min_reason_name(st->min.reason));
    r->steps++;
  }
  r->frames = fs->frame;
  r->last_inverted = m.inverted;
  r->last_min_detF = m.min_detF;
  if (m.inverted > r->max_inverted) r->max_inverted = m.inverted;
  if (m.penetrating > r->max_penetrating) r->max_penetrating = m.penetrating;
  if (m.max_depth > r->max_depth) r->max_depth = m.max_depth;
  if (r->first_clean < 0 && m.inverted == 0) r->first_clean = fs->frame;
  return 0;
}

/* Splits a space-separated list of "key=value" overrides (no spaces inside a
 * value) into sets[] (pointers into buf). Returns how many. */
static inline int sim_split_sets(const char *list, char *buf, size_t n, const char **sets, int max) {
  int k = 0;
  snprintf(buf, n, "%s", list ? list : "");
  for (char *save = NULL, *t = strtok_r(buf, " ", &save); t && k < max; t = strtok_r(NULL, " ", &save)) sets[k++] = t;
  return k;
}

/* Loads scene with the overrides in `sets` (space-separated), asserting success. */
static inline bs_scene *sim_load(const char *scene, const char *sets) {
  char buf[4096];
  const char *v[64];
  int n = sim_split_sets(sets, buf, sizeof buf, v, 64);
  bs_scene *sc = NULL;
  bs_error err;
  bs_error_clear(&err);
  int st = bs_scene_load(scene, n, v, &sc, &err);
  cr_assert_eq(st, 0, "%s [%s]: %s", scene, sets ? sets : "", err.msg);
  return sc;
}

/* Loads, creates and runs a scene (no output folder unless dir is not NULL),
 * asserting that load, create and run succeed; *rec receives the record and
 * *T the totals. Returns the simulation (and *out_sc its scene) when keep,
 * else destroys both and returns NULL. */
static inline bs_sim *sim_run_scene(const char *scene, const char *sets, const char *dir, sim_rec *rec,
                                    bs_run_totals *T, int keep, bs_scene **out_sc) {
  memset(rec, 0, sizeof *rec);
  rec->first_clean = -1;
  bs_scene *sc = sim_load(scene, sets);
  bs_sim *s = NULL;
  bs_error err;
  bs_error_clear(&err);
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s [%s]: %s", scene, sets ? sets : "", err.msg);
  const bs_runfolder_opts fo = {.replace = 1};
  if (dir) cr_assert_eq(bs_runfolder_open(dir, s, &fo, &rec->folder, &err), 0, "%s", err.msg);
  int st = bs_sim_run(s, sim_rec_frame, rec, T, &err);
  cr_assert_eq(st, 0, "%s [%s]: bs_sim_run %d: %s", scene, sets ? sets : "", st, err.msg);
  if (rec->folder) {
    char summary[2048];
    bs_summary u;
    bs_summary_make(s, T, 0.0, &u);
    bs_summary_format(&u, summary, sizeof summary);
    cr_assert_eq(bs_runfolder_finish(rec->folder, summary, &err), 0, "%s", err.msg);
    bs_runfolder_destroy(&rec->folder);
  }
  cr_assert_eq(rec->calls, (sc->mode == BS_MODE_STATIC ? 1 : sc->frames) + 1, "%s: %d callbacks", scene, rec->calls);
  if (keep) {
    *out_sc = sc;
    return s;
  }
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return NULL;
}

/* The scene's error: loading (then creating) with the overrides must fail;
 * returns the status and the message in *err. */
static inline int sim_load_error(const char *scene, const char *const *sets, int n_sets, bs_error *err) {
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_error_clear(err);
  int st = bs_scene_load(scene, n_sets, sets, &sc, err);
  if (!st) {
    st = bs_sim_create(sc, &s, err);
    bs_sim_destroy(&s);
  }
  bs_scene_destroy(&sc);
  return st;
}

#endif
