/* bigstep study SCENE --vary KEY=v1,v2,... — speed against accuracy, measured.
 *
 * Runs the cross product of the varied settings, each as a child `bigstep run`
 * (this executable, /proc/self/exe) in its own folder, then compares every run
 * with a reference run at common frame times and writes study.csv, gnuplot
 * PNG plots and a one-screen summary.
 *
 * Errors against the reference (x_ref, v_ref), over the compared vertices C
 * (refinement appends edge midpoints, so the first vertices of each body are
 * the vertices of its coarsest mesh in the study; those are compared):
 *   position e_x(t) = sqrt(Σ_{i∈C} |x_i − x_ref,i|² / |C|) / L,
 *            L = the diagonal of the bounding box of all bodies at rest;
 *   velocity e_v(t) = sqrt(Σ_{i∈C} |v_i − v_ref,i|² / |C|) / V,
 *            V = the reference's largest vertex speed over all frames, or 1 m/s if 0;
 * each reported as the max over common frames and at the last common frame.
 * Energy drift = max_t |total(t) − total(0)| / max(|total(0)|, max_t kinetic(t))
 * (1 J if both are 0), from the run's own frames.csv.
 * Observed orders: least squares slope of log(error) against log(h), with
 * h = 2^-refine (space) or h = Δt (time), over the runs whose other settings
 * are the finest ones, the reference itself left out; and, unbiased by the
 * reference, from successive levels (each run of that group against the next
 * finer one: see successive_order). */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "app.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"

static const char *study_help =
    "usage: bigstep study SCENE --vary KEY=v1,v2,... [--vary ...] [--set key.path=value]...\n"
    "                           [--reference auto|RUN_DIR] [--jobs N] [--out DIR]\n"
    "\n"
    "Runs every combination of the varied settings (`bigstep run --quiet` in its own\n"
    "folder under DIR, default out/study/<scene name>; a folder holding a complete\n"
    "frames.csv and a 'done' marker is not run again), compares each run with the\n"
    "reference at common frame times, and writes study.csv, PNG plots (gnuplot) and\n"
    "a summary: for each method the cheapest setting within 1%, 0.1% and 0.01%\n"
    "position error, and the observed orders of convergence in space and time.\n"
    "  --vary KEY=v1,v2,...  a scene key path or a shorthand: steps_per_frame\n"
    "                        (time.steps_per_frame), refine (bodies.*.refine, every\n"
    "                        body), method (solver.method), tolerance (solver.tolerance)\n"
    "  --set key.path=value  any scene key, as in `bigstep run` (applied to every run)\n"
    "  --reference auto      the finest setting of every varied knob [default]: largest\n"
    "                        steps_per_frame / refine / fps, smallest tolerance / dt,\n"
    "                        method optimization (else the first listed); the last listed\n"
    "                        value of any other key\n"
    "  --reference RUN_DIR   a run folder holding frames.csv and state.bin\n"
    "  --jobs N              runs in parallel [1] (each child gets OMP_NUM_THREADS =\n"
    "                        cores / N unless set)\n"
    "  --out DIR             the study folder\n"
    "Errors: position = RMS over the compared vertices of x - x_ref over the body size\n"
    "(bounding-box diagonal at rest); velocity = RMS of v - v_ref over the reference's\n"
    "largest speed (1 m/s if it is 0); both the max over frames and at the last frame.\n"
    "Energy drift = max |total(t) - total(0)| over max(|total(0)|, max kinetic) (1 J if 0).\n"
    "Orders: the slope of log error against log h (h = 2^-refine or dt) over the runs\n"
    "whose other knobs are at the reference; and from successive levels (each run\n"
    "against the next finer one), which the nearness of the reference does not bias.\n"
    "A failed run is recorded (failed column) and does not stop the study.\n";

#define MAX_VARY 16

typedef enum { K_SPF, K_TOL, K_REFINE, K_METHOD, K_DT, K_FPS, K_OTHER } knob_kind;

typedef struct vary {
  char key[256];   /* as given (column name)                        */
  char path[256];  /* scene key path; "" for refine over every body */
  knob_kind kind;
  int body;        /* K_REFINE through bodies.N.refine: N; -1: every body */
  int n;
  char **vals;
  int finest;
} vary;

typedef struct run {
  int idx[MAX_VARY];
  char name[512], dir[1400];
  int n_sets;
  char **sets;     /* owned: "key=value" */
  int pending;
  pid_t pid;
  double t0;
  /* from the run's scene */
  int frames, spf, is_static;
  double fps;
  char method[32];
  int *body_refine;
  /* results */
  int exit_code, complete, is_ref, pareto;
  long maxrss_kib;
  double wall;
  int n_rows;
  long newton, cg, failed_steps;
  double s_per_frame, newton_per_step, cg_per_step, peak_mib;
  double pos_max, pos_last, vel_max, vel_last, drift, pen_max;
  int inv_max;
} run;

typedef struct study {
  const char *scene_path;
  char name[256], out[1200];
  int n_vary;
  vary vary[MAX_VARY];
  int n_user;
  const char **user_sets;
  int jobs;
  const char *ref_dir; /* NULL: auto */
  int n_bodies;
  int n_runs;
  run *runs;
  int ref;             /* index of the reference run, -1 for a given folder */
  double size;         /* body size L (m)                                     */
  int64_t (*counts)[4];/* per body V, E, F, T at refine 0                    */
  int64_t cmp[64];     /* compared vertices per body (the coarsest level)    */
  double vscale;       /* velocity scale of the errors                       */
  int direct;          /* compare whole states (no refinement relation)     */
} study;

/* ---- small helpers ------------------------------------------------------ */

static int mkdir_p(const char *dir) {
  char buf[1400];
  snprintf(buf, sizeof buf, "%s", dir);
  for (char *p = buf + 1; *p; p++)
    if (*p == '/') {
      *p = 0;
      if (mkdir(buf, 0755) && errno != EEXIST) return -1;
      *p = '/';
    }
  if (mkdir(buf, 0755) && errno != EEXIST) return -1;
  return 0;
}

