/* bigstep run SCENE — one simulation, progress per frame, VTU/PVD and stats
 * CSV output, and a closing summary in the columns of the paper's Figure 11. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app.h"
#include "scene.h"
#include "bs_shim.h"
#include "sim.h"

static const char *run_help =
    "usage: bigstep run SCENE [--method M] [--steps-per-frame N] [--frames N]\n"
    "                         [--set key.path=value]... [--out DIR] [--quiet] [--trace]\n"
    "\n"
    "Runs a scene (JSON; see README.md, 'Scenes'). Prints a line per frame and a\n"
    "summary in the columns of the paper's Figure 11; writes VTU/PVD files and a\n"
    "per-step stats CSV into the output folder. Exit status 1 when a step failed.\n"
    "  --method M            optimization | newton | newton_k (solver.method)\n"
    "  --steps-per-frame N   time.steps_per_frame\n"
    "  --frames N            time.frames\n"
    "  --set key.path=value  any scene key, arrays by index (bodies.0.material.youngs=1e6)\n"
    "  --out DIR             output.dir\n"
    "  --quiet               no per-frame lines\n"
    "  --trace               one line per solver iteration on stderr (to follow a slow step)\n";

static int mkdir_p(const char *dir, bs_error *err) {
  char buf[1024];
  snprintf(buf, sizeof buf, "%s", dir);
  for (char *p = buf + 1; *p; p++)
    if (*p == '/') {
      *p = 0;
      if (mkdir(buf, 0755) && errno != EEXIST) return bs_error_set(err, BS_EIO, "cannot create folder '%s'", buf);
      *p = '/';
    }
  if (mkdir(buf, 0755) && errno != EEXIST) return bs_error_set(err, BS_EIO, "cannot create folder '%s'", buf);
  return 0;
}

typedef struct run_totals {
  long steps, failed, iterations, cg, ls, indefinite, fb_dx, fb_grad, clamps, chol_fb, downhill;
  double seconds, max_grad;
} run_totals;

static void add_stats(run_totals *T, const bs_step_stats *st) {
  T->steps++;
  T->failed += st->failed;
  T->iterations += st->min.iterations;
  T->cg += st->min.cg_iterations;
  T->ls += st->min.ls_evaluations;
  T->indefinite += st->min.indefinite_exits;
  T->downhill += st->min.downhill_iterates;
  T->fb_dx += st->min.fallback_neg_dx;
  T->fb_grad += st->min.fallback_neg_grad;
  T->clamps += st->min.clamps;
  T->chol_fb += st->min.cholmod_fallbacks;
  T->seconds += st->seconds;
  if (st->min.grad_norm > T->max_grad) T->max_grad = st->min.grad_norm;
}

static int write_frame(const bs_sim *s, const char *dir, int frame, char **names, double *times, int *n_out,
                       bs_error *err) {
  char path[1200], name[64];
  snprintf(name, sizeof name, "frame_%05d.vtu", frame);
  snprintf(path, sizeof path, "%s/%s", dir, name);
  bs_vtu_fields f = {.x = s->x, .velocity = s->v, .cell_detF = NULL};
  int st = bs_mesh_write_vtu(s->mesh, &f, path, err);
  if (st) return st;
  names[*n_out] = strdup(name);
  times[*n_out] = s->time;
  (*n_out)++;
  return 0;
}

/* Per-frame energies: kinetic ½ Σ m |v|², elastic Φ_e, gravity −Σ m gᵀx. */
static void frame_energies(const bs_sim *s, double *kin, double *ela, double *grav) {
  const bs_fem *fem = s->fem;
  const double *g = s->scene->gravity;
  double k = 0, gp = 0;
  for (int32_t v = 0; v < fem->n_vertices; v++) {
    const double *vv = s->v + 3 * v, *xx = s->x + 3 * v;
    k += 0.5 * fem->mass[v] * (vv[0] * vv[0] + vv[1] * vv[1] + vv[2] * vv[2]);
    gp -= fem->mass[v] * (g[0] * xx[0] + g[1] * xx[1] + g[2] * xx[2]);
  }
  *kin = k;
  *grav = gp;
  *ela = bs_fem_elastic_energy(fem, s->x);
}

