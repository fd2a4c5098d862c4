/* bench/integrators_vibration.c — free vibration of the cantilever of
 * data/scenes/beam_sag.json under the time integrators (bs_step.h:
 * backward Euler, BDF2, Newmark): the beam's static deflection under gravity,
 * then gravity switched off and the beam released from it at rest; per
 * integrator and rate (steps per second) the period of the motion's
 * coordinate along the static deflection (coordinate(): upward zero
 * crossings, linearly interpolated, over the whole run; the slope of their
 * times against their index)
 * and the amplitude decay per period (from the mechanical energy, kinetic
 * plus elastic, between the end of the second period and the end of the run:
 * 1 - (E_b / E_a)^(T / (2 (t_b - t_a))); after two periods the higher
 * modes that the release also excites are gone under backward Euler and
 * BDF2), with the observed orders in dt between successive rates. The
 * period error is against Newmark at REF steps per second (the semi-discrete
 * period of this mesh); Euler-Bernoulli's is printed beside it.
 *
 *   bench_integrators_vibration [SCENE] [SECONDS] [OUT] [REF] [key.path=value]...
 *
 * (defaults data/scenes/beam_sag.json, 4, bench/results/integrators-vibration.txt,
 * 1536). Accuracy figures only: nothing is timed. Never run by the tests. */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_scene.h"
#include "bs_sim.h"

#define N_RATES 4
static const int rates[N_RATES] = {24, 48, 96, 192};
static const char *const names[3] = {"backward_euler", "bdf2", "newmark"};

typedef struct result {
  double period;   /* s; NAN when fewer than 3 upward crossings */
  double decay;    /* amplitude lost per period (fraction); NAN when not measurable */
  int crossings;
  int failed;      /* steps that did not converge (at the tolerance's rounding floor) */
} result;

/* The displacement's coordinate along the static deflection d = xs - x0,
 * mass-weighted: q = sum m (x - x0).d / sum m d.d (1 at the release). Of the
 * modes that the release excites, q holds each as the square of its share of
 * d, so the second bending mode, which moves the tip by a few percent of the
 * first, enters q at about 1e-3 of it. */
static double coordinate(const bs_sim *s, const double *xs) {
  double num = 0, den = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    for (int k = 0; k < 3; k++) {
      const size_t i = 3 * (size_t)v + k;
      const double d = xs[i] - s->x0[i];
      num += s->fem->mass[v] * (s->x[i] - s->x0[i]) * d, den += s->fem->mass[v] * d * d;
    }
  return num / den;
}

/* Kinetic plus elastic energy (J) of the state. */
static double energy(const bs_sim *s) {
  double E = 0, e;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++)
    for (int k = 0; k < 3; k++) E += 0.5 * s->fem->mass[v] * s->v[3 * (size_t)v + k] * s->v[3 * (size_t)v + k];
  for (int i = 0; i < s->n_terms; i++)
    if (s->terms[i]->kind == BS_TERM_ELASTICITY && s->terms[i]->ops->value(s->terms[i], s->x, &e) == BS_TERM_OK) E += e;
  return E;
}

/* The command line's key.path=value settings, applied after each run's own. */
#define MAX_SETS 16
static const char *extra[MAX_SETS];
static int n_extra;

static int load(const char *path, int n, const char *const *sets, bs_scene **sc, bs_sim **s, bs_error *err) {
  const char *all[MAX_SETS + 8];
  for (int i = 0; i < n; i++) all[i] = sets[i];
  for (int i = 0; i < n_extra; i++) all[n + i] = extra[i];
  int rc = bs_scene_load(path, n + n_extra, all, sc, err);
  return rc ? rc : bs_sim_create(*sc, s, err);
}

/* The static deflection (3n doubles, malloc'ed) into *xs. */
static int static_deflection(const char *path, double **xs, bs_error *err) {
  const char *sets[] = {"solver.mode=static", "solver.tolerance=1e-8"};
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_frame_stats fs;
  int rc = load(path, 2, sets, &sc, &s, err);
  if (!rc) rc = bs_sim_statics(s, &fs, err);
  if (!rc) {
    const size_t n = 3 * (size_t)s->mesh->n_vertices * sizeof(double);
    *xs = malloc(n);
    memcpy(*xs, s->x, n);
  }
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return rc;
}