static char *xstrdup(const char *s) {
  size_t n = strlen(s) + 1;
  char *d = malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

static char *xprintf(const char *fmt, const char *a, const char *b) {
  size_t n = strlen(fmt) + strlen(a) + strlen(b) + 1;
  char *s = malloc(n);
  snprintf(s, n, fmt, a, b);
  return s;
}

static void fmt_time(double s, char *buf, size_t n) {
  long t = (long)(s + 0.5);
  if (t >= 3600) snprintf(buf, n, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else snprintf(buf, n, "%ld:%02ld", t / 60, t % 60);
}

/* Least squares slope of log y against log x over points with x, y > 0 and finite. */
static double fit_order(int n, const double *x, const double *y, double *logc, int *used) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (int i = 0; i < n; i++) {
    if (!(x[i] > 0) || !(y[i] > 0) || !isfinite(y[i])) continue;
    double lx = log(x[i]), ly = log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    m++;
  }
  *used = m;
  double d = m * sxx - sx * sx;
  if (m < 2 || d <= 0) {
    *logc = NAN;
    return NAN;
  }
  double p = (m * sxy - sx * sy) / d;
  *logc = (sy - p * sx) / m;
  return p;
}

/* ---- argument parsing --------------------------------------------------- */

static int valid_key(const char *k) {
  if (!*k || *k == '.') return 0;
  for (const char *p = k; *p; p++)
    if (!(isalnum((unsigned char)*p) || *p == '_' || *p == '.')) return 0;
  return k[strlen(k) - 1] != '.';
}

/* Copies a key (snprintf from a sibling field of the same struct trips -Wrestrict). */
static void bs_copy_key(char *dst, size_t n, const char *src) {
  size_t l = strlen(src);
  if (l >= n) l = n - 1;
  memmove(dst, src, l);
  dst[l] = '\0';
}

/* Parses "KEY=v1,v2,..." into v. Returns 0, or a usage error. */
static int parse_vary(const char *arg, vary *v) {
  const char *eq = strchr(arg, '=');
  if (!eq || eq == arg || !eq[1])
    return bs_app_usage_error("study", "bad --vary '%s': expected KEY=v1,v2,...", arg);
  snprintf(v->key, sizeof v->key, "%.*s", (int)(eq - arg), arg);
  if (!valid_key(v->key)) return bs_app_usage_error("study", "bad --vary '%s': '%s' is not a key path", arg, v->key);
  v->body = -1;
  const char *k = v->key;
  if (!strcmp(k, "steps_per_frame") || !strcmp(k, "time.steps_per_frame")) {
    v->kind = K_SPF;
    snprintf(v->path, sizeof v->path, "time.steps_per_frame");
  } else if (!strcmp(k, "tolerance") || !strcmp(k, "solver.tolerance")) {
    v->kind = K_TOL;
    snprintf(v->path, sizeof v->path, "solver.tolerance");
  } else if (!strcmp(k, "method") || !strcmp(k, "solver.method")) {
    v->kind = K_METHOD;
    snprintf(v->path, sizeof v->path, "solver.method");
  } else if (!strcmp(k, "refine")) {
    v->kind = K_REFINE;
    v->path[0] = 0;
  } else if (!strcmp(k, "time.dt")) {
    v->kind = K_DT;
    bs_copy_key(v->path, sizeof v->path, v->key);
  } else if (!strcmp(k, "time.fps")) {
    v->kind = K_FPS;
    bs_copy_key(v->path, sizeof v->path, v->key);
  } else {
    int b, len = 0;
    v->kind = K_OTHER;
    if (sscanf(k, "bodies.%d.refine%n", &b, &len) == 1 && len == (int)strlen(k) && b >= 0) {
      v->kind = K_REFINE;
      v->body = b;
    }
    bs_copy_key(v->path, sizeof v->path, v->key);
  }
  /* values */
  char *list = xstrdup(eq + 1);
  int cap = 1;
  for (const char *p = list; *p; p++) cap += *p == ',';
  v->vals = calloc((size_t)cap, sizeof(char *));
  v->n = 0;
  int rc = 0;
  char *p = list;
  for (int i = 0; i < cap; i++) {
    char *c = strchr(p, ',');
    if (c) *c = 0;
    if (!*p) {
      rc = bs_app_usage_error("study", "bad --vary '%s': empty value in the list", arg);
      break;
    }
    for (int j = 0; j < v->n; j++)
      if (!strcmp(v->vals[j], p)) {
        rc = bs_app_usage_error("study", "bad --vary '%s': value '%s' listed twice", arg, p);
        break;
      }
    if (rc) break;
    v->vals[v->n++] = xstrdup(p);
    if (c) p = c + 1;
  }
  free(list);
  if (rc) return rc;
  /* numeric knobs must be numbers */
  if (v->kind != K_METHOD && v->kind != K_OTHER)
    for (int j = 0; j < v->n; j++) {
      double d;
      if (bs_app_parse_double(v->vals[j], &d))
        return bs_app_usage_error("study", "bad --vary '%s': '%s' is not a number", arg, v->vals[j]);
    }
  /* the finest value */
  v->finest = v->n - 1;
  for (int j = 0; j < v->n; j++) {
    double d = 0, f = 0;
    if (v->kind != K_METHOD && v->kind != K_OTHER) {
      bs_app_parse_double(v->vals[j], &d);
      bs_app_parse_double(v->vals[v->finest], &f);
    }
    switch (v->kind) {
      case K_SPF: case K_REFINE: case K_FPS:
        if (d > f) v->finest = j;
        break;
      case K_TOL: case K_DT:
        if (d < f) v->finest = j;
        break;
      default: break;
    }
  }
  if (v->kind == K_METHOD) {
    v->finest = 0;
    for (int j = 0; j < v->n; j++)
      if (!strcmp(v->vals[j], "optimization")) v->finest = j;
  }
  return 0;
}

/* ---- runs --------------------------------------------------------------- */

static void sanitize(const char *in, char *out, size_t n) {
  size_t k = 0;
  for (const char *p = in; *p && k + 1 < n; p++)
    out[k++] = (isalnum((unsigned char)*p) || strchr("._+-", *p)) ? *p : '_';
  out[k] = 0;
}

/* The --set list of run r: study defaults, the user's, the varied values, the outputs. */
static void build_sets(study *S, run *r) {
  int cap = 8 + S->n_user + S->n_vary * (S->n_bodies + 1);
  r->sets = calloc((size_t)cap, sizeof(char *));
  r->n_sets = 0;
  r->sets[r->n_sets++] = xstrdup("output.vtu_every=0");
  for (int i = 0; i < S->n_user; i++) r->sets[r->n_sets++] = xstrdup(S->user_sets[i]);
  char name[512] = "";
  for (int k = 0; k < S->n_vary; k++) {
    const vary *v = &S->vary[k];
    const char *val = v->vals[r->idx[k]];
    if (v->kind == K_REFINE && v->body < 0) {
      for (int b = 0; b < S->n_bodies; b++) {
        char buf[64];
        snprintf(buf, sizeof buf, "bodies.%d.refine=", b);
        r->sets[r->n_sets++] = xprintf("%s%s", buf, val);
      }
    } else {
      r->sets[r->n_sets++] = xprintf("%s=%s", v->path, val);
    }
    char sv[128];
    sanitize(val, sv, sizeof sv);
    size_t len = strlen(name);
    snprintf(name + len, sizeof name - len, "%s%s=%s", k ? "," : "", v->key, sv);
  }
  snprintf(r->name, sizeof r->name, "%s", name);
  snprintf(r->dir, sizeof r->dir, "%s/%s", S->out, name);
  r->sets[r->n_sets++] = xprintf("output.dir=%s%s", r->dir, "");
  r->sets[r->n_sets++] = xstrdup("output.states=true");
  r->sets[r->n_sets++] = xstrdup("output.stats=true");
}

/* The "args" line of the done marker: the run's settings, one string. */
static void args_line(const run *r, char *buf, size_t n) {
  size_t k = 0;
  buf[0] = 0;
  for (int i = 0; i < r->n_sets && k < n; i++) k += (size_t)snprintf(buf + k, n - k, "%s%s", i ? " " : "", r->sets[i]);
}

static int count_lines(const char *path) {
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  int n = 0, c, last = '\n';
  while ((c = fgetc(f)) != EOF) {
    if (c == '\n') n++;
    last = c;
  }
  if (last != '\n') n++;
  fclose(f);
  return n;
}

/* Reads the done marker; 0 when present and made with the same settings. */
static int read_done(run *r, const char *want_args) {
  char p[1500];
  snprintf(p, sizeof p, "%s/done", r->dir);
  FILE *f = fopen(p, "r");
  if (!f) return -1;
  char line[8192];
  int ok_args = 0;
  r->exit_code = -1;
  while (fgets(line, sizeof line, f)) {
    line[strcspn(line, "\n")] = 0;
    if (!strncmp(line, "exit ", 5)) r->exit_code = atoi(line + 5);
    else if (!strncmp(line, "maxrss_kib ", 11)) r->maxrss_kib = atol(line + 11);
    else if (!strncmp(line, "wall ", 5)) r->wall = atof(line + 5);
    else if (!strncmp(line, "args ", 5)) ok_args = !strcmp(line + 5, want_args);
  }
  fclose(f);
  return ok_args && r->exit_code >= 0 ? 0 : -1;
}

static int expected_rows(const run *r) { return r->is_static ? 2 : r->frames + 1; }

static int frames_complete(const run *r) {
  char p[1500];
  snprintf(p, sizeof p, "%s/frames.csv", r->dir);
  return count_lines(p) == expected_rows(r) + 1;
}

static void write_done(const run *r) {
  char p[1500], args[8192];
  snprintf(p, sizeof p, "%s/done", r->dir);
  args_line(r, args, sizeof args);
  FILE *f = fopen(p, "w");
  if (!f) return;
  fprintf(f, "exit %d\nmaxrss_kib %ld\nwall %.6f\nargs %s\n", r->exit_code, r->maxrss_kib, r->wall, args);
  fclose(f);
}

static int start_run(const study *S, run *r, const char *omp) {
  char p[1500];
  snprintf(p, sizeof p, "%s/done", r->dir);
  unlink(p);
  if (mkdir_p(r->dir)) {
    fprintf(stderr, "bigstep study: cannot create folder '%s'\n", r->dir);
    return -1;
  }
  snprintf(p, sizeof p, "%s/run.log", r->dir);
  char **argv = calloc((size_t)(2 * r->n_sets + 8), sizeof(char *));
  int a = 0;
  argv[a++] = "bigstep";
  argv[a++] = "run";
  argv[a++] = (char *)S->scene_path;
  argv[a++] = "--quiet";
  for (int i = 0; i < r->n_sets; i++) {
    argv[a++] = "--set";
    argv[a++] = r->sets[i];
  }
  argv[a] = NULL;
  fflush(stdout);
  fflush(stderr);
  r->t0 = bs_seconds();
  pid_t pid = fork();
  if (pid < 0) {
    free(argv);
    fprintf(stderr, "bigstep study: cannot start a run: %s\n", strerror(errno));
    return -1;
  }
  if (pid == 0) {
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    if (omp && !getenv("OMP_NUM_THREADS")) setenv("OMP_NUM_THREADS", omp, 1);
    execv("/proc/self/exe", argv);
    fprintf(stderr, "bigstep study: cannot execute /proc/self/exe: %s\n", strerror(errno));
    _exit(127);
  }
  free(argv);
  r->pid = pid;
  return 0;
}

static void progress(int done, int total, double t0, int final) {
  double el = bs_seconds() - t0;
  char e[32], l[32];
  fmt_time(el, e, sizeof e);
  if (done > 0) fmt_time(el / done * (total - done), l, sizeof l);
  else snprintf(l, sizeof l, "?");
  if (isatty(2)) {
    char bar[31];
    int w = total ? 30 * done / total : 30;
    for (int i = 0; i < 30; i++) bar[i] = i < w ? '#' : '-';
    bar[30] = 0;
    fprintf(stderr, "\rstudy [%s] %d/%d runs, %s elapsed, ~%s left ", bar, done, total, e, l);
    if (final) fputc('\n', stderr);
  } else {
    fprintf(stderr, "study: %d/%d runs done, %s elapsed, ~%s left\n", done, total, e, l);
  }
  fflush(stderr);
}

/* Runs the pending runs, at most S->jobs at a time. */
static int run_all(study *S, int n_pending) {
  if (n_pending == 0) return 0;
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  char omp[16];
  const char *ompp = NULL;
  if (S->jobs > 1) {
    long t = cores / S->jobs;
    snprintf(omp, sizeof omp, "%ld", t < 1 ? 1 : t);
    ompp = omp;
  }
  double t0 = bs_seconds();
  int next = 0, running = 0, done = 0, rc = 0;
  progress(0, n_pending, t0, 0);
  while (done < n_pending) {
    while (running < S->jobs && next < S->n_runs) {
      run *r = &S->runs[next++];
      if (!r->pending) continue;
      if (start_run(S, r, ompp)) {
        r->exit_code = 127;
        done++;
        rc = -1;
        continue;
      }
      running++;
    }
    if (!running) break;
    int status;
    struct rusage ru;
    pid_t pid = wait4(-1, &status, 0, &ru);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < S->n_runs; i++) {
      run *r = &S->runs[i];
      if (r->pending && r->pid == pid) {
        r->pid = 0;
        r->wall = bs_seconds() - r->t0;
        r->maxrss_kib = ru.ru_maxrss;
        r->exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
        write_done(r);
        running--;
        done++;
        progress(done, n_pending, t0, done == n_pending);
        break;
      }
    }
  }
  return rc;
}

