/* bigstep run SCENE — one simulation: parse, loop, print. The library does
 * the work (bs_sim.h: stepping; bs_runfolder.h: the output folder). */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "app.h"
#include "bs_runfolder.h"
#include "bs_scene.h"
#include "bs_sim.h"

static const char *run_help =
    "usage: bigstep run SCENE [--method M] [--backend B] [--steps-per-frame N] [--frames N]\n"
    "                         [--set key.path=value]... [--out DIR] [--replace] [--quiet] [--trace]\n"
    "                         [--resume [DIR]]\n"
    "\n"
    "Runs a scene (JSON; see docs/scenes.md). Prints a line per frame and a\n"
    "summary in the columns of the paper's Figure 11; writes VTU/PVD files and a\n"
    "per-step stats CSV into the output folder. On a terminal the frame lines\n"
    "update one progress line (frames, elapsed time, s/frame, ETA); otherwise each\n"
    "frame prints its own line. Ctrl-C (SIGINT) or SIGTERM stops the run at the\n"
    "next Newton iteration (the frame cut short is undone): the frames done so\n"
    "far are written as after every frame (rows flushed, frames.pvd, a summary.txt\n"
    "marked interrupted); a second Ctrl-C ends the program at once. One run per\n"
    "output folder (a lock, .bigstep.lock).\n"
    "  --method M            optimization | newton | newton_k (solver.method)\n"
    "  --steps-per-frame N   time.steps_per_frame\n"
    "  --frames N            time.frames\n"
    "  --set key.path=value  any scene key, arrays by index (bodies.0.material.youngs=1e6)\n"
    "  --out DIR             output.dir\n"
    "  --replace             replace an earlier run's files in the output folder\n"
    "                        (without it such a folder is refused)\n"
    "  --resume [DIR]        continue the stopped run in DIR (default: the scene's\n"
    "                        output.dir) from its last checkpoint (checkpoint.bin,\n"
    "                        every output.checkpoint_every frames): the frames after\n"
    "                        it are removed and made again, the same bit for bit; the\n"
    "                        scene must be the one the folder was run with\n"
    "  --quiet               no per-frame lines\n"
    "  --trace               one line per solver iteration on stderr (to follow a slow step)\n"
    "  --backend B           serial | petsc (solver.backend); petsc runs the scene\n"
    "                        distributed: mpirun -np N bigstep run SCENE --backend petsc\n"
    "                        (a stop request stops every rank at the same Newton\n"
    "                        iteration; no checkpoint is written: into an output\n"
    "                        folder it needs output.checkpoint_every 0, and --resume\n"
    "                        is refused)\n"
    "\n"
    "Exit status: 0 every step converged; 1 a step did not converge, or an error\n"
    "(bad scene, a file that cannot be written, a folder in use or holding an\n"
    "earlier run; --resume: no checkpoint, a bad one, another scene); 2 a usage\n"
    "error; 130 stopped by SIGINT, 143 by SIGTERM (--resume continues it). A\n"
    "resumed run returns the same statuses, for the whole run.\n";

typedef struct run_args {
  const char *scene;
  int quiet, trace, replace, resume;
  char *command;  /* the command line, for run.txt */
  bs_app_sets sets;
} run_args;

/* The scene key a flag stands for, and whether its value is a count. */
static const char *flag_key(const char *flag, int *is_count) {
  *is_count = !strcmp(flag, "--steps-per-frame") || !strcmp(flag, "--frames");
  if (!strcmp(flag, "--method")) return "solver.method";
  if (!strcmp(flag, "--steps-per-frame")) return "time.steps_per_frame";
  if (!strcmp(flag, "--frames")) return "time.frames";
  if (!strcmp(flag, "--out")) return "output.dir";
  if (!strcmp(flag, "--backend")) return "solver.backend";
  return NULL;
}

static int is_dir(const char *p) {
  struct stat sb;
  return stat(p, &sb) == 0 && S_ISDIR(sb.st_mode);
}

/* --resume, --resume=DIR or --resume DIR (DIR: an existing folder); DIR
 * becomes output.dir. 0, or the usage status. */
