/* bigstep study SCENE --vary KEY=v1,v2,... — speed against accuracy, measured.
 *
 * The study engine (plan, metrics, report) is study/bs_study.h; this command
 * parses the arguments, runs every pending run as a child `bigstep run` (this
 * executable, /proc/self/exe) in its own folder, at most --jobs at a time,
 * with a progress line and a done marker per run, runs gnuplot on the plots
 * the engine writes and prints the engine's summary. A folder holding a
 * complete frames.csv and a done marker made with the same settings is not
 * run again. */
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
#include "bs_study.h"

static const char *study_help =
    "usage: bigstep study SCENE --vary KEY=v1,v2,... [--vary ...] [--set key.path=value]...\n"
    "                           [--qoi NAME]... [--reference auto|RUN_DIR] [--jobs N] [--out DIR]\n"
    "                           [--run-budget SECONDS] [--force]\n"
    "\n"
    "Runs every combination of the varied settings (`bigstep run --quiet` in its own\n"
    "folder under DIR, default out/study/<scene name>; a folder holding a complete\n"
    "frames.csv and a 'done' marker made from the same scene content (the scene\n"
    "file, the settings and the mesh files' bytes) is not run again), compares each run with the\n"
    "reference at common frame times, and writes study.csv, PNG plots (gnuplot) and\n"
    "a summary: each quantity of interest with its GCI, the observed orders of\n"
    "convergence in space and time, and ONE verdict: the runs ranked by cost with\n"
    "their error in the judged quantity, and the cheapest within 1%, 0.1%, 0.01%.\n"
    "  --vary KEY=v1,v2,...  any scene key path (numbers or words: solver.linear=cg,pcg)\n"
    "                        or a shorthand: steps_per_frame (time.steps_per_frame),\n"
    "                        refine (bodies.*.refine, every body), element\n"
    "                        (bodies.*.element, every body: tet4,tet10), integrator\n"
    "                        (solver.integrator), method (solver.method), tolerance\n"
    "                        (solver.tolerance)\n"
    "  --set key.path=value  any scene key, as in `bigstep run` (applied to every run)\n"
    "  --reference auto      the finest setting of every varied knob [default]: largest\n"
    "                        steps_per_frame / refine / fps, smallest tolerance / dt,\n"
    "                        method optimization (else the first listed); the last listed\n"
    "                        value of any other key\n"
    "  --reference RUN_DIR   a run folder holding frames.csv and state.bin\n"
    "  --qoi NAME            a quantity of interest (a qoi.csv column) [default: the\n"
    "                        scene's own \"qoi\", if it defines any]; --qoi none: judge\n"
    "                        the position error. Per run its error against the\n"
    "                        reference; with three or more levels of a refine or time\n"
    "                        knob its observed order, Richardson extrapolation and GCI\n"
    "                        (Roache, Fs 1.25)\n"
    "  --run-budget SECONDS  wall seconds a run may take before it is stopped and\n"
    "                        marked timeout [900]\n"
    "  --force               rerun every run, cached or not\n"
    "  --jobs N              runs in parallel [1] (each child gets OMP_NUM_THREADS =\n"
    "                        cores / N unless set)\n"
    "  --out DIR             the study folder\n"
    "The verdict judges the quantities of interest at the last frame (a run's error:\n"
    "the largest of theirs), each against its Richardson extrapolation along the\n"
    "first refine (else time) knob with a monotone sequence of three levels, else\n"
    "against the reference; with no quantity, the position error. It ranks every run\n"
    "that finished, across all knobs; the reference too when a quantity is extrapolated.\n"
    "Errors: position = RMS over the compared vertices of x - x_ref over what the\n"
    "reference moved (the max over frames of its RMS displacement from its first\n"
    "frame; the body size if it did not move); velocity = RMS of v - v_ref over the\n"
    "reference's largest speed (1 m/s if it is 0); both the max over frames and at\n"
    "the last frame. A quantity: |q - target| over its magnitude (a position: its\n"
    "change from the first frame).\n"
    "Energy drift = max |total(t) - total(0)| over max(|total(0)|, max kinetic) (1 J if 0).\n"
    "Orders: the slope of log error against log h (h = 2^-refine or dt) over the runs\n"
    "whose other knobs are at the reference; and from successive levels (each run\n"
    "against the next finer one), which the nearness of the reference does not bias.\n"
    "A failed run is recorded (failed column) and does not stop the study.\n";