/* ---- reading a run's outputs -------------------------------------------- */

typedef struct frames_csv {
  int n;
  double *time, *kin, *total, *pen;
  long newton, cg, failed;
  int inv_max, has_pen;
  double seconds;
} frames_csv;

static void frames_free(frames_csv *f) {
  free(f->time);
  free(f->kin);
  free(f->total);
  free(f->pen);
  memset(f, 0, sizeof *f);
}

static int read_frames(const char *dir, frames_csv *F) {
  memset(F, 0, sizeof *F);
  char p[1500];
  snprintf(p, sizeof p, "%s/frames.csv", dir);
  FILE *f = fopen(p, "r");
  if (!f) return -1;
  char line[8192];
  if (!fgets(line, sizeof line, f)) {
    fclose(f);
    return -1;
  }
  enum { C_TIME, C_KIN, C_TOTAL, C_INV, C_NEWTON, C_CG, C_FAILED, C_SECONDS, C_PEN, C_N };
  static const char *names[C_N] = {"time", "kinetic", "total", "inverted", "newton", "cg", "failed", "seconds",
                                   "max_depth"};
  int col[C_N];
  for (int c = 0; c < C_N; c++) col[c] = -1;
  int nc = 0;
  line[strcspn(line, "\r\n")] = 0;
  for (char *tok = strtok(line, ","); tok; tok = strtok(NULL, ","), nc++)
    for (int c = 0; c < C_N; c++)
      if (!strcmp(tok, names[c])) col[c] = nc;
  F->has_pen = col[C_PEN] >= 0;
  int cap = 64;
  F->time = malloc(sizeof(double) * cap);
  F->kin = malloc(sizeof(double) * cap);
  F->total = malloc(sizeof(double) * cap);
  F->pen = malloc(sizeof(double) * cap);
  while (fgets(line, sizeof line, f)) {
    double v[64];
    int k = 0;
    char *s = line;
    while (k < 64) {
      v[k++] = strtod(s, NULL);
      s = strchr(s, ',');
      if (!s) break;
      s++;
    }
    if (F->n == cap) {
      cap *= 2;
      F->time = realloc(F->time, sizeof(double) * cap);
      F->kin = realloc(F->kin, sizeof(double) * cap);
      F->total = realloc(F->total, sizeof(double) * cap);
      F->pen = realloc(F->pen, sizeof(double) * cap);
    }
#define COL(c) (col[c] >= 0 && col[c] < k ? v[col[c]] : 0.0)
    F->time[F->n] = COL(C_TIME);
    F->kin[F->n] = COL(C_KIN);
    F->total[F->n] = COL(C_TOTAL);
    F->pen[F->n] = COL(C_PEN);
    if ((int)COL(C_INV) > F->inv_max) F->inv_max = (int)COL(C_INV);
    F->newton += (long)COL(C_NEWTON);
    F->cg += (long)COL(C_CG);
    F->failed += (long)COL(C_FAILED);
    F->seconds += COL(C_SECONDS);
#undef COL
    F->n++;
  }
  fclose(f);
  return 0;
}

/* s/frame and solves/step from summary.txt's second line; peak memory (MiB). */
static int read_summary(const char *dir, double *spf_s, double *peak) {
  char p[1500];
  snprintf(p, sizeof p, "%s/summary.txt", dir);
  FILE *f = fopen(p, "r");
  if (!f) return -1;
  char line[4096];
  int got = -1, ln = 0;
  while (fgets(line, sizeof line, f)) {
    ln++;
    char m[64];
    int steps;
    double s;
    if (ln == 2 && sscanf(line, "%63s %d %lf", m, &steps, &s) == 3) {
      *spf_s = s;
      got = 0;
    }
    const char *pk = strstr(line, "peak memory ");
    if (pk) *peak = atof(pk + 12);
  }
  fclose(f);
  return got;
}

/* state.bin reader: one frame at a time (bs_runfolder.h). */
typedef bs_state_reader state_file;

static int state_open(const char *dir, state_file *s) {
  bs_error e;
  return bs_state_open(dir, s, &e) ? -1 : 0;
}

static int state_next(state_file *s) { return bs_state_next(s) ? -1 : 0; }

