/* The time integrators (bs_step.h: backward Euler, BDF2, Newmark average
 * acceleration) on a linear oscillator, a single mass on a zero-length
 * spring (the free vertex of one tet, the other three fixed; inertia and a
 * custom spring term, no elasticity), against its exact solution: backward
 * Euler converges with order 1, BDF2 and Newmark with order 2; Newmark keeps
 * the energy of the linear problem over 100 periods; a step's history
 * restored into a fresh integrator continues bit for bit; `bigstep run`
 * stopped by SIGINT and resumed with bdf2 and newmark (and backward Euler
 * from a checkpoint of version 3) ends with the run's state.bin and
 * frames.csv; an unknown integrator is refused by key. */
#define _GNU_SOURCE
#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bs_fem.h"
#include "bs_runfolder.h"
#include "bs_step.h"
#include "bs_terms.h"
#include "cli_util.h"

/* ---- the oscillator ------------------------------------------------------ */

#define FREE 3 /* the free vertex */

typedef struct spring {
  double k, rest[3];
} spring;

static int spring_value(const bs_term *t, const double *x, double *E) {
  const spring *s = t->data;
  double e = 0;
  for (int c = 0; c < 3; c++) e += 0.5 * s->k * (x[3 * FREE + c] - s->rest[c]) * (x[3 * FREE + c] - s->rest[c]);
  *E = e;
  return BS_TERM_OK;
}

static int spring_gradient(const bs_term *t, const double *x, double *E, double *g) {
  const spring *s = t->data;
  spring_value(t, x, E);
  for (int c = 0; c < 3; c++) g[3 * FREE + c] += s->k * (x[3 * FREE + c] - s->rest[c]);
  return BS_TERM_OK;
}

static int spring_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  (void)x;
  const spring *s = t->data;
  double *B = H->val + 9 * (size_t)H->diag[FREE];
  for (int c = 0; c < 3; c++) B[4 * c] += s->k;
  return BS_TERM_OK;
}

static const bs_term_ops spring_ops = {spring_value, spring_gradient, spring_hessian, NULL, free, NULL, NULL, NULL,
                                       NULL, NULL};

typedef struct osc {
  bs_mesh *mesh;
  bs_fem *fem;
  bs_material mat;
  bs_step_data step;
  bs_term *terms[2];
  bs_integrator *I;
  double m, k, omega;
  double x[12], v[12];
} osc;

/* A = the initial displacement (x), V0 the initial velocity (y); omega = 2 pi. */
#define A0 0.01
#define V0 0.02

static void osc_integrator(osc *o, int integrator) {
  bs_error err;
  bs_integrator_opts op;
  bs_integrator_opts_default(&op);
  op.min.tol = 1e-11;
  op.integrator = integrator;
  const uint8_t mask[4] = {0, 0, 0, 1};
  bs_integrator_destroy(&o->I);
  cr_assert_eq(bs_integrator_create(o->fem, &o->step, 2, o->terms, mask, NULL, NULL, &op, &o->I, &err), 0, "%s",
               err.msg);
}