static int parse_resume(int argc, char **argv, int *i, run_args *a) {
  const char *arg = argv[*i], *dir = NULL;
  a->resume = 1;
  if (arg[8] == '=') dir = arg + 9;
  else if (*i + 1 < argc && argv[*i + 1][0] != '-' && is_dir(argv[*i + 1])) dir = argv[++*i];
  if (dir && !dir[0]) return bs_app_usage_error("run", "--resume= needs a folder");
  if (dir && bs_app_sets_add(&a->sets, "output.dir", dir, 1)) return bs_app_usage_error("run", "out of memory");
  return 0;
}

/* 0 to run, -1 after --help, else the usage status. */
static int parse_args(int argc, char **argv, run_args *a) {
  for (int i = 1; i < argc; i++) {
    const char *arg = argv[i], *flag, *val;
    if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
      fputs(run_help, stdout);
      return -1;
    }
    if (!strcmp(arg, "--quiet") || !strcmp(arg, "--trace") || !strcmp(arg, "--replace")) {
      *(arg[2] == 'q' ? &a->quiet : arg[2] == 't' ? &a->trace : &a->replace) = 1;
      continue;
    }
    if (!strcmp(arg, "--resume") || !strncmp(arg, "--resume=", 9)) {
      int rc = parse_resume(argc, argv, &i, a);
      if (rc) return rc;
      continue;
    }
    if (strncmp(arg, "--", 2)) {
      if (a->scene) return bs_app_usage_error("run", "unexpected argument '%s'", arg);
      a->scene = arg;
      continue;
    }
    char fbuf[64];
    if (bs_app_flag_value(argc, argv, &i, fbuf, sizeof fbuf, &flag, &val)) return bs_app_usage_error("run", "flag %s needs a value", fbuf);
    if (!strcmp(flag, "--set")) {
      if (bs_app_sets_add(&a->sets, val, NULL, 0)) return bs_app_usage_error("run", "out of memory");
      continue;
    }
    int is_count, n;
    const char *key = flag_key(flag, &is_count);
    if (!key) return bs_app_usage_error("run", "unknown flag '%s'", flag);
    if (is_count && bs_parse_int(val, 1, 100000000, &n))
      return bs_app_usage_error("run", "%s must be a positive integer, got '%s'", flag, val);
    if (bs_app_sets_add(&a->sets, key, val, !is_count)) return bs_app_usage_error("run", "out of memory");
  }
  if (a->resume && a->replace) return bs_app_usage_error("run", "--resume and --replace exclude each other");
  return a->scene ? 0 : bs_app_usage_error("run", "missing SCENE");
}

typedef struct run_ctx {
  const run_args *args;
  bs_runfolder *folder; /* NULL: no output folder */
  double t0;            /* wall clock at the start of the run */
  int first;            /* the frame the run (or its resumption) started from */
  int tty;              /* stdout is a terminal: one updating line */
  int measured_frame;   /* the frame last_m measured, with intersections; -1: none */
  bs_sim_measures last_m;
} run_ctx;

/* The progress part of a frame line: frames done, elapsed, s/frame, ETA. */
static void print_progress(const run_ctx *c, const bs_sim *s, int frame) {
  double el = bs_seconds() - c->t0, per = el / (frame > c->first ? frame - c->first : 1);
  printf("  [%d/%d, %.1f s, %.3g s/frame, ETA %.0f s]", frame, s->scene->frames, el, per,
         per * (s->scene->frames - frame));
}

