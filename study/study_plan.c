/* study_plan.c — a study's plan: the scene, the user's settings and the
 * knobs; the cross product of the knobs' values into runs (names, folders,
 * --set lists, each validated through the scene loader) and the reference
 * (bs_study.h). */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"

static char *xstrdup(const char *s) {
  size_t n = strlen(s) + 1;
  char *d = malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

static char *xprintf(const char *fmt, const char *a, const char *b) {
  size_t n = strlen(fmt) + strlen(a) + strlen(b) + 1;
  char *s = malloc(n);
  if (s) snprintf(s, n, fmt, a, b);
  return s;
}

static int knob_copy(const bs_study_knob *src, bs_study_knob *dst) {
  *dst = *src;
  dst->vals = calloc((size_t)src->n + 1, sizeof(char *));
  dst->num = malloc(sizeof(double) * ((size_t)src->n + 1));
  if (!dst->vals || !dst->num) return -1;
  for (int j = 0; j < src->n; j++) {
    if (!(dst->vals[j] = xstrdup(src->vals[j]))) return -1;
    dst->num[j] = src->num[j];
  }
  return 0;
}

/* The study's name (the scene file's, without folder and extension) and folder. */
static void study_names(bs_study *S, const char *out) {
  const char *base = strrchr(S->scene_path, '/');
  base = base ? base + 1 : S->scene_path;
  snprintf(S->name, sizeof S->name, "%s", base);
  char *dot = strrchr(S->name, '.');
  if (dot && dot != S->name) *dot = 0;
  if (out) snprintf(S->out, sizeof S->out, "%s", out);
  else snprintf(S->out, sizeof S->out, "out/study/%s", S->name);
}

/* The quantities: the scene's own when none is given (and scene_qoi), and
 * the scene's kind of each name (-1: not the scene's). */
static void scene_quantities(bs_study *S, const bs_scene *sc, int scene_qoi) {
  for (int q = 0; scene_qoi && S->n_qoi == 0 && q < sc->n_qoi && q < BS_STUDY_MAX_QOI; q++)
    snprintf(S->qoi[q], BS_MAX_NAME, "%s", sc->qoi[q].name);
  if (scene_qoi && S->n_qoi == 0) S->n_qoi = sc->n_qoi < BS_STUDY_MAX_QOI ? sc->n_qoi : BS_STUDY_MAX_QOI;
  for (int q = 0; q < S->n_qoi; q++) {
    S->q_kind[q] = -1;
    for (int j = 0; j < sc->n_qoi; j++)
      if (!strcmp(sc->qoi[j].name, S->qoi[q])) S->q_kind[q] = (int)sc->qoi[j].kind;
  }
}

/* The scene with the user's settings: its body count and quantities. */
static int base_scene(bs_study *S, int scene_qoi, bs_error *err) {
  bs_scene *sc = NULL;
  int st = bs_scene_load(S->scene_path, S->n_user, (const char *const *)S->user_sets, &sc, err);
  if (st) return st;
  S->n_bodies = sc->n_bodies;
  scene_quantities(S, sc, scene_qoi);
  bs_scene_destroy(&sc);
  if (S->n_bodies > BS_STUDY_MAX_BODIES)
    return bs_error_set(err, BS_EINPUT, "%s: at most %d bodies, got %d", S->scene_path, BS_STUDY_MAX_BODIES,
                        S->n_bodies);
  return 0;
}

int bs_study_create(const bs_study_opts *o, bs_study **out, bs_error *err) {
  *out = NULL;
  if (o->n_knobs < 0 || o->n_knobs > BS_STUDY_MAX_KNOBS)
    return bs_error_set(err, BS_EINPUT, "at most %d knobs, got %d", BS_STUDY_MAX_KNOBS, o->n_knobs);
  bs_study *S = calloc(1, sizeof *S);
  if (!S) return bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  S->ref = -1;
  int st = 0;
  const char *const paths[3] = {o->scene, o->reference, o->out};
  static const char *const what[3] = {"scene", "reference folder", "study folder"};
  for (int i = 0; i < 3 && !st; i++)
    if (paths[i] && strlen(paths[i]) >= BS_MAX_PATH)
      st = bs_error_set(err, BS_EINPUT, "%s '%.80s...': longer than %d bytes", what[i], paths[i], BS_MAX_PATH - 1);
  if (st) {
    free(S);
    return st;
  }
  snprintf(S->scene_path, sizeof S->scene_path, "%s", o->scene);
  if (o->reference) snprintf(S->ref_dir, sizeof S->ref_dir, "%s", o->reference);
  study_names(S, o->out);
  S->user_sets = calloc((size_t)o->n_sets + 1, sizeof(char *));
  if (!S->user_sets) st = bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  for (int i = 0; !st && i < o->n_sets; i++)
    if (!(S->user_sets[S->n_user++] = xstrdup(o->sets[i]))) st = bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  for (int k = 0; !st && k < o->n_knobs; k++)
    if (knob_copy(&o->knobs[k], &S->knobs[S->n_knobs++])) st = bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  if (!st && (o->n_qoi < 0 || o->n_qoi > BS_STUDY_MAX_QOI))
    st = bs_error_set(err, BS_EINPUT, "at most %d quantities (--qoi), got %d", BS_STUDY_MAX_QOI, o->n_qoi);
  for (int q = 0; !st && q < o->n_qoi; q++) {
    if (strlen(o->qoi[q]) >= BS_MAX_NAME || !o->qoi[q][0])
      st = bs_error_set(err, BS_EINPUT, "--qoi '%s': not a quantity name", o->qoi[q]);
    for (int j = 0; !st && j < q; j++)
      if (!strcmp(o->qoi[j], o->qoi[q])) st = bs_error_set(err, BS_EINPUT, "--qoi '%s' is given twice", o->qoi[q]);
    if (!st) snprintf(S->qoi[S->n_qoi++], BS_MAX_NAME, "%s", o->qoi[q]);
  }
  if (!st) st = base_scene(S, o->n_qoi == 0 && !o->no_scene_qoi, err);
  if (st) {
    bs_study_destroy(&S);
    return st;
  }
  *out = S;
  return 0;
}

void bs_study_destroy(bs_study **Sp) {
  bs_study *S = Sp ? *Sp : NULL;
  if (!S) return;
  for (int k = 0; k < S->n_knobs; k++) bs_study_knob_free(&S->knobs[k]);
  for (int i = 0; S->runs && i < S->n_runs; i++) {
    for (int j = 0; S->runs[i].sets && j < S->runs[i].n_sets; j++) free(S->runs[i].sets[j]);
    free(S->runs[i].sets);
    free(S->runs[i].body_refine);
  }
  for (int i = 0; i < S->n_user; i++) free(S->user_sets[i]);
  free(S->user_sets);
  free(S->runs);
  free(S->counts);
  free(S);
  *Sp = NULL;
}

int bs_study_check_bodies(const bs_study *S, bs_error *err) {
  for (int k = 0; k < S->n_knobs; k++)
    if (S->knobs[k].kind == BS_KNOB_REFINE && S->knobs[k].body >= S->n_bodies)
      return bs_error_set(err, BS_EINPUT, "'%s': the scene has %d bodies", S->knobs[k].key, S->n_bodies);
  return 0;
}

static void sanitize(const char *in, char *out, size_t n) {
  size_t k = 0;
  for (const char *p = in; *p && k + 1 < n; p++)
    out[k++] = (isalnum((unsigned char)*p) || strchr("._+-", *p)) ? *p : '_';
  out[k] = 0;
}

static void add_set(bs_study_run *r, char *s, int *oom) {
  if (!s) *oom = 1;
  r->sets[r->n_sets++] = s;
}

/* Run r's name from its knobs' values, and its folder OUT/name. */
static int run_name(const bs_study *S, bs_study_run *r, bs_error *err) {
  size_t len = 0;
  for (int k = 0; k < S->n_knobs; k++) {
    char sv[128];
    sanitize(S->knobs[k].vals[r->idx[k]], sv, sizeof sv);
    int n = snprintf(r->name + len, sizeof r->name - len, "%s%s=%s", k ? "," : "", S->knobs[k].key, sv);
    if (n < 0 || (size_t)n >= sizeof r->name - len)
      return bs_error_set(err, BS_EINPUT, "run '%.100s...': the name is longer than %d bytes", r->name,
                          BS_STUDY_NAME_LEN - 1);
    len += (size_t)n;
  }
  int n = snprintf(r->dir, sizeof r->dir, "%s/%s", S->out, r->name);
  if (n < 0 || (size_t)n >= sizeof r->dir)
    return bs_error_set(err, BS_EINPUT, "run %.200s: its folder of %d bytes is longer than %d bytes: '%.100s.../%s'",
                        r->name, n, BS_MAX_PATH - 1, S->out, r->name);
  return 0;
}

/* The --set list of run r: study defaults, the user's, the knobs' values, the
 * outputs (its name and folder made first). */
static int build_sets(const bs_study *S, bs_study_run *r, bs_error *err) {
  int st = run_name(S, r, err);
  if (st) return st;
  int cap = 8 + S->n_user + S->n_knobs * (S->n_bodies + 1), oom = 0;
  if (!(r->sets = calloc((size_t)cap, sizeof(char *)))) return bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  add_set(r, xstrdup("output.vtu_every=0"), &oom);
  add_set(r, xstrdup("output.checkpoint_every=0"), &oom); /* a study's runs are measured, never resumed */
  for (int i = 0; i < S->n_user; i++) add_set(r, xstrdup(S->user_sets[i]), &oom);
  for (int k = 0; k < S->n_knobs; k++) {
    const bs_study_knob *v = &S->knobs[k];
    const char *val = v->vals[r->idx[k]];
    const char *every = v->kind == BS_KNOB_REFINE && v->body < 0       ? "refine"
                        : !strncmp(v->path, "bodies.*.", strlen("bodies.*.")) ? v->path + strlen("bodies.*.")
                                                                              : NULL;
    if (every) { /* a shorthand of every body: bodies.B.KEY for each body B */
      for (int b = 0; b < S->n_bodies; b++) {
        char buf[300];
        snprintf(buf, sizeof buf, "bodies.%d.%s=", b, every);
        add_set(r, xprintf("%s%s", buf, val), &oom);
      }
    } else {
      add_set(r, xprintf("%s=%s", v->path, val), &oom);
    }
  }
  add_set(r, xprintf("output.dir=%s%s", r->dir, ""), &oom);
  add_set(r, xstrdup("output.states=true"), &oom);
  add_set(r, xstrdup("output.stats=true"), &oom);
  return oom ? bs_error_set(err, BS_ENOMEM, "out of memory (study)") : 0;
}

/* Run r's scene: validated, and what the study needs of it. */
static int run_scene(const bs_study *S, bs_study_run *r, int any_refine, bs_error *err) {
  bs_scene *sc = NULL;
  if (bs_scene_load(S->scene_path, r->n_sets, (const char *const *)r->sets, &sc, err)) {
    bs_error_prefix(err, "run %s", r->name);
    return BS_EINPUT;
  }
  r->frames = sc->frames;
  r->spf = sc->steps_per_frame;
  r->fps = sc->fps;
  r->is_static = sc->mode == BS_MODE_STATIC;
  snprintf(r->method, sizeof r->method, "%s", bs_method_name(sc->solver.method));
  int st = 0;
  if (!(r->body_refine = calloc((size_t)S->n_bodies + 1, sizeof(int))))
    st = bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  for (int b = 0; !st && b < S->n_bodies; b++) {
    r->body_refine[b] = sc->bodies[b].refine;
    if (any_refine && sc->bodies[b].reorder != BS_ORDER_NONE)
      st = bs_error_set(err, BS_EINPUT, "bodies.%d.reorder must be none when refine is varied (runs are compared "
                                        "through the vertices refinement keeps)", b);
  }
  bs_scene_destroy(&sc);
  return st;
}

int bs_study_plan(bs_study *S, bs_error *err) {
  int st = bs_study_check_bodies(S, err);
  if (st) return st;
  if (S->n_knobs == 0) return bs_error_set(err, BS_EINPUT, "nothing to vary");
  int n = 1, any_refine = 0;
  for (int k = 0; k < S->n_knobs; k++) {
    if (n > BS_STUDY_MAX_RUNS / S->knobs[k].n)
      return bs_error_set(err, BS_EINPUT, "too many runs (more than %d)", BS_STUDY_MAX_RUNS);
    n *= S->knobs[k].n;
    any_refine |= S->knobs[k].kind == BS_KNOB_REFINE;
  }
  if (!(S->runs = calloc((size_t)n, sizeof(bs_study_run)))) return bs_error_set(err, BS_ENOMEM, "out of memory (study)");
  S->n_runs = n;
  for (int i = 0; !st && i < S->n_runs; i++) {
    bs_study_run *r = &S->runs[i];
    int q = i, fin = 1;
    for (int k = S->n_knobs - 1; k >= 0; k--) {
      r->idx[k] = q % S->knobs[k].n;
      q /= S->knobs[k].n;
      fin &= r->idx[k] == S->knobs[k].finest;
    }
    st = build_sets(S, r, err);
    if (!st) st = run_scene(S, r, any_refine, err);
    if (!st && fin && !S->ref_dir[0]) {
      r->is_ref = 1;
      S->ref = i;
    }
  }
  return st;
}

int bs__study_run_rows(const bs_study_run *r) { return r->is_static ? 2 : r->frames + 1; }

int bs_study_run_complete(const bs_study_run *r) { return bs_frames_csv_lines(r->dir) == bs__study_run_rows(r) + 1; }