static void osc_create(osc *o, int integrator) {
  memset(o, 0, sizeof *o);
  bs_error err;
  const double X[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const int32_t tet[4] = {0, 1, 2, 3};
  cr_assert_eq(bs_mesh_create(4, X, 1, tet, 0, NULL, &o->mesh, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_material_init(BS_MODEL_LINEAR, 1e3, 0.3, 1000, &o->mat, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_fem_create(o->mesh, 1, &o->mat, NULL, &o->fem, &err), 0, "%s", err.msg);
  o->m = o->fem->mass[FREE];
  o->omega = 2 * M_PI;
  o->k = o->m * o->omega * o->omega;
  spring *s = malloc(sizeof *s);
  s->k = o->k;
  memcpy(s->rest, o->mesh->x + 3 * FREE, sizeof s->rest);
  cr_assert_eq(bs_term_inertia_create(o->fem, &o->step, &o->terms[0], &err), 0, "%s", err.msg);
  cr_assert_eq(bs_term_create("spring", &spring_ops, o->fem, &o->step, s, &o->terms[1], &err), 0, "%s", err.msg);
  o->terms[1]->quadratic = 1;
  osc_integrator(o, integrator);
  memcpy(o->x, o->mesh->x, sizeof o->x);
  memset(o->v, 0, sizeof o->v);
  o->x[3 * FREE] += A0;
  o->v[3 * FREE + 1] = V0;
}

static void osc_destroy(osc *o) {
  bs_integrator_destroy(&o->I);
  bs_term_destroy(&o->terms[0]);
  bs_term_destroy(&o->terms[1]);
  bs_fem_destroy(&o->fem);
  bs_mesh_destroy(&o->mesh);
}

static void osc_steps(osc *o, double *t, double dt, int n) {
  bs_step_stats st;
  bs_error err;
  for (int i = 0; i < n; i++) {
    cr_assert_eq(bs_integrator_step(o->I, *t, dt, o->x, o->v, &st, &err), 0, "%s", err.msg);
    cr_assert_eq(st.failed, 0, "step %d: %s", i, st.min.reason_text ? st.min.reason_text : "");
    *t += dt;
  }
}

/* The error at t = 1 s (one period) with n steps: |x - x_exact| and
 * |v - v_exact| / omega of the free vertex, combined. */
static double osc_error(int integrator, int n) {
  osc o;
  osc_create(&o, integrator);
  double t = 0;
  const double dt = 1.0 / n;
  osc_steps(&o, &t, dt, n);
  const double w = o.omega, T = 1.0, *X = o.mesh->x + 3 * FREE;
  const double xe[3] = {A0 * cos(w * T), V0 / w * sin(w * T), 0}, ve[3] = {-A0 * w * sin(w * T), V0 * cos(w * T), 0};
  double e = 0;
  for (int c = 0; c < 3; c++) {
    const double dx = o.x[3 * FREE + c] - X[c] - xe[c], dv = (o.v[3 * FREE + c] - ve[c]) / w;
    e += dx * dx + dv * dv;
  }
  osc_destroy(&o);
  return sqrt(e);
}

/* The observed orders log2(e(dt) / e(dt/2)) at 80, 160, 320, 640 steps per
 * period (backward Euler leaves its pre-asymptotic range, order 0.68 from 20
 * to 40, slowly). */
static void observed_orders(int integrator, double lo, double hi) {
  const int n[4] = {80, 160, 320, 640};
  double e[4];
  for (int i = 0; i < 4; i++) e[i] = osc_error(integrator, n[i]);
  for (int i = 0; i < 3; i++) {
    const double p = log2(e[i] / e[i + 1]);
    cr_log_info("%s: %d -> %d steps/period: error %.3e -> %.3e, order %.3f",
                bs_time_integrator_name((bs_time_integrator)integrator), n[i], n[i + 1], e[i], e[i + 1], p);
    cr_expect(p >= lo && p <= hi, "%s: observed order %.3f between %d and %d steps per period (errors %.3e, %.3e)",
              bs_time_integrator_name((bs_time_integrator)integrator), p, n[i], n[i + 1], e[i], e[i + 1]);
  }
}

Test(integrators, backward_euler_is_first_order) { observed_orders(BS_INTEGRATOR_BACKWARD_EULER, 0.85, 1.15); }
Test(integrators, bdf2_is_second_order) { observed_orders(BS_INTEGRATOR_BDF2, 1.85, 2.15); }
Test(integrators, newmark_is_second_order) { observed_orders(BS_INTEGRATOR_NEWMARK, 1.85, 2.15); }

/* The trapezoidal rule keeps 1/2 m v^2 + 1/2 k |x - X|^2 of a linear problem. */
Test(integrators, newmark_keeps_the_energy_of_a_linear_oscillator) {
  osc o;
  osc_create(&o, BS_INTEGRATOR_NEWMARK);
  const int per = 20, periods = 100;
  const double dt = 1.0 / per, *X = o.mesh->x + 3 * FREE;
  double t = 0, E0 = 0, drift = 0;
  for (int s = 0; s <= per * periods; s++) {
    double E = 0;
    for (int c = 0; c < 3; c++) {
      const double u = o.x[3 * FREE + c] - X[c], vc = o.v[3 * FREE + c];
      E += 0.5 * o.m * vc * vc + 0.5 * o.k * u * u;
    }
    if (s == 0) E0 = E;
    drift = fmax(drift, fabs(E - E0) / E0);
    if (s < per * periods) osc_steps(&o, &t, dt, 1);
  }
  cr_log_info("newmark: largest relative energy change over %d periods: %.3e", periods, drift);
  cr_expect(drift < 1e-8, "relative energy drift %.3e over %d periods", drift, periods);
  osc_destroy(&o);
}

/* Backward Euler loses energy on the same oscillator (the comparison). */
Test(integrators, backward_euler_damps_the_oscillator) {
  osc o;
  osc_create(&o, BS_INTEGRATOR_BACKWARD_EULER);
  double t = 0;
  osc_steps(&o, &t, 1.0 / 20, 20);
  const double u = o.x[3 * FREE] - o.mesh->x[3 * FREE];
  cr_expect(fabs(u) < 0.5 * A0, "after one period of 20 steps the amplitude is %.3e of %.3e", u, A0);
  osc_destroy(&o);
}

/* The history (with the state, the carry) put into a fresh integrator: the
 * steps after it are the ones the first integrator makes, bit for bit; a
 * state that is not the one the history belongs to restarts (BDF2: a
 * backward Euler step). */
static void history_restores(int integrator) {
  osc a, b;
  osc_create(&a, integrator);
  osc_create(&b, integrator);
  double ta = 0, tb = 0;
  const double dt = 1.0 / 24;
  osc_steps(&a, &ta, dt, 5);
  osc_steps(&b, &tb, dt, 5);
  const size_t nh = bs_integrator_history_doubles(a.I);
  cr_assert_eq(nh, integrator == BS_INTEGRATOR_BDF2 ? 24u : 12u);
  double h[24];
  bs_step_history hs = {0, 0, 0, h};
  bs_integrator_get_history(b.I, &hs);
  cr_assert_eq(hs.have, 1);
  bs_min_carry c;
  bs_integrator_get_carry(b.I, &c);
  osc_integrator(&b, integrator); /* a fresh one */
  bs_integrator_set_carry(b.I, &c);
  bs_integrator_set_history(b.I, &hs);
  osc_steps(&a, &ta, dt, 7);
  osc_steps(&b, &tb, dt, 7);
  cr_expect(memcmp(a.x, b.x, sizeof a.x) == 0 && memcmp(a.v, b.v, sizeof a.v) == 0,
            "%s: the restored run differs", bs_time_integrator_name((bs_time_integrator)integrator));
  /* without the history the fresh integrator restarts: another answer */
  osc_integrator(&b, integrator);
  memcpy(b.x, a.x, sizeof a.x), memcpy(b.v, a.v, sizeof a.v);
  osc_steps(&a, &ta, dt, 1);
  osc_steps(&b, &tb, dt, 1);
  cr_expect(memcmp(a.x, b.x, sizeof a.x) != 0, "a restart without history gave the same step");
  osc_destroy(&a);
  osc_destroy(&b);
}

Test(integrators, bdf2_history_restores_bit_for_bit) { history_restores(BS_INTEGRATOR_BDF2); }
Test(integrators, newmark_history_restores_bit_for_bit) { history_restores(BS_INTEGRATOR_NEWMARK); }

Test(integrators, names_parse_and_unknown_ones_are_refused) {
  bs_time_integrator k;
  bs_error err;
  const char *names[] = {"backward_euler", "bdf2", "newmark"};
  for (int i = 0; i < 3; i++) {
    cr_expect_eq(bs_time_integrator_parse(names[i], &k, &err), 0);
    cr_expect_eq((int)k, i);
    cr_expect_str_eq(bs_time_integrator_name(k), names[i]);
  }
  cr_expect_eq(bs_time_integrator_parse("rk4", &k, &err), BS_EINPUT);
  cr_expect_not_null(strstr(err.msg, "'rk4'"), "%s", err.msg);
  cr_expect_str_eq(bs_time_integrator_name((bs_time_integrator)7), "?");
  osc o;
  osc_create(&o, BS_INTEGRATOR_BACKWARD_EULER);
  bs_integrator_opts op;
  bs_integrator_opts_default(&op);
  op.integrator = 7;
  bs_integrator *I = NULL;
  cr_expect_eq(bs_integrator_create(o.fem, &o.step, 2, o.terms, NULL, NULL, NULL, &op, &I, &err), BS_EINPUT);
  cr_expect_null(I);
  cr_expect_not_null(strstr(err.msg, "time integrator"), "%s", err.msg);
  osc_destroy(&o);
}

/* ---- bigstep run -------------------------------------------------------- */

static char root[128];
#define AT(buf, name) snprintf(buf, sizeof buf, "%s/%s", root, name)

/* A cantilever (the beam of data/scenes/beam_sag.json, coarser) released from
 * rest under gravity, with a penalty floor under its tip. */
static const char *const scene_text =
    "{\"time\": {\"fps\": 48, \"frames\": 30, \"steps_per_frame\": 2},\n"
    " \"solver\": {\"tolerance\": 1e-6},\n"
    " \"gravity\": [0, -9.8, 0],\n"
    " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [12, 2, 2], \"size\": [1, 0.1, 0.1]},\n"
    "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000},\n"
    "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}],\n"
    " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": -0.15, \"collision\": \"penalty\"}],\n"
    " \"output\": {\"vtu_every\": 0, \"states\": true, \"checkpoint_every\": 2}}\n";

static void sh(const char *fmt, const char *arg) {
  char cmd[1024];
  snprintf(cmd, sizeof cmd, fmt, arg);
  cr_assert_eq(system(cmd), 0, "%s", cmd);
}

static void cli_setup(void) {
  snprintf(root, sizeof root, "/tmp/bs_integrators_%ld", (long)getpid());
  sh("rm -rf %1$s && mkdir -p %1$s", root);
  char p[256];
  AT(p, "scene.json");
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fputs(scene_text, f);
  fclose(f);
}
static void cli_teardown(void) { sh("rm -rf %s", root); }

static int run(const char *dir, const char *args, char **out) {
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "%s run %s/scene.json --quiet --out %s %s", BS_BIGSTEP_EXE, root, dir, args);
  return bs_test_run(cmd, out);
}

/* `bigstep run` with --set solver.integrator=NAME in the background: its pid. */
static pid_t start(const char *dir, const char *set) {
  char log[512], scene[256];
  snprintf(log, sizeof log, "%s.log", dir);
  AT(scene, "scene.json");
  pid_t pid = fork();
  cr_assert(pid >= 0);
  if (pid == 0) {
    int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    execl(BS_BIGSTEP_EXE, BS_BIGSTEP_EXE, "run", scene, "--quiet", "--out", dir, "--set", set, (char *)NULL);
    _exit(127);
  }
  return pid;
}

static char *frames_without_seconds(const char *dir) {
  char cmd[600], *out = NULL;
  snprintf(cmd, sizeof cmd, "cut -d, -f1-11,13- %s/frames.csv", dir);
  cr_assert_eq(bs_test_run(cmd, &out), 0);
  return out;
}

/* checkpoint.bin of version 4 rewritten as version 3 (bs_runfolder.h): the
 * integrator's 32-byte block after the previous-step block dropped (backward
 * Euler has no history vectors), the version and the checksum made again. */
#define CK_HEAD3 (48 + 12 * 8 + 2 * 8 + 2 * 4 + 256 + 16 + 24)
static void make_version3(const char *dir) {
  char p[512];
  snprintf(p, sizeof p, "%s/checkpoint.bin", dir);
  FILE *f = fopen(p, "rb");
  cr_assert_not_null(f);
  unsigned char *b = malloc(1 << 20);
  size_t n = fread(b, 1, 1 << 20, f);
  fclose(f);
  uint32_t version;
  memcpy(&version, b + 4, 4);
  cr_assert_eq(version, 4u);
  memmove(b + CK_HEAD3, b + CK_HEAD3 + 32, n - CK_HEAD3 - 32);
  n -= 32;
  version = 3;
  memcpy(b + 4, &version, 4);
  const uint64_t h = bs_fnv1a(BS_FNV_SEED, b, n - 8);
  memcpy(b + n - 8, &h, 8);
  f = fopen(p, "wb");
  cr_assert_not_null(f);
  cr_assert_eq(fwrite(b, 1, n, f), n);
  fclose(f);
  free(b);
}

static void resume_repeats(const char *integrator) {
  char *out = NULL, ref[160], dir[160], set[64], args[128], cmd[600];
  snprintf(set, sizeof set, "solver.integrator=%s", integrator);
  snprintf(args, sizeof args, "--set %s", set);
  AT(ref, "ref");
  AT(dir, "stopped");
  cr_assert_eq(run(ref, args, &out), 0, "%s", out);
  free(out);
  pid_t pid = start(dir, set);
  int status, ended = 0;
  while (bs_frames_csv_lines(dir) < 6 + 2)
    if (waitpid(pid, &status, WNOHANG) == pid) {
      ended = 1;
      break;
    } else {
      usleep(1000);
    }
  if (!ended) {
    kill(pid, SIGINT);
    cr_assert_eq(waitpid(pid, &status, 0), pid);
    cr_expect(WIFEXITED(status) && (WEXITSTATUS(status) == 130 || WEXITSTATUS(status) == 0));
  } else {
    cr_log_warn("%s: the run ended before it could be stopped", integrator);
  }
  cr_log_info("%s: stopped after %d frames.csv lines", integrator, bs_frames_csv_lines(dir));
  if (!strcmp(integrator, "backward_euler")) make_version3(dir);
  snprintf(args, sizeof args, "--set %s --resume", set);
  cr_assert_eq(run(dir, args, &out), 0, "%s", out);
  free(out);
  snprintf(cmd, sizeof cmd, "cmp -s %s/state.bin %s/state.bin", ref, dir);
  cr_expect_eq(system(cmd), 0, "%s: state.bin differs from the run never stopped", integrator);
  char *a = frames_without_seconds(ref), *b = frames_without_seconds(dir);
  cr_expect_str_eq(b, a, "%s: frames.csv (but its seconds) differs", integrator);
  free(a);
  free(b);
  snprintf(cmd, sizeof cmd, "grep -q '\"integrator\": \"%s\"' %s/scene.json", integrator, ref);
  const int be = !strcmp(integrator, "backward_euler");
  cr_expect_eq(system(cmd) == 0, !be, "the resolved scene names the integrator unless it is the default");
}

Test(integrators_cli, bdf2_stopped_and_resumed_repeats_the_run, .init = cli_setup, .fini = cli_teardown) {
  resume_repeats("bdf2");
}

Test(integrators_cli, newmark_stopped_and_resumed_repeats_the_run, .init = cli_setup, .fini = cli_teardown) {
  resume_repeats("newmark");
}

/* A checkpoint of the version before the integrators (3) still resumes a
 * backward Euler run bit for bit. */
Test(integrators_cli, backward_euler_resumes_from_a_version_3_checkpoint, .init = cli_setup, .fini = cli_teardown) {
  resume_repeats("backward_euler");
}

Test(integrators_cli, an_unknown_integrator_is_refused_by_key, .init = cli_setup, .fini = cli_teardown) {
  char *out = NULL, dir[160];
  AT(dir, "bad");
  cr_expect_eq(run(dir, "--set solver.integrator=rk4", &out), 1, "%s", out);
  cr_expect_not_null(strstr(out, "solver.integrator"), "%s", out);
  cr_expect_not_null(strstr(out, "rk4"), "%s", out);
  free(out);
  cr_expect_eq(run(dir, "--set solver.integrator=bdf2 --set obstacles.0.collision=postprocess", &out), 1, "%s", out);
  cr_expect_not_null(strstr(out, "obstacles.0.collision"), "%s", out);
  cr_expect_not_null(strstr(out, "solver.integrator bdf2"), "%s", out);
  free(out);
}