static void state_close(state_file *s) { bs_state_close(s); }

/* Vertex count of body b after r uniform refinements: V' = V + E,
 * E' = 2E + 3F + T, F' = 4F + 8T, T' = 8T (F counts every triangle). */
static int64_t body_vertices(const int64_t c[4], int r) {
  int64_t V = c[0], E = c[1], F = c[2], T = c[3];
  for (int i = 0; i < r; i++) {
    int64_t V1 = V + E, E1 = 2 * E + 3 * F + T, F1 = 4 * F + 8 * T, T1 = 8 * T;
    V = V1;
    E = E1;
    F = F1;
    T = T1;
  }
  return V;
}

/* The compared vertex blocks of a run: per body, its offset in the run. */
static int64_t run_offsets(const study *S, const int *refine, int64_t *off) {
  int64_t o = 0;
  for (int b = 0; b < S->n_bodies; b++) {
    off[b] = o;
    o += body_vertices(S->counts[b], refine[b]);
  }
  return o;
}

/* Errors of run r against the reference folder. cmp[b] vertices of body b
 * are compared, at offsets off_r[b] (run) and off_ref[b] (reference). */
static int compare_run(const study *S, run *r, const char *ref_dir, const int64_t *cmp, const int64_t *off_ref,
                       double vscale, int direct) {
  state_file a, b;
  if (state_open(r->dir, &a)) return -1;
  if (state_open(ref_dir, &b)) {
    state_close(&a);
    return -1;
  }
  int64_t off_r[64];
  int ok = 1;
  if (!direct) {
    int64_t n = run_offsets(S, r->body_refine, off_r);
    if (n != a.n) ok = 0;
  } else if (a.n != b.n) ok = 0;
  int64_t ncmp = 0;
  if (ok) {
    if (direct) ncmp = a.n;
    else
      for (int q = 0; q < S->n_bodies; q++) ncmp += cmp[q];
  }
  r->pos_max = r->vel_max = r->pos_last = r->vel_last = NAN;
  int have_a = ok && state_next(&a) == 0, have_b = ok && state_next(&b) == 0, n_common = 0;
  while (have_a && have_b) {
    double ta = a.buf[0], tb = b.buf[0], eps = 1e-9 * (1 + fabs(tb));
    if (fabs(ta - tb) <= eps) {
      double ex = 0, ev = 0;
      int nblk = direct ? 1 : S->n_bodies;
      for (int q = 0; q < nblk; q++) {
        int64_t ca = direct ? 0 : off_r[q], cb = direct ? 0 : off_ref[q], nn = direct ? a.n : cmp[q];
        const double *xa = a.buf + 1 + 3 * ca, *xb = b.buf + 1 + 3 * cb;
        const double *va = a.buf + 1 + 3 * (size_t)a.n + 3 * ca, *vb = b.buf + 1 + 3 * (size_t)b.n + 3 * cb;
        for (int64_t i = 0; i < 3 * nn; i++) {
          double dx = xa[i] - xb[i], dv = va[i] - vb[i];
          ex += dx * dx;
          ev += dv * dv;
        }
      }
      double px = sqrt(ex / (double)ncmp) / S->size, pv = sqrt(ev / (double)ncmp) / vscale;
      if (!isfinite(px)) px = INFINITY;
      if (!isfinite(pv)) pv = INFINITY;
      r->pos_max = n_common ? fmax(r->pos_max, px) : px;
      r->vel_max = n_common ? fmax(r->vel_max, pv) : pv;
      r->pos_last = px;
      r->vel_last = pv;
      n_common++;
      have_a = state_next(&a) == 0;
      have_b = state_next(&b) == 0;
    } else if (ta < tb) have_a = state_next(&a) == 0;
    else have_b = state_next(&b) == 0;
  }
  state_close(&a);
  state_close(&b);
  return ok && n_common ? 0 : -1;
}

/* Largest vertex speed over all frames of a state file (m/s). */
static double max_speed(const char *dir) {
  state_file s;
  if (state_open(dir, &s)) return 0;
  double m = 0;
  while (state_next(&s) == 0) {
    const double *v = s.buf + 1 + 3 * (size_t)s.n;
    for (int32_t i = 0; i < s.n; i++) {
      double q = v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2];
      if (q > m) m = q;
    }
  }
  state_close(&s);
  return sqrt(m);
}

/* Cost and energy columns of a finished run. */
static void read_costs(run *r) {
  frames_csv F;
  r->s_per_frame = r->newton_per_step = r->cg_per_step = r->drift = r->pen_max = NAN;
  r->peak_mib = r->maxrss_kib > 0 ? r->maxrss_kib / 1024.0 : NAN;
  r->complete = frames_complete(r);
  if (read_frames(r->dir, &F)) return;
  r->n_rows = F.n;
  r->newton = F.newton;
  r->cg = F.cg;
  r->failed_steps = F.failed;
  r->inv_max = F.inv_max;
  int fr = F.n - 1;
  long steps = r->is_static ? (fr > 0 ? 1 : 0) : (long)fr * r->spf;
  double sum_s, peak = NAN;
  /* s/frame: the solver's time per frame (frames.csv, microsecond resolution);
     summary.txt's wall-clock figure when frames.csv has no timing */
  int have_sum = read_summary(r->dir, &sum_s, &peak) == 0;
  if (fr > 0 && F.seconds > 0) r->s_per_frame = F.seconds / fr;
  else if (have_sum) r->s_per_frame = sum_s;
  if (!isfinite(r->peak_mib) && isfinite(peak)) r->peak_mib = peak;
  if (steps > 0) {
    r->newton_per_step = (double)F.newton / steps;
    r->cg_per_step = (double)F.cg / steps;
  }
  if (F.n > 0) {
    double scale = fabs(F.total[0]), d = 0;
    for (int i = 0; i < F.n; i++) {
      if (F.kin[i] > scale) scale = F.kin[i];
      double q = fabs(F.total[i] - F.total[0]);
      if (q > d || !isfinite(q)) d = q;
    }
    r->drift = d / (scale > 0 ? scale : 1.0);
    if (F.has_pen) {
      r->pen_max = 0;
      for (int i = 0; i < F.n; i++)
        if (F.pen[i] > r->pen_max) r->pen_max = F.pen[i];
    }
  }
  frames_free(&F);
}

/* ---- body size and per-body counts -------------------------------------- */

static int body_geometry(study *S, bs_error *err) {
  int n = S->n_user + S->n_bodies;
  const char **sets = calloc((size_t)n + 1, sizeof(char *));
  char **own = calloc((size_t)S->n_bodies + 1, sizeof(char *));
  for (int i = 0; i < S->n_user; i++) sets[i] = S->user_sets[i];
  for (int b = 0; b < S->n_bodies; b++) {
    char buf[64];
    snprintf(buf, sizeof buf, "bodies.%d.refine=0", b);
    own[b] = xstrdup(buf);
    sets[S->n_user + b] = own[b];
  }
  bs_scene *sc = NULL;
  bs_sim *sim = NULL;
  int st = bs_scene_load(S->scene_path, n, sets, &sc, err);
  if (!st) st = bs_sim_create(sc, &sim, err);
  if (!st) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t v = 0; v < sim->mesh->n_vertices; v++)
      for (int k = 0; k < 3; k++) {
        lo[k] = fmin(lo[k], sim->x0[3 * v + k]);
        hi[k] = fmax(hi[k], sim->x0[3 * v + k]);
      }
    S->size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(S->size > 0)) S->size = 1.0;
  }
  /* per body V, E, F, T of the unrefined mesh (for the compared vertex blocks) */
  S->counts = calloc((size_t)S->n_bodies, sizeof *S->counts);
  for (int b = 0; !st && b < S->n_bodies; b++) {
    const bs_scene_body *bd = &sc->bodies[b];
    bs_mesh *m = NULL;
    if (!strcmp(bd->mesh, "box")) {
      double o[3] = {0, 0, 0};
      st = bs_mesh_create_box(o, bd->box_size, bd->box_cells[0], bd->box_cells[1], bd->box_cells[2], &m, err);
    } else {
      bs_mesh_read_opts o = {.size = bd->mesh_size, .refine = 0};
      st = bs_mesh_read(bd->mesh, &o, &m, err);
    }
    int32_t *ptr = NULL, *adj = NULL;
    if (!st) st = bs_mesh_vertex_graph(m, &ptr, &adj, err);
    if (!st) {
      S->counts[b][0] = m->n_vertices;
      S->counts[b][1] = ptr[m->n_vertices] / 2;
      S->counts[b][2] = (4 * (int64_t)m->n_tets + m->n_faces) / 2;
      S->counts[b][3] = m->n_tets;
    }
    free(ptr);
    free(adj);
    bs_mesh_destroy(&m);
  }
  bs_sim_destroy(&sim);
  bs_scene_destroy(&sc);
  for (int b = 0; b < S->n_bodies; b++) free(own[b]);
  free(own);
  free(sets);
  return st;
}