/* The parsed command line. */
typedef struct study_args {
  const char *scene, *ref_dir, *out; /* ref_dir NULL: auto */
  int n_knobs;
  bs_study_knob knobs[BS_STUDY_MAX_KNOBS];
  int n_user;
  const char **user_sets;
  int jobs, help, force;
  double budget;  /* s: a run's wall-clock budget */
  int n_qoi, no_qoi; /* no_qoi: --qoi none */
  const char *qoi[BS_STUDY_MAX_QOI];
} study_args;

/* A run as a process. */
typedef struct slot {
  int pending;
  pid_t pid;
  double t0;
  double term_at;  /* when SIGTERM was sent after the budget (0: not) */
} slot;

/* ---- argument parsing --------------------------------------------------- */

static int add_vary(study_args *A, const char *val) {
  if (A->n_knobs == BS_STUDY_MAX_KNOBS) return bs_app_usage_error("study", "at most %d --vary flags", BS_STUDY_MAX_KNOBS);
  bs_error err;
  bs_study_knob *v = &A->knobs[A->n_knobs];
  if (bs_study_knob_parse(val, v, &err)) return bs_app_usage_error("study", "bad --vary %s", err.msg);
  A->n_knobs++;
  for (int k = 0; k + 1 < A->n_knobs; k++)
    if (bs_study_knob_same(&A->knobs[k], v))
      return bs_app_usage_error("study", "bad --vary '%s': %s is varied twice", val, v->key);
  return 0;
}

/* One flag with its value. */
static int parse_flag(study_args *A, const char *flag, const char *val) {
  if (!strcmp(flag, "--vary")) return add_vary(A, val);
  if (!strcmp(flag, "--set")) {
    if (!strchr(val, '=')) return bs_app_usage_error("study", "bad --set '%s': expected key.path=value", val);
    A->user_sets[A->n_user++] = val;
  } else if (!strcmp(flag, "--reference")) {
    A->ref_dir = strcmp(val, "auto") ? val : NULL;
  } else if (!strcmp(flag, "--qoi") && !strcmp(val, "none")) {
    A->no_qoi = 1;
  } else if (!strcmp(flag, "--qoi")) {
    if (A->n_qoi == BS_STUDY_MAX_QOI) return bs_app_usage_error("study", "at most %d --qoi flags", BS_STUDY_MAX_QOI);
    A->qoi[A->n_qoi++] = val;
  } else if (!strcmp(flag, "--run-budget")) {
    if (bs_parse_double(val, &A->budget) || !(A->budget > 0))
      return bs_app_usage_error("study", "--run-budget must be a positive number of seconds, got '%s'", val);
  } else if (!strcmp(flag, "--jobs")) {
    if (bs_parse_int(val, 1, 1024, &A->jobs))
      return bs_app_usage_error("study", "--jobs must be an integer in 1..1024, got '%s'", val);
  } else {
    A->out = val;
  }
  return 0;
}

/* The flag at argv[*i]: "--flag value" or "--flag=value" (bs_app_flag_value). */
static int parse_option(study_args *A, int argc, char **argv, int *i) {
  char fbuf[64];
  const char *flag, *val;
  const int missing = bs_app_flag_value(argc, argv, i, fbuf, sizeof fbuf, &flag, &val);
  int known = !strcmp(flag, "--vary") || !strcmp(flag, "--set") || !strcmp(flag, "--reference") ||
              !strcmp(flag, "--jobs") || !strcmp(flag, "--out") || !strcmp(flag, "--qoi") ||
              !strcmp(flag, "--run-budget");
  if (!known) return bs_app_usage_error("study", "unknown flag '%s'", flag);
  if (missing) return bs_app_usage_error("study", "flag %s needs a value", flag);
  return parse_flag(A, flag, val);
}