/* After each frame: the folder's files, then the progress line. */
static int on_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  run_ctx *c = ctx;
  if ((c->args->quiet || fs->frame == 0) && !c->folder) return 0;
  bs_sim_measures m; /* once: the folder's row (with intersections), the line and, kept, the summary's */
  bs_sim_measure(s, c->folder != NULL, &m);
  if (c->folder) c->last_m = m, c->measured_frame = fs->frame;
  if (c->folder && bs_runfolder_write(c->folder, s, fs, &m, err)) return BS_EIO;
  if (c->args->quiet || fs->frame == 0) return 0;
  if (s->scene->mode == BS_MODE_STATIC) {
    const bs_step_stats *st = &fs->steps[0].st;
    printf("static: %s after %d iterations (%d CG), |grad E| %.3e, E %.6e, %d inverted tets, %.3f s\n",
           st->failed                           ? "FAILED"
           : st->min.reason == BS_MIN_FLOOR ? "converged at the rounding floor of E"
                                            : "converged",
           st->min.iterations, st->min.cg_iterations, st->min.grad_norm,
           st->min.E, m.inverted, st->seconds);
    return 0;
  }
  if (c->tty) printf("\r\033[K");
  printf("frame %d/%d  newton %ld  cg %ld  |grad E| %.2e  inverted %d", fs->frame, s->scene->frames, fs->iterations,
         fs->cg_iterations, fs->grad_max, m.inverted);
  if (s->obstacles) printf("  inside obstacles %d (depth %.2e m)", m.penetrating, m.max_depth);
  long sweep = 0; /* stages of moving obstacles swept within steps (bs_step.h) */
  for (int k = 0; k < fs->n_steps; k++) sweep += fs->steps[k].st.sweep_stages;
  if (sweep) printf("  swept in %ld stages", sweep);
  printf("  peak %.0f MiB  %.3f s%s", bs_peak_rss() / 1048576.0, fs->seconds, fs->failed ? "  FAILED STEPS" : "");
  print_progress(c, s, fs->frame);
  if (!c->tty || fs->frame == s->scene->frames) putchar('\n');
  fflush(stdout);
  return 0;
}

static void print_header(const run_args *a, const bs_sim *s) {
  const bs_scene *sc = s->scene;
  printf("bigstep run %s: %d vertices, %d tets, %ld dofs (%d scripted vertices), method %s, linear %s, "
         "%d frames at %g fps, %d steps/frame (dt %.6g s), tolerance %g, memory estimate %.0f MiB\n",
         a->scene, s->mesh->n_vertices, s->mesh->n_tets, bs_sim_dofs(s), s->mesh->n_vertices - s->n_free,
         bs_method_name(sc->solver.method),
         sc->solver.method == BS_METHOD_OPTIMIZATION ? bs_lin_kind_name(sc->solver.min.linear) : "minres", sc->frames,
         sc->fps, sc->steps_per_frame, sc->dt, sc->solver.min.tol, s->memory_bytes / 1048576.0);
  fflush(stdout);
}

/* The summary (printed, and written into the folder, marked interrupted when
 * the run stopped early); the exit status. */
static int finish(run_ctx *c, const bs_sim *s, const bs_run_totals *T, int stopped, double wall,
                  bs_error *err) {
  bs_summary u;
  char summary[2048];
  if (!stopped && c->measured_frame == s->frame) /* the last frame line's measures: the same state */
    bs_summary_make_measured(s, T, wall, &c->last_m, &u);
  else
    bs_summary_make(s, T, wall, &u);
  if (stopped) u.partial = BS_SUMMARY_INTERRUPTED;
  bs_summary_format(&u, summary, sizeof summary);
  printf("\n%s", summary);
  int rc = 0;
  if (c->folder && bs_runfolder_finish(c->folder, summary, err)) {
    fprintf(stderr, "bigstep run: %s\n", err->msg);
    rc = BS_EXIT_FAIL;
  }
  if (stopped) {
    const int sig = bs_app_stop_signal;
    fprintf(stderr, "bigstep run: interrupted (%s) at frame %d of %d%s%s%s\n", bs_app_signal_name(sig),
            s->frame, s->scene->frames, c->folder ? "; continue it with the same command and --resume '" : "",
            c->folder ? s->scene->out_dir : "", c->folder ? "'" : "");
    return rc ? rc : bs_app_stop_status(sig);
  }
  if (!rc && T->failed) {
    fprintf(stderr, "bigstep run: %ld of %ld steps did not converge; the first (frame %d, step %d): %s\n", T->failed,
            T->steps, T->first_fail_frame, T->first_fail_step, T->first_fail_reason);
    rc = BS_EXIT_FAIL;
  }
  return rc;
}

/* The output folder: a new run's, or the stopped run's to continue (then *T
 * holds its totals so far). 0, or BS_EXIT_FAIL after the message. */