/* ---- outputs ------------------------------------------------------------ */

static int is_time_knob(const vary *v) { return v->kind == K_SPF || v->kind == K_DT || v->kind == K_FPS; }

/* The runs of a convergence group: every knob but `k` (and the method) at its
 * finest value; returns how many, indices into out. */
static int group(const study *S, int k, const char *method, int *out) {
  int n = 0;
  for (int i = 0; i < S->n_runs; i++) {
    const run *r = &S->runs[i];
    int ok = !strcmp(r->method, method);
    for (int q = 0; ok && q < S->n_vary; q++)
      if (q != k && S->vary[q].kind != K_METHOD && r->idx[q] != S->vary[q].finest) ok = 0;
    if (ok) out[n++] = i;
  }
  return n;
}

/* h of run r for knob k: 2^-refine (space) or dt (time). */
static double knob_h(const study *S, const run *r, int k) {
  const vary *v = &S->vary[k];
  if (v->kind == K_REFINE) {
    double d = 0;
    bs_app_parse_double(v->vals[r->idx[k]], &d);
    return pow(2.0, -d);
  }
  return 1.0 / (r->fps * r->spf);
}

static int n_methods(const study *S, const char **names) {
  int n = 0;
  for (int i = 0; i < S->n_runs; i++) {
    int seen = 0;
    for (int j = 0; j < n; j++) seen |= !strcmp(names[j], S->runs[i].method);
    if (!seen) names[n++] = S->runs[i].method;
  }
  return n;
}

/* Whether run r (of a knob-k group) enters the order fit: it finished, and
 * it is not at the reference's level of knob k (there the error measures the
 * solver or method difference, not the discretization). */
static int fit_point(const study *S, const run *r, int k) {
  if (r->is_ref || r->exit_code != 0) return 0;
  return S->ref_dir || r->idx[k] != S->vary[k].finest;
}

typedef struct order_fit {
  double p, logc;
  int used;
} order_fit;

static order_fit fit_knob(const study *S, int k, const char *method, int *grp, int *ng) {
  order_fit o = {NAN, NAN, 0};
  *ng = group(S, k, method, grp);
  double *x = malloc(sizeof(double) * (*ng + 1)), *y = malloc(sizeof(double) * (*ng + 1));
  int m = 0;
  for (int i = 0; i < *ng; i++) {
    const run *r = &S->runs[grp[i]];
    if (!fit_point(S, r, k)) continue;
    x[m] = knob_h(S, r, k);
    y[m] = r->pos_max;
    m++;
  }
  o.p = fit_order(m, x, y, &o.logc, &o.used);
  free(x);
  free(y);
  return o;
}

static int write_csv(const study *S) {
  char p[1400];
  snprintf(p, sizeof p, "%s/study.csv", S->out);
  FILE *f = fopen(p, "w");
  if (!f) return -1;
  fprintf(f, "run");
  /* the shorthand "method" would repeat the method column's name: its path instead */
  for (int k = 0; k < S->n_vary; k++) fprintf(f, ",%s", !strcmp(S->vary[k].key, "method") ? S->vary[k].path : S->vary[k].key);
  fprintf(f, ",method,exit,failed,failed_steps,frames,s_per_frame,newton_per_step,cg_per_step,peak_mib,pos_err_max,"
             "pos_err_last,vel_err_max,vel_err_last,energy_drift,inverted_max,penetration_max,reference,pareto\n");
  for (int i = 0; i < S->n_runs; i++) {
    const run *r = &S->runs[i];
    fprintf(f, "%s", r->name);
    for (int k = 0; k < S->n_vary; k++) fprintf(f, ",%s", S->vary[k].vals[r->idx[k]]);
    fprintf(f, ",%s,%d,%d,%ld,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%.6g,%d,%d\n", r->method, r->exit_code,
            r->exit_code != 0, r->failed_steps, r->n_rows > 0 ? r->n_rows - 1 : 0, r->s_per_frame, r->newton_per_step,
            r->cg_per_step, r->peak_mib, r->pos_max, r->pos_last, r->vel_max, r->vel_last, r->drift, r->inv_max,
            r->pen_max, r->is_ref, r->pareto);
  }
  fclose(f);
  return 0;
}

static double successive_order(const study *S, int k, const char *method, int *used, FILE *pts);