static int parse_args(study_args *A, int argc, char **argv) {
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int rc = 0;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      A->help = 1;
      return 0;
    }
    if (!strcmp(a, "--force")) {
      A->force = 1;
      continue;
    }
    if (!strncmp(a, "--", 2)) rc = parse_option(A, argc, argv, &i);
    else if (A->scene) rc = bs_app_usage_error("study", "unexpected argument '%s'", a);
    else A->scene = a;
    if (rc) return rc;
  }
  if (!A->scene) return bs_app_usage_error("study", "missing SCENE");
  if (A->n_knobs == 0) return bs_app_usage_error("study", "nothing to vary: give at least one --vary KEY=v1,v2,...");
  if (A->no_qoi && A->n_qoi) return bs_app_usage_error("study", "--qoi none with --qoi NAME: give one or the other");
  if (A->ref_dir) {
    char p[BS_STUDY_FILE_PATH];
    bs_error err;
    if (bs_study_file_path(A->ref_dir, "state.bin", p, &err))
      return bs_app_usage_error("study", "--reference: %s", err.msg);
    if (access(p, R_OK))
      return bs_app_usage_error("study", "--reference '%s': no state.bin in that folder (a study run folder)",
                                A->ref_dir);
  }
  return 0;
}

/* ---- done markers ------------------------------------------------------- */

/* The "args" line of the done marker: the run's settings, one string. */
static void args_line(const bs_study_run *r, char *buf, size_t n) {
  size_t k = 0;
  buf[0] = 0;
  for (int i = 0; i < r->n_sets && k < n; i++) k += (size_t)snprintf(buf + k, n - k, "%s%s", i ? " " : "", r->sets[i]);
}

/* Reads the done marker; 0 when present and made from the same scene
 * content (its key line equals key). */
static int read_done(bs_study_run *r, const char *key) {
  char p[BS_STUDY_FILE_PATH];
  bs_error err;
  if (bs_study_file_path(r->dir, "done", p, &err)) return -1;
  FILE *f = fopen(p, "r");
  if (!f) return -1;
  char line[8192];
  int ok_key = 0;
  r->exit_code = -1;
  while (fgets(line, sizeof line, f)) {
    line[strcspn(line, "\n")] = 0;
    if (!strncmp(line, "exit ", 5)) r->exit_code = atoi(line + 5);
    else if (!strncmp(line, "maxrss_kib ", 11)) r->maxrss_kib = atol(line + 11);
    else if (!strncmp(line, "wall ", 5)) r->wall = atof(line + 5);
    else if (!strncmp(line, "timeout ", 8)) r->timed_out = atoi(line + 8);
    else if (!strncmp(line, "key ", 4)) ok_key = !strcmp(line + 4, key);
  }
  fclose(f);
  return ok_key && r->exit_code >= 0 ? 0 : -1;
}

static void write_done(const bs_study *S, const bs_study_run *r) {
  char p[BS_STUDY_FILE_PATH], args[8192], key[BS_STUDY_KEY_LEN + 1] = "none";
  bs_error err;
  if (bs_study_file_path(r->dir, "done", p, &err)) {
    fprintf(stderr, "bigstep study: %s\n", err.msg);
    return;
  }
  args_line(r, args, sizeof args);
  if (bs_study_run_key(S, r, key, &err)) fprintf(stderr, "bigstep study: %s (the run will not be reused)\n", err.msg);
  FILE *f = fopen(p, "w");
  if (!f) return;
  fprintf(f, "exit %d\nmaxrss_kib %ld\nwall %.6f\ntimeout %d\nkey %s\nargs %s\n", r->exit_code, r->maxrss_kib,
          r->wall, r->timed_out, key, args);
  if (fclose(f)) fprintf(stderr, "bigstep study: cannot write '%s'\n", p);
}