/* Pairs of boundary triangles that intersect at the current state (exact,
 * CGAL), counted up to BS_RUN_SELF_CAP (a tangled state, e.g. the random
 * 65^3 cube, has ~1e9 candidate pairs: the count stops there and reads as
 * "at least"); -1 if the test could not run. */
#define BS_RUN_SELF_CAP 100000
static int64_t surface_self_intersections(const bs_sim *s) {
  int64_t n = 0;
  int truncated = 0;
  bs_error err;
  if (bs_shim_count_self_intersections(s->x, s->mesh->n_vertices, s->mesh->faces, s->mesh->n_faces,
                                       BS_RUN_SELF_CAP, &n, &truncated, &err))
    return -1;
  return n;
}

static void write_frame_row(FILE *f, const bs_sim *s, int frame, long it, long cg, long failed, double secs) {
  if (!f) return;
  double kin, ela, grav, mn;
  frame_energies(s, &kin, &ela, &grav);
  int32_t inv = bs_fem_count_inverted(s->fem, s->x, &mn), pen;
  double depth;
  bs_sim_penetration(s, &pen, &depth);
  int64_t si = surface_self_intersections(s);
  fprintf(f, "%d,%.9g,%.12e,%.12e,%.12e,%.12e,%d,%.6e,%ld,%ld,%ld,%.6f,%d,%.6e,%lld\n", frame, s->time, kin, ela,
          grav, kin + ela + grav, inv, mn, it, cg, failed, secs, pen, depth, (long long)si);
  fflush(f);
}

/* state.bin: "BSST1\0\0\0", int32 n_vertices, int32 0, then per frame: time, x (3n), v (3n). */
static void write_state(FILE *f, const bs_sim *s) {
  if (!f) return;
  size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  fwrite(&s->time, sizeof(double), 1, f);
  fwrite(s->x, sizeof(double), n3, f);
  fwrite(s->v, sizeof(double), n3, f);
  fflush(f);
}