/* Writes the data files and plots.gp, then runs gnuplot in the study folder. */
static int make_plots(const study *S, char *msg, size_t msg_n) {
  const char *methods[256];
  int nm = n_methods(S, methods);
  char p[1400];
  int *grp = malloc(sizeof(int) * (S->n_runs + 1)), ng;
  snprintf(p, sizeof p, "%s/plots.gp", S->out);
  FILE *gp = fopen(p, "w");
  if (!gp) {
    snprintf(msg, msg_n, "cannot write '%s'", p);
    free(grp);
    return -1;
  }
  fprintf(gp, "# written by bigstep study; run with: gnuplot plots.gp (in this folder)\n"
              "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) { set terminal pngcairo size 900,600 } "
              "else { set terminal png size 900,600 }\n"
              "set termoption noenhanced\n"
              "set grid\nset key outside right\nset format y '%%.0e'\n");
  /* 1. error against cost, the Pareto front marked */
  snprintf(p, sizeof p, "%s/plot_cost.dat", S->out);
  FILE *d = fopen(p, "w");
  for (int m = 0; d && m < nm; m++) {
    fprintf(d, "# method %s: s_per_frame pos_err_max\n", methods[m]);
    for (int i = 0; i < S->n_runs; i++) {
      const run *r = &S->runs[i];
      if (!strcmp(r->method, methods[m]) && r->pos_max > 0 && isfinite(r->pos_max) && r->s_per_frame > 0)
        fprintf(d, "%.9g %.9g\n", r->s_per_frame, r->pos_max);
    }
    fprintf(d, "\n\n");
  }
  if (d) fclose(d);
  snprintf(p, sizeof p, "%s/plot_pareto.dat", S->out);
  d = fopen(p, "w");
  if (d) {
    fprintf(d, "# Pareto front (error > 0): s_per_frame pos_err_max\n");
    int *ord = malloc(sizeof(int) * (S->n_runs + 1)), no = 0;
    for (int i = 0; i < S->n_runs; i++)
      if (S->runs[i].pareto && S->runs[i].pos_max > 0) ord[no++] = i;
    for (int i = 1; i < no; i++)
      for (int j = i; j > 0 && S->runs[ord[j]].s_per_frame < S->runs[ord[j - 1]].s_per_frame; j--) {
        int t = ord[j];
        ord[j] = ord[j - 1];
        ord[j - 1] = t;
      }
    for (int i = 0; i < no; i++) fprintf(d, "%.9g %.9g\n", S->runs[ord[i]].s_per_frame, S->runs[ord[i]].pos_max);
    if (no == 0) fprintf(d, "nan nan\n");
    free(ord);
    fclose(d);
  }
  fprintf(gp, "set output 'error_vs_cost.png'\nset logscale xy\nset xlabel 'seconds per frame'\n"
              "set ylabel 'position error (max over frames, / body size)'\n"
              "set title 'Error against cost (%s; the reference, error 0, is not drawn)'\nplot ",
          S->name);
  for (int m = 0; m < nm; m++) fprintf(gp, "'plot_cost.dat' index %d using 1:2 with points pt 7 ps 1.3 title '%s', ", m, methods[m]);
  fprintf(gp, "'plot_pareto.dat' using 1:2 with linespoints lw 2 lc rgb 'black' pt 6 ps 2.2 title 'Pareto front'\n"
              "unset logscale\n");
  /* 2. error against refinement level, with the fitted order */
  for (int k = 0; k < S->n_vary; k++) {
    if (S->vary[k].kind != K_REFINE) continue;
    snprintf(p, sizeof p, "%s/plot_refine_%d.dat", S->out, k);
    d = fopen(p, "w");
    snprintf(p, sizeof p, "%s/plot_refine_successive_%d.dat", S->out, k);
    FILE *ds = fopen(p, "w");
    fprintf(gp, "set output 'error_vs_refine%s%s.png'\nset logscale y\nset key inside top right\nset xtics 1\n"
                "set xlabel '%s (h ~ 2^-level)'\n"
                "set ylabel 'position error (max over frames, / body size)'\n"
                "set title 'Error against refinement (other knobs at the reference)'\nplot ",
            k ? "_" : "", k ? S->vary[k].key : "", S->vary[k].key);
    for (int m = 0; m < nm; m++) {
      order_fit o = fit_knob(S, k, methods[m], grp, &ng);
      if (d) {
        fprintf(d, "# method %s: level pos_err_max\n", methods[m]);
        for (int i = 0; i < ng; i++) {
          const run *r = &S->runs[grp[i]];
          if (fit_point(S, r, k) && r->pos_max > 0)
            fprintf(d, "%s %.9g\n", S->vary[k].vals[r->idx[k]], r->pos_max);
        }
        fprintf(d, "\n\n");
      }
      fprintf(gp, "'plot_refine_%d.dat' index %d using 1:2 with points pt 7 ps 1.3 title '%s: against the reference', ",
              k, m, methods[m]);
      if (isfinite(o.p))
        fprintf(gp, "exp(%.9g) * 2**(-%.9g * x) with lines dt 2 title '%s fit: order %.2f', ", o.logc, o.p, methods[m], o.p);
      int used = 0;
      if (ds) fprintf(ds, "# method %s: level, position error against the next finer level\n", methods[m]);
      double ps = successive_order(S, k, methods[m], &used, ds);
      if (ds) fprintf(ds, "\n\n");
      if (ds && used > 0) {
        char ord[64] = "";
        if (isfinite(ps)) snprintf(ord, sizeof ord, " (order %.2f)", ps);
        fprintf(gp, "'plot_refine_successive_%d.dat' index %d using 1:2 with linespoints pt 5 ps 1.1 title "
                    "'%s: against the next finer level%s', ",
                k, m, methods[m], ord);
      }
    }
    fprintf(gp, "1/0 notitle\nunset logscale\nset key outside right\nset xtics autofreq\n");
    if (d) fclose(d);
    if (ds) fclose(ds);
  }
  /* 3. iterations per step against steps per frame */
  for (int k = 0; k < S->n_vary; k++) {
    if (S->vary[k].kind != K_SPF) continue;
    snprintf(p, sizeof p, "%s/plot_iterations.dat", S->out);
    d = fopen(p, "w");
    for (int m = 0; d && m < nm; m++) {
      ng = group(S, k, methods[m], grp);
      fprintf(d, "# method %s: steps_per_frame newton_per_step cg_per_step\n", methods[m]);
      for (int i = 0; i < ng; i++) {
        const run *r = &S->runs[grp[i]];
        fprintf(d, "%d %.9g %.9g\n", r->spf, r->newton_per_step, r->cg_per_step);
      }
      fprintf(d, "\n\n");
    }
    if (d) fclose(d);
    fprintf(gp, "set output 'iterations_vs_steps.png'\nset format y '%%g'\nset logscale x 2\nset xlabel 'steps per frame'\n"
                "set ylabel 'Newton iterations per step'\nset y2label 'CG iterations per step'\n"
                "set ytics nomirror\nset y2tics\nset logscale y2\nset format y2 '%%g'\n"
                "set title 'Iterations per step (other knobs at the reference)'\nplot ");
    for (int m = 0; m < nm; m++)
      fprintf(gp, "'plot_iterations.dat' index %d using 1:2 with linespoints pt 7 lw 2 title '%s Newton', "
                  "'plot_iterations.dat' index %d using 1:3 axes x1y2 with linespoints pt 6 dt 2 title '%s CG', ",
              m, methods[m], m, methods[m]);
    fprintf(gp, "1/0 notitle\nunset logscale\nunset y2tics\nunset y2label\n");
    break;
  }
  fclose(gp);
  free(grp);
  /* run gnuplot */
  snprintf(p, sizeof p, "%s/plots.log", S->out);
  fflush(stdout);
  fflush(stderr);
  pid_t pid = fork();
  if (pid < 0) {
    snprintf(msg, msg_n, "cannot start gnuplot: %s", strerror(errno));
    return -1;
  }
  if (pid == 0) {
    int fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    if (chdir(S->out)) _exit(126);
    execlp("gnuplot", "gnuplot", "plots.gp", (char *)NULL);
    fprintf(stderr, "cannot execute gnuplot: %s (Debian package gnuplot-nox)\n", strerror(errno));
    _exit(127);
  }
  int status;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    snprintf(msg, msg_n, "gnuplot failed (exit %d); see '%s'", WIFEXITED(status) ? WEXITSTATUS(status) : -1, p);
    return -1;
  }
  return 0;
}

/* Order of knob k from successive levels: the position error d_j of each run
 * of the group against the next finer run of the group (not the reference),
 * d_j ~ C h_j^p (1 - (h_j+1 / h_j)^p), fitted by least squares in log-log with
 * the bracket solved for by fixed-point iteration. Unlike the fit against the
 * reference, whose error at the level next to it is |u_h - u_h/2| and not
 * |u_h - u|, this is unbiased (for halvings, the fit against a reference one
 * level finer reports log2(2^p + 1) from two points). NAN when fewer than two
 * pairs of finished runs. */
static double successive_order(const study *S, int k, const char *method, int *used, FILE *pts) {
  int *grp = malloc(sizeof(int) * (S->n_runs + 1)), ng = group(S, k, method, grp);
  /* coarse to fine */
  for (int i = 1; i < ng; i++)
    for (int j = i; j > 0 && knob_h(S, &S->runs[grp[j]], k) > knob_h(S, &S->runs[grp[j - 1]], k); j--) {
      int t = grp[j];
      grp[j] = grp[j - 1];
      grp[j - 1] = t;
    }
  double *h = malloc(sizeof(double) * (ng + 1)), *d = malloc(sizeof(double) * (ng + 1)),
         *rho = malloc(sizeof(double) * (ng + 1)), *y = malloc(sizeof(double) * (ng + 1));
  int m = 0;
  for (int i = 0; i + 1 < ng; i++) {
    const run *a = &S->runs[grp[i]], *b = &S->runs[grp[i + 1]];
    double ha = knob_h(S, a, k), hb = knob_h(S, b, k);
    if (a->exit_code != 0 || b->exit_code != 0 || !(hb < ha)) continue;
    run tmp = *a;
    int64_t off_b[64];
    run_offsets(S, b->body_refine, off_b);
    if (compare_run(S, &tmp, b->dir, S->cmp, off_b, S->vscale, S->direct) || !(tmp.pos_max > 0) ||
        !isfinite(tmp.pos_max))
      continue;
    h[m] = ha;
    d[m] = tmp.pos_max;
    if (pts) fprintf(pts, "%s %.9g\n", S->vary[k].vals[a->idx[k]], tmp.pos_max);
    rho[m] = hb / ha;
    m++;
  }
  double logc, p = fit_order(m, h, d, &logc, used);
  for (int it = 0; it < 100 && isfinite(p) && p > 0; it++) {
    for (int j = 0; j < m; j++) y[j] = d[j] / (1 - pow(rho[j], p));
    double q = fit_order(m, h, y, &logc, used);
    if (!isfinite(q) || !(q > 0)) break;
    int done = fabs(q - p) < 1e-10;
    p = q;
    if (done) break;
  }
  free(h);
  free(d);
  free(rho);
  free(y);
  free(grp);
  return p;
}