/* Marks the runs left to do (all with force); returns how many. A run whose
 * key cannot be computed (an unreadable mesh) is run, and fails there. */
static int mark_pending(bs_study *S, slot *sl, int force) {
  int n_pending = 0;
  for (int i = 0; i < S->n_runs; i++) {
    bs_study_run *r = &S->runs[i];
    char key[BS_STUDY_KEY_LEN + 1];
    bs_error err;
    int have_key = bs_study_run_key(S, r, key, &err) == 0;
    sl[i].pending = force || !have_key || !(read_done(r, key) == 0 && (r->timed_out || bs_study_run_complete(r) ||
                                                                       r->exit_code != 0));
    if (sl[i].pending) r->timed_out = 0;
    n_pending += sl[i].pending;
  }
  return n_pending;
}

/* ---- the process pool --------------------------------------------------- */

static void fmt_time(double s, char *buf, size_t n) {
  long t = (long)(s + 0.5);
  if (t >= 3600) snprintf(buf, n, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else snprintf(buf, n, "%ld:%02ld", t / 60, t % 60);
}

static int start_run(const bs_study *S, bs_study_run *r, slot *sl, const char *omp) {
  char p[BS_STUDY_FILE_PATH];
  bs_error err;
  if (bs_study_file_path(r->dir, "done", p, &err)) {
    fprintf(stderr, "bigstep study: %s\n", err.msg);
    return -1;
  }
  unlink(p);
  if (bs_mkdir_p(r->dir, &err)) {
    fprintf(stderr, "bigstep study: cannot create folder '%s'\n", r->dir);
    return -1;
  }
  bs_study_file_path(r->dir, "run.log", p, &err); /* fits: "done" did */
  char **argv = calloc((size_t)(2 * r->n_sets + 8), sizeof(char *));
  int a = 0;
  argv[a++] = "bigstep";
  argv[a++] = "run";
  argv[a++] = (char *)S->scene_path;
  argv[a++] = "--quiet";
  argv[a++] = "--replace"; /* a run that is not reused is run again from scratch */
  if (bs_mesh_geo_system_calls()) argv[a++] = "--allow-geo-system";
  for (int i = 0; i < r->n_sets; i++) {
    argv[a++] = "--set";
    argv[a++] = r->sets[i];
  }
  argv[a] = NULL;
  fflush(stdout);
  fflush(stderr);
  sl->t0 = bs_seconds();
  sl->term_at = 0;
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
  sl->pid = pid;
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

/* Records the end of the child pid (status, resources): its done marker.
 * Returns 1 when pid was one of the runs. */
static int reap(bs_study *S, slot *sl, pid_t pid, int status, const struct rusage *ru) {
  for (int i = 0; i < S->n_runs; i++) {
    bs_study_run *r = &S->runs[i];
    if (!sl[i].pending || sl[i].pid != pid) continue;
    sl[i].pid = 0;
    r->wall = bs_seconds() - sl[i].t0;
    r->maxrss_kib = ru->ru_maxrss;
    r->exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    write_done(S, r);
    return 1;
  }
  return 0;
}

/* Stops the runs past their budget: SIGTERM, then SIGKILL 5 s later. */
static void enforce_budget(bs_study *S, slot *sl, double budget) {
  double now = bs_seconds();
  for (int i = 0; i < S->n_runs; i++) {
    if (!sl[i].pending || sl[i].pid <= 0) continue;
    if (!sl[i].term_at && now - sl[i].t0 > budget) {
      S->runs[i].timed_out = 1;
      sl[i].term_at = now;
      kill(sl[i].pid, SIGTERM);
    } else if (sl[i].term_at && now - sl[i].term_at > 5.0) {
      kill(sl[i].pid, SIGKILL);
    }
  }
}

/* Runs the pending runs, at most jobs at a time, each within budget seconds. */
static int run_all(bs_study *S, slot *sl, int jobs, int n_pending, double budget) {
  if (n_pending == 0) return 0;
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  char omp[16];
  const char *ompp = NULL;
  if (jobs > 1) {
    long t = cores / jobs;
    snprintf(omp, sizeof omp, "%ld", t < 1 ? 1 : t);
    ompp = omp;
  }
  double t0 = bs_seconds();
  int next = 0, running = 0, done = 0, rc = 0;
  progress(0, n_pending, t0, 0);
  while (done < n_pending) {
    while (running < jobs && next < S->n_runs) {
      int i = next++;
      if (!sl[i].pending) continue;
      if (start_run(S, &S->runs[i], &sl[i], ompp)) {
        S->runs[i].exit_code = 127;
        done++;
        rc = -1;
        continue;
      }
      running++;
    }
    if (!running) break;
    int status;
    struct rusage ru;
    pid_t pid = wait4(-1, &status, WNOHANG, &ru);
    if (pid == 0) {
      enforce_budget(S, sl, budget);
      usleep(20000);
      continue;
    }
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    if (reap(S, sl, pid, status, &ru)) {
      running--;
      done++;
      progress(done, n_pending, t0, done == n_pending);
    }
  }
  return rc;
}

/* ---- gnuplot ------------------------------------------------------------ */

/* Runs gnuplot on plots.gp in the study folder (its output in plots.log). */
static int run_gnuplot(const bs_study *S, char *msg, size_t msg_n) {
  char p[BS_STUDY_FILE_PATH];
  bs_error err;
  if (bs_study_file_path(S->out, "plots.log", p, &err)) {
    snprintf(msg, msg_n, "%s", err.msg);
    return -1;
  }
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

/* ---- the command -------------------------------------------------------- */

/* The study planned from the arguments: a usage error (2) for a bad knob
 * or run setting, 1 for a scene or mesh that cannot be read. */
static int plan(const study_args *A, bs_study **S) {
  bs_error err;
  bs_error_clear(&err);
  bs_study_opts o = {.scene = A->scene, .n_sets = A->n_user, .sets = A->user_sets, .n_knobs = A->n_knobs,
                     .knobs = A->knobs, .reference = A->ref_dir, .out = A->out, .n_qoi = A->n_qoi,
                     .qoi = A->qoi, .no_scene_qoi = A->no_qoi};
  if (bs_study_create(&o, S, &err)) {
    fprintf(stderr, "bigstep study: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  if (bs_study_check_bodies(*S, &err)) return bs_app_usage_error("study", "bad --vary %s", err.msg);
  if (bs_study_plan(*S, &err)) return bs_app_usage_error("study", "%s", err.msg);
  if (bs_study_measure_bodies(*S, &err)) {
    fprintf(stderr, "bigstep study: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  if (bs_mkdir_p((*S)->out, &err)) {
    fprintf(stderr, "bigstep study: cannot create folder '%s'\n", (*S)->out);
    return BS_EXIT_FAIL;
  }
  return 0;
}

/* ---- the verdict -------------------------------------------------------- */

#define RANKED_MAX 30 /* runs listed in the ranking; the rest are in study.csv */

/* What the verdict judged, and against what. */
static void print_judged(const bs_study *S, const bs_study_verdict *v) {
  if (!v->on_qoi) {
    printf("verdict: judged on the position error (RMS |x - x_ref| over %s, max over frames) against the "
           "reference %s; %s\n",
           S->disp > 1e-12 * S->size ? "what the reference moved" : "the body size",
           S->ref >= 0 ? S->runs[S->ref].name : S->ref_dir,
           S->n_qoi ? "the quantities of interest could not be read from the runs' qoi.csv"
                    : "no quantity of interest (the scene defines none, or --qoi none)");
    return;
  }
  printf("verdict: judged on");
  for (int i = 0; i < v->n_judged; i++) printf("%s %s", i ? "," : "", S->qoi[v->judged[i].qoi]);
  printf(" at the last frame%s\n", v->n_judged > 1 ? " (a run's error: the largest of theirs)" : "");
  for (int i = 0; i < v->n_judged; i++) {
    const bs_study_judged *j = &v->judged[i];
    if (j->extrapolated)
      printf("  %s against its Richardson extrapolation along %s (method %s): %.9g; error |q - q_ext| / %.4g; "
             "observed order %.4g, GCI_fine %.3g%%, %s\n",
             S->qoi[j->qoi], S->knobs[j->knob].key, v->method, j->target, j->scale, j->gci.p, 100 * j->gci.gci_fine,
             j->gci.status == BS_GCI_CONVERGED        ? "converged"
             : fabs(j->gci.asymptotic - 1) < 0.1 ? "in the asymptotic range"
                                                   : "not yet asymptotic: the extrapolation is an estimate");
    else if (j->knob >= 0 && j->gci.status != BS_GCI_OK)
      printf("  %s against the reference's value %.9g (its sequence along %s is %s: nothing to extrapolate); "
             "error |q - q_ref| / %.4g\n",
             S->qoi[j->qoi], j->target, S->knobs[j->knob].key, bs_gci_status_name(j->gci.status), j->scale);
    else if (j->knob >= 0)
      printf("  %s against the reference's value %.9g (its extrapolation along %s, %.9g, has observed order %.3g < "
             "%g: not trusted); error |q - q_ref| / %.4g\n",
             S->qoi[j->qoi], j->target, S->knobs[j->knob].key, j->gci.extrapolated, j->gci.p, BS_STUDY_MIN_ORDER,
             j->scale);
    else
      printf("  %s against the reference's value %.9g (no monotone refinement or time sequence of three levels to "
             "extrapolate); error |q - q_ref| / %.4g\n",
             S->qoi[j->qoi], j->target, j->scale);
  }
}

/* A run's error and what set it, "nan" when not measured. */
static void print_error(const bs_study *S, const bs_study_run *r) {
  if (!isfinite(r->verdict_err)) printf("error not measured");
  else printf("error %.3g%%", 100 * r->verdict_err);
  if (S->verdict.on_qoi && r->verdict_by >= 0 && S->verdict.n_judged > 1) printf(" (%s)", S->qoi[r->verdict_by]);
}

/* Whether cost a ranks before cost b (an unknown cost ranks last). */
static int cheaper(double a, double b) { return isfinite(a) && (!isfinite(b) || a < b); }

/* The runs by cost (s/frame, unknown last) with their errors. */
static void print_ranking(const bs_study *S, const bs_study_verdict *v) {
  int *ord = malloc(sizeof(int) * ((size_t)S->n_runs + 1));
  if (!ord) return;
  for (int i = 0; i < S->n_runs; i++) {
    int j = i;
    double c = S->runs[i].s_per_frame;
    for (; j > 0 && cheaper(c, S->runs[ord[j - 1]].s_per_frame); j--) ord[j] = ord[j - 1];
    ord[j] = i;
  }
  int all_ext = 1;
  for (int i = 0; i < v->n_judged; i++) all_ext &= v->judged[i].extrapolated;
  printf("  runs by cost (s/frame)%s:\n",
         !v->ref_competes ? "; the reference is not ranked (its error is 0 by construction)"
         : all_ext        ? ""
                          : "; the reference's error counts the extrapolated quantities (against itself it is 0)");
  for (int n = 0; n < S->n_runs && n < RANKED_MAX; n++) {
    const bs_study_run *r = &S->runs[ord[n]];
    printf("    %-40s %-7s %10.4g s/frame  ", r->name, bs_study_run_status(r), r->s_per_frame);
    print_error(S, r);
    printf("%s\n", r->is_ref ? "  [reference]" : "");
  }
  if (S->n_runs > RANKED_MAX) printf("    ... %d more in study.csv (verdict_error)\n", S->n_runs - RANKED_MAX);
  free(ord);
}

/* The verdict the library made (S->verdict): what it judged, the runs, the
 * cheapest within each threshold. */
static void print_verdict(const bs_study *S) {
  const bs_study_verdict *v = &S->verdict;
  printf("\n");
  print_judged(S, v);
  print_ranking(S, v);
  static const char *const thr_name[BS_STUDY_N_THRESHOLDS] = {"1%", "0.1%", "0.01%"};
  for (int t = 0; t < BS_STUDY_N_THRESHOLDS; t++) {
    int b = v->cheapest[t];
    printf("  cheapest within %-6s ", thr_name[t]);
    if (b >= 0) {
      printf("%s (%.4g s/frame, ", S->runs[b].name, S->runs[b].s_per_frame);
      print_error(S, &S->runs[b]);
      printf(")\n");
    } else if (v->most_accurate >= 0 && (t == 0 || v->cheapest[t - 1] >= 0)) {
      printf("none (the most accurate: %s, ", S->runs[v->most_accurate].name);
      print_error(S, &S->runs[v->most_accurate]);
      printf(")\n");
    } else {
      printf("none%s\n", v->most_accurate < 0 ? " (no run with a measured error)" : "");
    }
  }
}

/* Results, study.csv, plots and the summary of a study whose runs have run. */
static int report(bs_study *S) {
  bs_error err;
  int n_bad = bs_study_evaluate(S);
  if (n_bad)
    fprintf(stderr, "bigstep study: %d run(s) could not be compared with the reference (failed run, no common "
                    "frame times or unmatched vertices); their error columns are nan\n", n_bad);
  if (bs_study_csv_write(S, &err)) {
    fprintf(stderr, "bigstep study: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  char msg[BS_ERROR_MSG + BS_STUDY_FILE_PATH] = ""; /* a library message, or gnuplot's naming plots.log */
  int plots = bs_study_plots_write(S, &err);
  if (plots) snprintf(msg, sizeof msg, "%s", err.msg);
  else plots = run_gnuplot(S, msg, sizeof msg);
  bs_study_summary_write(S, stdout);
  print_verdict(S);
  printf("wrote %s/study.csv%s\n", S->out, plots ? "" : " and the PNG plots");
  if (plots) {
    fprintf(stderr, "bigstep study: plots: %s\n", msg);
    return BS_EXIT_FAIL;
  }
  return 0;
}

int bs_cmd_study(int argc, char **argv) {
  study_args A;
  memset(&A, 0, sizeof A);
  A.jobs = 1;
  A.budget = 900;
  A.user_sets = calloc((size_t)argc + 1, sizeof(char *));
  bs_study *S = NULL;
  slot *sl = NULL;
  int rc = parse_args(&A, argc, argv);
  if (!rc && A.help) fputs(study_help, stdout);
  if (!rc && !A.help) rc = plan(&A, &S);
  if (!rc && !A.help && !(sl = calloc((size_t)S->n_runs + 1, sizeof *sl))) {
    fprintf(stderr, "bigstep study: out of memory\n");
    rc = BS_EXIT_FAIL;
  }
  if (!rc && !A.help) {
    int n_pending = mark_pending(S, sl, A.force);
    printf("study %s: %d runs, %d to do (%d done before), in %s\n", S->name, S->n_runs, n_pending,
           S->n_runs - n_pending, S->out);
    fflush(stdout);
    run_all(S, sl, A.jobs, n_pending, A.budget);
    rc = report(S);
  }
  for (int k = 0; k < A.n_knobs; k++) bs_study_knob_free(&A.knobs[k]);
  free(A.user_sets);
  free(sl);
  bs_study_destroy(&S);
  return rc;
}