static int open_folder(const run_args *a, run_ctx *c, bs_sim *s, bs_run_totals *T) {
  bs_error err;
  bs_error_clear(&err);
  const bs_scene *sc = s->scene;
  const bs_runfolder_opts fo = {.replace = a->replace, .command_line = a->command};
  int st = 0;
  if (a->resume && !sc->out_dir[0])
    st = bs_error_set(&err, BS_EINPUT, "--resume: the scene has no output.dir (give --resume DIR)");
  else if (a->resume)
    st = bs_runfolder_resume(sc->out_dir, s, &fo, &c->folder, T, &err);
  else if (sc->out_dir[0])
    st = bs_runfolder_open(sc->out_dir, s, &fo, &c->folder, &err);
  if (st) {
    fprintf(stderr, "bigstep run: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  c->first = s->frame;
  if (a->resume && !a->quiet) printf("continuing '%s' from frame %d of %d\n", sc->out_dir, s->frame, sc->frames);
  return 0;
}

/* The loop and the summary; the exit status. */
static int run_scene(const run_args *a, bs_sim *s) {
  bs_error err;
  bs_error_clear(&err);
  run_ctx c = {.args = a, .t0 = bs_seconds(), .tty = isatty(fileno(stdout)), .measured_frame = -1};
  bs_run_totals T;
  memset(&T, 0, sizeof T);
  bs_app_install_stop_handlers(); /* from here a Ctrl-C stops between steps, leaving a consistent folder */
  if (open_folder(a, &c, s, &T)) return BS_EXIT_FAIL;
  const bs_sim_run_opts ro = {.on_frame = on_frame, .ctx = &c, .stop = &bs_app_stop_signal, .resume = a->resume};
  int st = bs_sim_run_with(s, &ro, &T, &err), rc = 0;
  if (st == BS_SIM_STOPPED && c.folder && s->scene->checkpoint_every > 0 && bs_runfolder_checkpoint(c.folder, s, &err))
    st = err.code;
  if (st < 0) {
    fprintf(stderr, "bigstep run: %s\n", err.msg);
    rc = BS_EXIT_FAIL;
  } else {
    double wall = c.folder ? bs_runfolder_wall(c.folder) : bs_seconds() - c.t0;
    rc = finish(&c, s, &T, st == BS_SIM_STOPPED, wall, &err);
  }
  bs_runfolder_destroy(&c.folder);
  return rc;
}

/* The ranks mpirun started this process among (Open MPI's, or a PMI's
 * environment), 1 outside mpirun. */
static int mpi_ranks(void) {
  const char *v = getenv("OMPI_COMM_WORLD_SIZE");
  if (!v) v = getenv("PMI_SIZE");
  int n = 1;
  if (v && bs_parse_int(v, 1, 1 << 30, &n)) n = 1;
  return n;
}

int bs_cmd_run(int argc, char **argv) {
  run_args a = {0};
  int rc = parse_args(argc, argv, &a);
  if (!rc && !(a.command = bs_app_command_line(argc, argv))) rc = bs_app_usage_error("run", "out of memory");
  if (rc) {
    bs_app_sets_free(&a.sets);
    return rc < 0 ? 0 : rc;
  }
  bs_error err;
  bs_error_clear(&err);
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  int st = bs_scene_load(a.scene, a.sets.n, (const char *const *)a.sets.v, &sc, &err);
  if (!st && a.trace) sc->solver.trace = stderr;
  if (!st && sc->backend == BS_BACKEND_PETSC) {
    const bs_app_petsc_args pa = {.quiet = a.quiet, .replace = a.replace, .resume = a.resume, .command = a.command};
    rc = bs_app_run_petsc(a.scene, sc, &pa);
  } else if (!st && mpi_ranks() > 1) {
    fprintf(stderr, "bigstep run: %s: solver.backend is \"serial\" but mpirun started %d ranks (each would run the "
                    "whole scene): set solver.backend to \"petsc\" (--set solver.backend=petsc) or run one process\n",
            a.scene, mpi_ranks());
    rc = BS_EXIT_FAIL;
  } else if (st || bs_sim_create(sc, &s, &err)) {
    fprintf(stderr, "bigstep run: %s\n", err.msg);
    rc = BS_EXIT_FAIL;
  } else {
    if (!a.quiet) print_header(&a, s);
    rc = run_scene(&a, s);
  }
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  bs_app_sets_free(&a.sets);
  free(a.command);
  return rc;
}