/* Period and decay from the coordinate's samples u[0..n] and energies E[0..n] at dt.
 * The period is the slope of the crossing times against their index (least
 * squares), which averages out what the higher modes add to each crossing. */
static void analyse(const double *u, const double *E, int n, double dt, result *r) {
  double s1 = 0, sk = 0, st = 0, skk = 0, skt = 0;
  r->crossings = 0;
  for (int k = 0; k < n; k++) {
    if (E[k + 1] < 1e-10 * E[0]) break; /* damped out: crossings of noise */
    if (u[k] < 0 && u[k + 1] >= 0) {
      const double t = (k + u[k] / (u[k] - u[k + 1])) * dt, i = r->crossings++;
      s1 += 1, sk += i, st += t, skk += i * i, skt += i * t;
    }
  }
  r->period = r->crossings >= 3 ? (s1 * skt - sk * st) / (s1 * skk - sk * sk) : NAN;
  r->decay = NAN;
  if (!isfinite(r->period)) return;
  const int a = (int)ceil(2 * r->period / dt);
  int b = n;
  while (b > a && E[b] < 1e-10 * E[0]) b--;
  if (b - a < 2 || !(E[a] > 0)) return;
  r->decay = 1 - pow(E[b] / E[a], r->period / (2 * (b - a) * dt));
}

static int run(const char *path, const double *xs, const char *integ, int rate, double seconds, result *r,
               bs_error *err) {
  char s_int[64], s_fps[64], s_frames[64];
  snprintf(s_int, sizeof s_int, "solver.integrator=%s", integ);
  snprintf(s_fps, sizeof s_fps, "time.fps=%d", rate);
  snprintf(s_frames, sizeof s_frames, "time.frames=%d", (int)lround(seconds * rate));
  const char *sets[] = {"solver.mode=dynamic", "solver.tolerance=1e-8", "gravity.1=0", "time.steps_per_frame=1",
                        s_int, s_fps, s_frames};
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  memset(r, 0, sizeof *r);
  int rc = load(path, 7, sets, &sc, &s, err);
  const int n = (int)lround(seconds * rate);
  double *u = calloc((size_t)n + 1, sizeof(double)), *E = calloc((size_t)n + 1, sizeof(double));
  const size_t n3 = s ? 3 * (size_t)s->mesh->n_vertices : 0;
  double *v0 = calloc(n3 + 1, sizeof(double));
  if (!rc) rc = bs_sim_restore(s, 0, xs, v0, err);
  if (!rc) u[0] = coordinate(s, xs), E[0] = energy(s);
  bs_frame_stats fs;
  for (int k = 1; k <= n && !rc; k++) {
    rc = bs_sim_advance_frame(s, &fs, err);
    u[k] = coordinate(s, xs), E[k] = energy(s);
    r->failed += !rc && fs.failed;
  }
  if (!rc) analyse(u, E, n, 1.0 / rate, r);
  const char *dump = getenv("BS_BENCH_DUMP"); /* a folder: the samples of every run, one file each */
  if (!rc && dump) {
    char p[512];
    snprintf(p, sizeof p, "%s/%s_%d.csv", dump, integ, rate);
    FILE *f = fopen(p, "w");
    for (int k = 0; f && k <= n; k++) fprintf(f, "%.9g,%.12g,%.12g\n", (double)k / rate, u[k], E[k]);
    if (f) fclose(f);
  }
  free(u), free(E), free(v0);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return rc;
}

/* Euler-Bernoulli's first period of a clamped-free beam of the scene's box
 * (length along x, square section h) and material: 2 pi / (1.8751^2
 * sqrt(E I / (rho A L^4))). */