static void print_summary(const study *S, const char *ref_desc) {
  const char *methods[256];
  int nm = n_methods(S, methods);
  int n_failed = 0;
  for (int i = 0; i < S->n_runs; i++) n_failed += S->runs[i].exit_code != 0;
  printf("\nstudy %s: %d runs (%d failed), body size %.4g m; reference: %s\n", S->name, S->n_runs, n_failed, S->size,
         ref_desc);
  printf("cheapest setting (by s/frame) within a position error (max over frames, / body size) of:\n");
  static const double thr[3] = {1e-2, 1e-3, 1e-4};
  static const char *thr_name[3] = {"1%", "0.1%", "0.01%"};
  for (int m = 0; m < nm; m++) {
    printf("  method %s\n", methods[m]);
    for (int t = 0; t < 3; t++) {
      int best = -1;
      for (int i = 0; i < S->n_runs; i++) {
        const run *r = &S->runs[i];
        if (strcmp(r->method, methods[m]) || r->exit_code != 0 || !(r->pos_max <= thr[t]) || !isfinite(r->s_per_frame))
          continue;
        if (best < 0 || r->s_per_frame < S->runs[best].s_per_frame) best = i;
      }
      if (best < 0) printf("    %-6s none\n", thr_name[t]);
      else
        printf("    %-6s %s  (%.4g s/frame, error %.3g%%)\n", thr_name[t], S->runs[best].name, S->runs[best].s_per_frame,
               100 * S->runs[best].pos_max);
    }
  }
  int *grp = malloc(sizeof(int) * (S->n_runs + 1)), ng;
  int any_t = 0, any_s = 0;
  for (int k = 0; k < S->n_vary; k++) {
    const vary *v = &S->vary[k];
    int is_t = is_time_knob(v), is_s = v->kind == K_REFINE;
    if (!is_t && !is_s) continue;
    any_t |= is_t;
    any_s |= is_s;
    for (int m = 0; m < nm; m++) {
      order_fit o = fit_knob(S, k, methods[m], grp, &ng);
      if (isfinite(o.p))
        printf("order in %s (error ~ %s^p, vs %s): method %s p = %.3f over %d runs\n", is_t ? "time" : "space",
               is_t ? "dt" : "h", v->key, methods[m], o.p, o.used);
      else
        printf("order in %s (vs %s): method %s: not measurable (fewer than 2 runs with a positive error)\n",
               is_t ? "time" : "space", v->key, methods[m]);
      int used = 0;
      double ps = successive_order(S, k, methods[m], &used, NULL);
      if (isfinite(ps))
        printf("  from successive levels (each run against the next finer): p = %.3f over %d pairs\n", ps, used);
    }
  }
  if (!any_t) printf("order in time: steps_per_frame not varied\n");
  if (!any_s) printf("order in space: refine not varied\n");
  free(grp);
}

/* ---- the command -------------------------------------------------------- */

static void study_free(study *S) {
  for (int k = 0; k < S->n_vary; k++) {
    for (int j = 0; j < S->vary[k].n; j++) free(S->vary[k].vals[j]);
    free(S->vary[k].vals);
  }
  for (int i = 0; S->runs && i < S->n_runs; i++) {
    for (int j = 0; j < S->runs[i].n_sets; j++) free(S->runs[i].sets[j]);
    free(S->runs[i].sets);
    free(S->runs[i].body_refine);
  }
  free(S->runs);
  free(S->counts);
  free(S->user_sets);
}