int bs_cmd_run(int argc, char **argv) {
  const char *scene_path = NULL;
  const char **sets = calloc((size_t)argc * 2 + 8, sizeof(char *));
  char **owned = calloc((size_t)argc + 8, sizeof(char *));
  int n_sets = 0, n_owned = 0, quiet = 0, trace = 0, rc = 0;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      fputs(run_help, stdout);
      rc = 0;
      goto out_args;
    }
    if (!strcmp(a, "--quiet")) {
      quiet = 1;
      continue;
    }
    if (!strcmp(a, "--trace")) {
      trace = 1;
      continue;
    }
    if (!strncmp(a, "--", 2)) {
      char flag[64];
      const char *val = NULL, *eq = strchr(a, '=');
      if (!strncmp(a, "--set=", 6)) {
        snprintf(flag, sizeof flag, "--set");
        val = a + 6;
      } else if (eq && strncmp(a, "--set", 5) != 0) {
        snprintf(flag, sizeof flag, "%.*s", (int)(eq - a), a);
        val = eq + 1;
      } else {
        snprintf(flag, sizeof flag, "%s", a);
        if (i + 1 < argc) val = argv[++i];
      }
      if (!val) {
        rc = bs_app_usage_error("run", "flag %s needs a value", flag);
        goto out_args;
      }
      const char *key = NULL;
      if (!strcmp(flag, "--set")) {
        sets[n_sets++] = val;
        continue;
      } else if (!strcmp(flag, "--method")) key = "solver.method";
      else if (!strcmp(flag, "--steps-per-frame")) key = "time.steps_per_frame";
      else if (!strcmp(flag, "--frames")) key = "time.frames";
      else if (!strcmp(flag, "--out")) key = "output.dir";
      else {
        rc = bs_app_usage_error("run", "unknown flag '%s'", flag);
        goto out_args;
      }
      int is_num = strcmp(flag, "--steps-per-frame") == 0 || strcmp(flag, "--frames") == 0;
      int dummy;
      if (is_num && bs_app_parse_int(val, 1, 100000000, &dummy)) {
        rc = bs_app_usage_error("run", "%s must be a positive integer, got '%s'", flag, val);
        goto out_args;
      }
      size_t len = strlen(key) + strlen(val) + 8;
      char *s = malloc(len);
      if (is_num) snprintf(s, len, "%s=%s", key, val);
      else snprintf(s, len, "%s=\"%s\"", key, val);
      owned[n_owned++] = s;
      sets[n_sets++] = s;
    } else {
      if (scene_path) {
        rc = bs_app_usage_error("run", "unexpected argument '%s'", a);
        goto out_args;
      }
      scene_path = a;
    }
  }
  if (!scene_path) {
    rc = bs_app_usage_error("run", "missing SCENE");
    goto out_args;
  }

  bs_error err;
  bs_error_clear(&err);
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  int load_rc = bs_scene_load(scene_path, n_sets, sets, &sc, &err);
  if (!load_rc && trace) sc->solver.trace = stderr;
  if (load_rc || bs_sim_create(sc, &s, &err)) {
    fprintf(stderr, "bigstep run: %s\n", err.msg);
    bs_scene_destroy(&sc);
    rc = BS_EXIT_FAIL;
    goto out_args;
  }
  const char *method = bs_method_name(sc->solver.method);
  int32_t n_free = 0;
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) n_free += s->mask[v];
  long dofs = 3L * n_free;
  if (!quiet)
    printf("bigstep run %s: %d vertices, %d tets, %ld dofs (%d scripted vertices), method %s, linear %s, "
           "%d frames at %g fps, %d steps/frame (dt %.6g s), tolerance %g\n",
           scene_path, s->mesh->n_vertices, s->mesh->n_tets, dofs, s->mesh->n_vertices - n_free, method,
           sc->solver.method == BS_METHOD_OPTIMIZATION ? bs_lin_kind_name(sc->solver.min.linear) : "minres",
           sc->frames, sc->fps, sc->steps_per_frame, sc->dt,
           sc->solver.min.tol);
  FILE *csv = NULL, *fcsv = NULL, *state = NULL;
  char **names = NULL;
  double *times = NULL;
  int n_out = 0;
  const char *dir = sc->out_dir[0] ? sc->out_dir : NULL;
  if (dir) {
    if (mkdir_p(dir, &err)) {
      fprintf(stderr, "bigstep run: %s\n", err.msg);
      rc = BS_EXIT_FAIL;
      goto out_sim;
    }
    if (sc->stats_csv) {
      char p[1200];
      snprintf(p, sizeof p, "%s/stats.csv", dir);
      csv = fopen(p, "w");
      if (!csv) {
        fprintf(stderr, "bigstep run: cannot write '%s'\n", p);
        rc = BS_EXIT_FAIL;
        goto out_sim;
      }
      fprintf(csv, "frame,step,time,guess,iterations,cg_iterations,ls_evaluations,indefinite,fallback_neg_dx,"
                   "fallback_neg_grad,clamps,cholmod_fallbacks,alpha_min,alpha_max,grad_norm,E,reason,inverted,"
                   "t_eval,t_assembly,t_linear,t_line_search,seconds\n");
    }
    {
      char p[1200];
      snprintf(p, sizeof p, "%s/frames.csv", dir);
      fcsv = fopen(p, "w");
      if (!fcsv) {
        fprintf(stderr, "bigstep run: cannot write '%s'\n", p);
        rc = BS_EXIT_FAIL;
        goto out_files;
      }
      fprintf(fcsv, "frame,time,kinetic,elastic,gravity,total,inverted,min_detF,newton,cg,failed,seconds,"
                    "penetrating,max_depth,self_intersections\n");
      if (sc->states) {
        snprintf(p, sizeof p, "%s/state.bin", dir);
        state = fopen(p, "wb");
        if (!state) {
          fprintf(stderr, "bigstep run: cannot write '%s'\n", p);
          rc = BS_EXIT_FAIL;
          goto out_files;
        }
        int32_t hdr[2] = {s->mesh->n_vertices, 0};
        fwrite("BSST1\0\0\0", 1, 8, state);
        fwrite(hdr, sizeof(int32_t), 2, state);
      }
    }
    names = calloc((size_t)sc->frames + 2, sizeof(char *));
    times = calloc((size_t)sc->frames + 2, sizeof(double));
  }
  run_totals T = {0};
  int first_fail_frame = 0, first_fail_step = 0;
  char first_fail_reason[512] = "";
  double t_wall = bs_seconds();
  write_frame_row(fcsv, s, 0, 0, 0, 0, 0.0);
  write_state(state, s);
  if (dir && sc->vtu_every > 0 && write_frame(s, dir, 0, names, times, &n_out, &err)) {
    fprintf(stderr, "bigstep run: %s\n", err.msg);
    rc = BS_EXIT_FAIL;
    goto out_files;
  }
  if (sc->mode == BS_MODE_STATIC) {
    bs_step_stats st;
    if (bs_integrator_static(s->integrator, 0.0, sc->load_steps, s->x, &st, &err)) {
      fprintf(stderr, "bigstep run: static solve: %s\n", err.msg);
      rc = BS_EXIT_FAIL;
      goto out_files;
    }
    add_stats(&T, &st);
    double mn;
    int32_t inv = bs_fem_count_inverted(s->fem, s->x, &mn);
    if (!quiet)
      printf("static: %s after %d iterations (%d CG), |grad E| %.3e, E %.6e, %d inverted tets, %.3f s\n",
             st.failed ? "FAILED" : "converged", st.min.iterations, st.min.cg_iterations, st.min.grad_norm, st.min.E,
             inv, st.seconds);
    if (st.failed) snprintf(first_fail_reason, sizeof first_fail_reason, "%s", st.min.reason_text ? st.min.reason_text : "?");
    write_frame_row(fcsv, s, 1, st.min.iterations, st.min.cg_iterations, st.failed, st.seconds);
    write_state(state, s);
    if (dir && sc->vtu_every > 0 && write_frame(s, dir, 1, names, times, &n_out, &err)) {
      fprintf(stderr, "bigstep run: %s\n", err.msg);
      rc = BS_EXIT_FAIL;
    }
  } else {
    for (int f = 1; f <= sc->frames; f++) {
      long it = 0, cg = 0, fails = 0;
      double secs = 0, gmax = 0;
      for (int k = 0; k < sc->steps_per_frame; k++) {
        bs_step_stats st;
        if (bs_integrator_step(s->integrator, s->time, sc->dt, s->x, s->v, &st, &err)) {
          fprintf(stderr, "bigstep run: frame %d step %d: %s\n", f, k, err.msg);
          rc = BS_EXIT_FAIL;
          goto out_files;
        }
        s->time = (f - 1) / sc->fps + (k + 1) * sc->dt;
        if (st.failed && !T.failed) {
          first_fail_frame = f;
          first_fail_step = k;
          snprintf(first_fail_reason, sizeof first_fail_reason, "%s", st.min.reason_text ? st.min.reason_text : "?");
        }
        add_stats(&T, &st);
        it += st.min.iterations;
        cg += st.min.cg_iterations;
        fails += st.failed;
        secs += st.seconds;
        if (st.min.grad_norm > gmax) gmax = st.min.grad_norm;
        if (csv) {
          int32_t inv = bs_fem_count_inverted(s->fem, s->x, NULL);
          fprintf(csv, "%d,%d,%.9g,%d,%d,%d,%d,%d,%d,%d,%d,%d,%.6g,%.6g,%.6e,%.9e,%s,%d,%.6f,%.6f,%.6f,%.6f,%.6f\n", f, k,
                  s->time, st.guess, st.min.iterations, st.min.cg_iterations, st.min.ls_evaluations,
                  st.min.indefinite_exits, st.min.fallback_neg_dx, st.min.fallback_neg_grad, st.min.clamps,
                  st.min.cholmod_fallbacks, st.min.alpha_min, st.min.alpha_max, st.min.grad_norm, st.min.E,
                  st.min.reason_text ? st.min.reason_text : "", inv, st.min.t_eval, st.min.t_assembly,
                  st.min.t_linear, st.min.t_line_search, st.seconds);
        }
      }
      s->time = f / sc->fps;
      write_frame_row(fcsv, s, f, it, cg, fails, secs);
      write_state(state, s);
      if (!quiet) {
        int32_t inv = bs_fem_count_inverted(s->fem, s->x, NULL), pen;
        double depth;
        bs_sim_penetration(s, &pen, &depth);
        printf("frame %d/%d  newton %ld  cg %ld  |grad E| %.2e  inverted %d", f, sc->frames, it, cg, gmax, inv);
        if (s->obstacles) printf("  inside obstacles %d (depth %.2e m)", pen, depth);
        printf("  peak %.0f MiB  %.3f s%s\n", bs_peak_rss() / 1048576.0, secs, fails ? "  FAILED STEPS" : "");
        fflush(stdout);
      }
      if (dir && sc->vtu_every > 0 && f % sc->vtu_every == 0 && write_frame(s, dir, f, names, times, &n_out, &err)) {
        fprintf(stderr, "bigstep run: %s\n", err.msg);
        rc = BS_EXIT_FAIL;
        goto out_files;
      }
    }
  }
  {
    double wall = bs_seconds() - t_wall;
    double frames = sc->mode == BS_MODE_STATIC ? 1 : (sc->frames ? sc->frames : 1);
    double mn;
    int32_t inv = bs_fem_count_inverted(s->fem, s->x, &mn);
    char summary[2048];
    int len = snprintf(summary, sizeof summary, "%-13s %6s %10s %9s %11s %8s %9s %9s\n", "method", "steps", "s/frame",
                       "dofs", "solves/step", "failed", "|gradE|", "inverted");
    len += snprintf(summary + len, sizeof summary - (size_t)len, "%-13s %6d %10.4f %9ld %11.2f %8ld %9.2e %9d\n",
                    method, sc->steps_per_frame, wall / frames, dofs, T.steps ? (double)T.iterations / T.steps : 0.0,
                    T.failed, T.max_grad, inv);
    {
      int32_t pen;
      double depth;
      bs_sim_penetration(s, &pen, &depth);
      const int64_t si = surface_self_intersections(s);
      len += snprintf(summary + len, sizeof summary - (size_t)len,
                      "at the last frame: %d inverted tets, %s%lld intersecting surface triangle pairs", inv,
                      si >= BS_RUN_SELF_CAP ? "at least " : "", (long long)si);
      if (s->obstacles)
        len += snprintf(summary + len, sizeof summary - (size_t)len, ", %d vertices inside obstacles (max depth %.3e m)",
                        pen, depth);
      len += snprintf(summary + len, sizeof summary - (size_t)len, "\n");
    }
    snprintf(summary + len, sizeof summary - (size_t)len,
             "solver health: %ld CG iterations (%.1f per solve), %ld line-search evaluations, %ld indefinite CG "
             "exits, %ld earlier CG iterates, %ld -dx and %ld -grad fallbacks, %ld clamps, %ld CHOLMOD fallbacks; "
             "peak memory %.1f MiB\n",
             T.cg, T.iterations ? (double)T.cg / T.iterations : 0.0, T.ls, T.indefinite, T.downhill, T.fb_dx, T.fb_grad,
             T.clamps, T.chol_fb, bs_peak_rss() / 1048576.0);
    printf("\n%s", summary);
    if (dir) {
      char p[1200];
      snprintf(p, sizeof p, "%s/summary.txt", dir);
      FILE *sf = fopen(p, "w");
      if (sf) {
        fputs(summary, sf);
        fclose(sf);
      }
    }
    if (T.failed) {
      fprintf(stderr, "bigstep run: %ld of %ld steps did not converge; the first (frame %d, step %d): %s\n", T.failed,
              T.steps, first_fail_frame, first_fail_step, first_fail_reason);
      rc = BS_EXIT_FAIL;
    }
  }
out_files:
  if (dir && n_out > 0) {
    char p[1200];
    snprintf(p, sizeof p, "%s/frames.pvd", dir);
    if (bs_pvd_write(p, n_out, times, (const char *const *)names, &err)) {
      fprintf(stderr, "bigstep run: %s\n", err.msg);
      rc = BS_EXIT_FAIL;
    }
  }
  if (csv) fclose(csv);
  if (fcsv) fclose(fcsv);
  if (state) fclose(state);
  for (int i = 0; i < n_out; i++) free(names[i]);
  free(names);
  free(times);
out_sim:
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
out_args:
  for (int i = 0; i < n_owned; i++) free(owned[i]);
  free(owned);
  free(sets);
  return rc;
}
