/* bigstep run SCENE with solver.backend = "petsc", under mpirun -np N: the
 * scene on the distributed backend (petsc/bs_dsim.h). Rank 0 prints the
 * header, the frame lines and the summary (bs_summary_format, the serial
 * run's summary). Without PETSc (BS_PETSC=OFF) the backend is refused. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "bs_runfolder.h"
#include "bs_scene.h"

#ifndef BS_HAVE_PETSC

int bs_app_run_petsc(const char *path, const bs_scene *sc, const bs_app_petsc_args *a) {
  (void)sc, (void)a;
  fprintf(stderr, "bigstep run: %s: solver.backend: this bigstep was built without PETSc (BS_PETSC=OFF); "
                  "use \"serial\" or rebuild with petsc-dev installed\n", path);
  return BS_EXIT_FAIL;
}

#else

#include "bs_dist.h"
#include "bs_doutput.h"
#include "bs_dsim.h"

/* The message of a failed collective call: rank 0's, and another rank's
 * when it differs. */
static void report(const bs_error *err) {
  char first[BS_ERROR_MSG];
  snprintf(first, sizeof first, "%s", err->msg);
  MPI_Bcast(first, (int)sizeof first, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (bs_dist_rank() == 0 || strcmp(first, err->msg) != 0)
    fprintf(stderr, "bigstep run%s: %s\n", bs_dist_rank() ? " (a rank > 0)" : "", err->msg);
}

static void print_header(const char *path, const bs_dsim *d) {
  const bs_scene *sc = d->scene;
  printf("bigstep run %s: %lld vertices, %lld tets, %ld dofs on %d ranks (petsc backend), method %s, linear %s, "
         "%d frames at %g fps, %d steps/frame (dt %.6g s), tolerance %g\n",
         path, (long long)d->mesh->n_global_vertices, (long long)d->mesh->n_global_cells, bs_dsim_dofs(d),
         bs_dist_size(), bs_method_name(sc->solver.method), bs_lin_kind_name(sc->solver.min.linear), sc->frames,
         sc->fps, sc->steps_per_frame, sc->dt, sc->solver.min.tol);
  fflush(stdout);
}

static void print_frame(const bs_dsim *d, const bs_frame_stats *fs) {
  const bs_scene *sc = d->scene;
  const bs_step_stats *st = &fs->steps[0].st;
  if (sc->mode == BS_MODE_STATIC)
    printf("static: %s after %d iterations (%d CG), |grad E| %.3e, E %.6e, %d inverted tets, %.3f s\n",
           st->failed ? "FAILED" : "converged", st->min.iterations, st->min.cg_iterations, st->min.grad_norm,
           st->min.E, fs->steps[fs->n_steps - 1].inverted, st->seconds);
  else
    printf("frame %d/%d  newton %ld  cg %ld  |grad E| %.2e  inverted %d  peak %.0f MiB (rank 0)  %.3f s%s\n",
           fs->frame, sc->frames, fs->iterations, fs->cg_iterations, fs->grad_max, fs->steps[fs->n_steps - 1].inverted,
           bs_peak_rss() / 1048576.0, fs->seconds, fs->failed ? "  FAILED STEPS" : "");
  fflush(stdout);
}

/* The frames (or the static solve), totals into *T, each frame into the
 * folder (out may be NULL), frame 0 (the initial state) first; a stop
 * request (bs_app_stop_signal) ends them with *stopped = 1. */
static int run_frames(bs_dsim *d, bs_dout *out, int quiet, bs_run_totals *T, int *stopped, bs_error *err) {
  const bs_scene *sc = d->scene;
  int n = sc->mode == BS_MODE_STATIC ? 1 : sc->frames;
  bs_frame_stats fs;
  bs_frame_sums(0, 0.0, 0, NULL, &fs);
  int rc = out ? bs_dout_frame(out, d, &fs, err) : BS_OK;
  for (int f = 0; f < n && !rc; f++) {
    rc = sc->mode == BS_MODE_STATIC ? bs_dsim_statics(d, &fs, err) : bs_dsim_advance_frame(d, &fs, err);
    if (rc == BS_SIM_STOPPED) {
      *stopped = 1;
      return BS_OK;
    }
    if (rc) return rc;
    bs_run_totals_add(T, &fs);
    if (!quiet && bs_dist_rank() == 0) print_frame(d, &fs);
    if (out) rc = bs_dout_frame(out, d, &fs, err);
  }
  return rc;
}

/* The serial run's summary (bs_summary_make_run), from the distributed run
 * (stopped: marked interrupted, over the frames done): printed by rank 0, and
 * written into the folder (out may be NULL). */
static int print_summary(bs_dsim *d, bs_dout *out, const bs_run_totals *T, double wall, int stopped, bs_error *err) {
  bs_sim_measures m;
  int rc = bs_dsim_measure(d, &m, err);
  if (rc) return rc;
  bs_summary u;
  bs_summary_make_run(d->scene, d->frame, bs_dsim_dofs(d), d->obstacles != NULL, T, wall, &m, &u);
  if (stopped) u.partial = BS_SUMMARY_INTERRUPTED, u.no_resume = 1;
  MPI_Allreduce(MPI_IN_PLACE, &u.peak_mib, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  char text[2048];
  bs_summary_format(&u, text, sizeof text);
  if (bs_dist_rank() == 0) printf("\n%s(peak memory: the largest of the %d ranks)\n", text, bs_dist_size());
  return out ? bs_dout_finish(out, text, err) : BS_OK;
}

/* A stopped run: rank 0 says where, every rank returns the status of the
 * signal (the largest over the ranks: a rank that got none agrees). */
static int stop_status(const bs_dsim *d) {
  int sig = bs_app_stop_signal;
  MPI_Allreduce(MPI_IN_PLACE, &sig, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (bs_dist_rank() == 0)
    fprintf(stderr, "bigstep run: interrupted (%s) at frame %d of %d; the petsc backend writes no checkpoint: "
                    "a new run starts from frame 0\n",
            bs_app_signal_name(sig), d->frame, d->scene->mode == BS_MODE_STATIC ? 1 : d->scene->frames);
  return bs_app_stop_status(sig);
}

int bs_app_run_petsc(const char *path, const bs_scene *sc, const bs_app_petsc_args *a) {
  bs_error err;
  bs_error_clear(&err);
  if (bs_dist_init(NULL, NULL, &err)) {
    fprintf(stderr, "bigstep run: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  double t0 = bs_seconds();
  bs_dsim *d = NULL;
  /* what the backend does not run, then what it does not write into the folder: refused before the run */
  int rc = bs_dsim_check(sc, &err);
  if (!rc && (a->resume || sc->out_dir[0])) rc = bs_dsim_check_output(sc, a->resume, &err);
  if (!rc) rc = bs_dsim_create(sc, &d, &err);
  bs_run_totals T;
  memset(&T, 0, sizeof T);
  const int quiet = a->quiet;
  if (!rc && !quiet && bs_dist_rank() == 0) print_header(path, d);
  bs_dout *out = NULL;
  const bs_runfolder_opts fo = {.replace = a->replace, .command_line = a->command};
  if (!rc && sc->out_dir[0]) rc = bs_dout_open(d, sc->out_dir, &fo, &out, &err);
  bs_app_install_stop_handlers(); /* a stop request stops every rank at the same Newton iteration */
  if (!rc) rc = bs_dsim_set_stop(d, &bs_app_stop_signal, &err);
  int stopped = 0;
  if (!rc) rc = run_frames(d, out, quiet, &T, &stopped, &err);
  if (!rc) rc = print_summary(d, out, &T, bs_seconds() - t0, stopped, &err);
  if (rc) report(&err);
  bs_dout_destroy(&out);
  int status = rc ? BS_EXIT_FAIL : T.failed ? BS_EXIT_FAIL : 0;
  if (!rc && stopped) status = stop_status(d);
  else if (!rc && T.failed && bs_dist_rank() == 0)
    fprintf(stderr, "bigstep run: %ld of %ld steps did not converge; the first (frame %d, step %d): %s\n", T.failed,
            T.steps, T.first_fail_frame, T.first_fail_step, T.first_fail_reason);
  bs_dsim_destroy(&d);
  bs_dist_finalize();
  return status;
}

#endif