static double euler_bernoulli(const char *path) {
  bs_scene *sc = NULL;
  bs_error err;
  if (bs_scene_load(path, 0, NULL, &sc, &err)) return NAN;
  const bs_scene_body *b = &sc->bodies[0];
  const double L = b->box_size[0], h = b->box_size[1], w = b->box_size[2];
  const bs_scene_material *m = &b->materials[0];
  const double I = w * h * h * h / 12, A = w * h, bl = 1.875104068711961;
  const double T = 2 * M_PI / (bl * bl * sqrt(m->youngs * I / (m->density * A * L * L * L * L)));
  bs_scene_destroy(&sc);
  return T;
}

static void print_order(FILE *f, double a, double b) {
  if (isfinite(a) && isfinite(b) && a > 0 && b > 0) fprintf(f, " %7.2f", log2(a / b));
  else fprintf(f, " %7s", "-");
}

int main(int argc, char **argv) {
  const char *path = argc > 1 ? argv[1] : "data/scenes/beam_sag.json";
  const double seconds = argc > 2 ? atof(argv[2]) : 4.0;
  const char *out = argc > 3 ? argv[3] : "bench/results/integrators-vibration.txt";
  const int ref_rate = argc > 4 ? atoi(argv[4]) : 1536;
  for (int i = 5; i < argc && n_extra < MAX_SETS; i++) extra[n_extra++] = argv[i];
  bs_error err;
  double *xs = NULL;
  if (static_deflection(path, &xs, &err)) {
    fprintf(stderr, "bench_integrators_vibration: %s\n", err.msg);
    return 1;
  }
  result ref, r[3][N_RATES];
  if (run(path, xs, "newmark", ref_rate, seconds, &ref, &err)) {
    fprintf(stderr, "bench_integrators_vibration: %s\n", err.msg);
    return 1;
  }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < N_RATES; j++)
      if (run(path, xs, names[i], rates[j], seconds, &r[i][j], &err)) {
        fprintf(stderr, "bench_integrators_vibration: %s %d: %s\n", names[i], rates[j], err.msg);
        return 1;
      }
  FILE *f = fopen(out, "w");
  if (!f) {
    fprintf(stderr, "bench_integrators_vibration: cannot write '%s'\n", out);
    return 1;
  }
  for (int pass = 0; pass < 2; pass++) {
    FILE *o = pass ? stdout : f;
    fprintf(o, "Free vibration of %s (gravity off, released at rest from the static deflection),\n", path);
    for (int i = 0; i < n_extra; i++) fprintf(o, "with %s%s", extra[i], i + 1 < n_extra ? ", " : ",\n");
    fprintf(o, "%.3g s per run; solver.tolerance 1e-8. Reference period: newmark at %d steps/s, T_ref = %.6f s\n",
            seconds, ref_rate, ref.period);
    fprintf(o, "(Euler-Bernoulli: %.6f s; the mesh's stiffer). Period error = T / T_ref - 1; decay = amplitude lost\n",
            euler_bernoulli(path));
    fprintf(o, "per period (energy from the end of period 2 on); order = log2(e(dt) / e(dt/2)) from the rate before;\n");
    fprintf(o, "zeros: upward zero crossings of the coordinate along the static deflection; unconv: steps that stopped at the rounding floor\n");
    fprintf(o, "of E before the tolerance (reference: %d).\n\n", ref.failed);
    fprintf(o, "%-15s %7s %9s %12s %7s %12s %7s %5s %6s\n", "integrator", "steps/s", "steps/T", "period err", "order",
            "decay/T", "order", "zeros", "unconv");
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < N_RATES; j++) {
        const double pe = r[i][j].period / ref.period - 1;
        fprintf(o, "%-15s %7d %9.2f %12.4e", names[i], rates[j], ref.period * rates[j], pe);
        if (j) print_order(o, fabs(r[i][j - 1].period / ref.period - 1), fabs(pe));
        else fprintf(o, " %7s", "");
        fprintf(o, " %12.4e", r[i][j].decay);
        if (j) print_order(o, fabs(r[i][j - 1].decay), fabs(r[i][j].decay));
        else fprintf(o, " %7s", "");
        fprintf(o, " %5d %6d\n", r[i][j].crossings, r[i][j].failed);
      }
  }
  fclose(f);
  free(xs);
  return 0;
}