int bs_cmd_study(int argc, char **argv) {
  study S;
  memset(&S, 0, sizeof S);
  S.jobs = 1;
  S.ref = -1;
  S.user_sets = calloc((size_t)argc + 1, sizeof(char *));
  const char *out = NULL;
  int rc = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      fputs(study_help, stdout);
      goto done;
    }
    if (!strncmp(a, "--", 2)) {
      char flag[64];
      const char *val = NULL;
      const char *eq = strchr(a, '=');
      if (eq) {
        snprintf(flag, sizeof flag, "%.*s", (int)(eq - a), a);
        val = eq + 1;
      } else {
        snprintf(flag, sizeof flag, "%s", a);
        if (i + 1 < argc) val = argv[++i];
      }
      int known = !strcmp(flag, "--vary") || !strcmp(flag, "--set") || !strcmp(flag, "--reference") ||
                  !strcmp(flag, "--jobs") || !strcmp(flag, "--out");
      if (!known) {
        rc = bs_app_usage_error("study", "unknown flag '%s'", flag);
        goto done;
      }
      if (!val) {
        rc = bs_app_usage_error("study", "flag %s needs a value", flag);
        goto done;
      }
      if (!strcmp(flag, "--vary")) {
        if (S.n_vary == MAX_VARY) {
          rc = bs_app_usage_error("study", "at most %d --vary flags", MAX_VARY);
          goto done;
        }
        vary *v = &S.vary[S.n_vary++];
        if ((rc = parse_vary(val, v))) goto done;
        for (int k = 0; k + 1 < S.n_vary; k++)
          if (!strcmp(S.vary[k].path, v->path) && !(v->kind == K_REFINE && v->body != S.vary[k].body)) {
            rc = bs_app_usage_error("study", "bad --vary '%s': %s is varied twice", val, v->key);
            goto done;
          }
      } else if (!strcmp(flag, "--set")) {
        if (!strchr(val, '=')) {
          rc = bs_app_usage_error("study", "bad --set '%s': expected key.path=value", val);
          goto done;
        }
        S.user_sets[S.n_user++] = val;
      } else if (!strcmp(flag, "--reference")) {
        S.ref_dir = strcmp(val, "auto") ? val : NULL;
      } else if (!strcmp(flag, "--jobs")) {
        if (bs_app_parse_int(val, 1, 1024, &S.jobs)) {
          rc = bs_app_usage_error("study", "--jobs must be an integer in 1..1024, got '%s'", val);
          goto done;
        }
      } else {
        out = val;
      }
    } else {
      if (S.scene_path) {
        rc = bs_app_usage_error("study", "unexpected argument '%s'", a);
        goto done;
      }
      S.scene_path = a;
    }
  }
  if (!S.scene_path) {
    rc = bs_app_usage_error("study", "missing SCENE");
    goto done;
  }
  if (S.n_vary == 0) {
    rc = bs_app_usage_error("study", "nothing to vary: give at least one --vary KEY=v1,v2,...");
    goto done;
  }
  if (S.ref_dir) {
    char p[1400];
    snprintf(p, sizeof p, "%s/state.bin", S.ref_dir);
    if (access(p, R_OK)) {
      rc = bs_app_usage_error("study", "--reference '%s': no state.bin in that folder (a study run folder)", S.ref_dir);
      goto done;
    }
  }
  {
    const char *base = strrchr(S.scene_path, '/');
    base = base ? base + 1 : S.scene_path;
    snprintf(S.name, sizeof S.name, "%s", base);
    char *dot = strrchr(S.name, '.');
    if (dot && dot != S.name) *dot = 0;
    if (out) snprintf(S.out, sizeof S.out, "%s", out);
    else snprintf(S.out, sizeof S.out, "out/study/%s", S.name);
  }

  bs_error err;
  bs_error_clear(&err);
  /* the base scene: the user's --set applied */
  {
    bs_scene *sc = NULL;
    if (bs_scene_load(S.scene_path, S.n_user, S.user_sets, &sc, &err)) {
      fprintf(stderr, "bigstep study: %s\n", err.msg);
      rc = BS_EXIT_FAIL;
      goto done;
    }
    S.n_bodies = sc->n_bodies;
    bs_scene_destroy(&sc);
  }
  if (S.n_bodies > 64) {
    fprintf(stderr, "bigstep study: %s: at most 64 bodies, got %d\n", S.scene_path, S.n_bodies);
    rc = BS_EXIT_FAIL;
    goto done;
  }
  for (int k = 0; k < S.n_vary; k++)
    if (S.vary[k].kind == K_REFINE && S.vary[k].body >= S.n_bodies) {
      rc = bs_app_usage_error("study", "bad --vary '%s': the scene has %d bodies", S.vary[k].key, S.n_bodies);
      goto done;
    }
  /* the cross product, each run's settings validated through the scene loader */
  S.n_runs = 1;
  for (int k = 0; k < S.n_vary; k++) {
    if (S.n_runs > 100000 / S.vary[k].n) {
      rc = bs_app_usage_error("study", "too many runs (more than 100000)");
      goto done;
    }
    S.n_runs *= S.vary[k].n;
  }
  S.runs = calloc((size_t)S.n_runs, sizeof(run));
  int any_refine = 0;
  for (int k = 0; k < S.n_vary; k++) any_refine |= S.vary[k].kind == K_REFINE;
  for (int i = 0; i < S.n_runs; i++) {
    run *r = &S.runs[i];
    int q = i;
    for (int k = S.n_vary - 1; k >= 0; k--) {
      r->idx[k] = q % S.vary[k].n;
      q /= S.vary[k].n;
    }
    build_sets(&S, r);
    bs_scene *sc = NULL;
    if (bs_scene_load(S.scene_path, r->n_sets, (const char *const *)r->sets, &sc, &err)) {
      rc = bs_app_usage_error("study", "run %s: %s", r->name, err.msg);
      goto done;
    }
    r->frames = sc->frames;
    r->spf = sc->steps_per_frame;
    r->fps = sc->fps;
    r->is_static = sc->mode == BS_MODE_STATIC;
    snprintf(r->method, sizeof r->method, "%s", bs_method_name(sc->solver.method));
    r->body_refine = calloc((size_t)S.n_bodies, sizeof(int));
    for (int b = 0; b < S.n_bodies; b++) {
      r->body_refine[b] = sc->bodies[b].refine;
      if (any_refine && sc->bodies[b].reorder != BS_ORDER_NONE) {
        bs_scene_destroy(&sc);
        rc = bs_app_usage_error("study", "bodies.%d.reorder must be none when refine is varied (runs are compared "
                                "through the vertices refinement keeps)", b);
        goto done;
      }
    }
    bs_scene_destroy(&sc);
    int fin = 1;
    for (int k = 0; k < S.n_vary; k++) fin &= r->idx[k] == S.vary[k].finest;
    if (fin && !S.ref_dir) {
      r->is_ref = 1;
      S.ref = i;
    }
  }
  if (body_geometry(&S, &err)) {
    fprintf(stderr, "bigstep study: %s\n", err.msg);
    rc = BS_EXIT_FAIL;
    goto done;
  }
  if (mkdir_p(S.out)) {
    fprintf(stderr, "bigstep study: cannot create folder '%s'\n", S.out);
    rc = BS_EXIT_FAIL;
    goto done;
  }
  /* what is left to run */
  int n_pending = 0;
  for (int i = 0; i < S.n_runs; i++) {
    run *r = &S.runs[i];
    char args[8192];
    args_line(r, args, sizeof args);
    r->pending = !(read_done(r, args) == 0 && frames_complete(r));
    n_pending += r->pending;
  }
  printf("study %s: %d runs, %d to do (%d done before), in %s\n", S.name, S.n_runs, n_pending, S.n_runs - n_pending, S.out);
  fflush(stdout);
  run_all(&S, n_pending);

  /* results */
  for (int i = 0; i < S.n_runs; i++) read_costs(&S.runs[i]);
  const char *ref_dir = S.ref_dir ? S.ref_dir : S.runs[S.ref].dir;
  char ref_desc[1600];
  if (S.ref_dir) snprintf(ref_desc, sizeof ref_desc, "the run in %s", S.ref_dir);
  else snprintf(ref_desc, sizeof ref_desc, "%s", S.runs[S.ref].name);
  {
    /* compared vertex blocks: per body, its vertex count at the coarsest level in the study */
    int64_t cmp[64], off_ref[64];
    int ref_refine[64], direct = 0;
    for (int b = 0; b < S.n_bodies; b++) {
      int mn = S.runs[0].body_refine[b];
      for (int i = 1; i < S.n_runs; i++)
        if (S.runs[i].body_refine[b] < mn) mn = S.runs[i].body_refine[b];
      ref_refine[b] = S.ref_dir ? 0 : S.runs[S.ref].body_refine[b];
      cmp[b] = body_vertices(S.counts[b], mn);
    }
    if (S.ref_dir) {
      /* the given reference: find a uniform refinement level that explains its vertex count */
      state_file sf;
      int found = 0;
      if (state_open(S.ref_dir, &sf) == 0) {
        for (int lvl = 0; lvl <= 10 && !found; lvl++) {
          for (int b = 0; b < S.n_bodies; b++) ref_refine[b] = lvl;
          if (run_offsets(&S, ref_refine, off_ref) == sf.n) found = 1;
        }
        if (!found) {
          for (int b = 0; b < S.n_bodies; b++) ref_refine[b] = S.runs[0].body_refine[b];
          found = run_offsets(&S, ref_refine, off_ref) == sf.n;
        }
        state_close(&sf);
      }
      if (!found) direct = 1; /* no refinement relation: same vertex count required */
      for (int b = 0; found && b < S.n_bodies; b++)
        if (cmp[b] > body_vertices(S.counts[b], ref_refine[b])) cmp[b] = body_vertices(S.counts[b], ref_refine[b]);
    }
    run_offsets(&S, ref_refine, off_ref);
    double vscale = max_speed(ref_dir);
    if (!(vscale > 0)) vscale = 1.0;
    memcpy(S.cmp, cmp, sizeof cmp);
    S.vscale = vscale;
    S.direct = direct;
    int n_bad = 0;
    for (int i = 0; i < S.n_runs; i++)
      if (compare_run(&S, &S.runs[i], ref_dir, cmp, off_ref, vscale, direct)) n_bad++;
    if (n_bad)
      fprintf(stderr, "bigstep study: %d run(s) could not be compared with the reference (failed run, no common "
                      "frame times or unmatched vertices); their error columns are nan\n", n_bad);
  }
  /* Pareto front over the runs that finished cleanly */
  for (int i = 0; i < S.n_runs; i++) {
    run *a = &S.runs[i];
    if (a->exit_code != 0 || !isfinite(a->pos_max) || !isfinite(a->s_per_frame)) continue;
    int dominated = 0;
    for (int j = 0; j < S.n_runs && !dominated; j++) {
      const run *b = &S.runs[j];
      if (j == i || b->exit_code != 0 || !isfinite(b->pos_max) || !isfinite(b->s_per_frame)) continue;
      if (b->s_per_frame <= a->s_per_frame && b->pos_max <= a->pos_max &&
          (b->s_per_frame < a->s_per_frame || b->pos_max < a->pos_max))
        dominated = 1;
    }
    a->pareto = !dominated;
  }
  if (write_csv(&S)) {
    fprintf(stderr, "bigstep study: cannot write '%s/study.csv'\n", S.out);
    rc = BS_EXIT_FAIL;
    goto done;
  }
  char msg[1600] = "";
  int plots = make_plots(&S, msg, sizeof msg);
  print_summary(&S, ref_desc);
  printf("wrote %s/study.csv%s\n", S.out, plots ? "" : " and the PNG plots");
  if (plots) {
    fprintf(stderr, "bigstep study: plots: %s\n", msg);
    rc = BS_EXIT_FAIL;
  }
done:
  study_free(&S);
  return rc;
}
