/* bench/dist_cube.c — the petsc backend (petsc/) on the unit cube of
 * CELLS^3 cells (64: the 65^3-vertex cube, 824k dofs), fixed_corotated
 * (E 1e5, nu 0.3, rho 1000), gravity, the x = 0 face fixed; static (one
 * solve) or dynamic (FRAMES frames at 24 fps); solver.linear LINEAR (amg:
 * GAMG with the rigid-body near-null space; pcg: point-block Jacobi; cg).
 * On 1 rank the serial backend runs the same scene in the same process
 * afterwards (--serial), for the side-by-side row.
 *
 *   mpirun -np N bench_dist_cube [--cells C] [--mode static|dynamic] [--frames F]
 *                                [--linear amg|pcg|cg] [--serial] [--csv]
 *
 * Prints one row per backend: ranks, cells, dofs, dofs per rank, Newton
 * iterations, CG (preconditioned) iterations, seconds per Newton iteration,
 * seconds per frame, GAMG setups, levels and seconds of the last setup,
 * peak resident memory per rank (largest over the ranks, MiB). --csv: the
 * same as CSV lines. Never run by the test suite (bench/dist.md: the
 * weak-scaling table and the 64-rank estimate; timings are the lead's to
 * take on an idle machine). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "bs_dsim.h"
#include "bs_sim.h"

typedef struct opts {
  int cells, frames, serial, csv, dynamic;
  const char *linear;
} opts;

typedef struct row {
  const char *backend;
  long newton, cg, steps;
  double seconds, setup_s;
  int levels, ranks;
  double peak_mib;
} row;

static char *scene_json(const opts *o) {
  char *s = malloc(2048);
  if (!s) return NULL;
  snprintf(s, 2048,
           "{\"time\": {\"fps\": 24, \"frames\": %d, \"steps_per_frame\": 1},"
           " \"solver\": {\"method\": \"optimization\", \"linear\": \"%s\", \"tolerance\": 1e-3, \"mode\": \"%s\"},"
           " \"gravity\": [0, -9.8, 0],"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [%d, %d, %d], \"size\": [1, 1, 1]},"
           "   \"material\": {\"model\": \"fixed_corotated\", \"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000},"
           "   \"scripted\": [{\"group\": \"xmin\", \"fixed\": true}]}]}",
           o->frames, o->linear, o->dynamic ? "dynamic" : "static", o->cells, o->cells, o->cells);
  return s;
}

static int parse(int argc, char **argv, opts *o) {
  *o = (opts){.cells = 64, .frames = 3, .linear = "amg"};
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--cells") && v) o->cells = atoi(argv[++i]);
    else if (!strcmp(a, "--frames") && v) o->frames = atoi(argv[++i]);
    else if (!strcmp(a, "--mode") && v) o->dynamic = !strcmp(argv[++i], "dynamic");
    else if (!strcmp(a, "--linear") && v) o->linear = argv[++i];
    else if (!strcmp(a, "--serial")) o->serial = 1;
    else if (!strcmp(a, "--csv")) o->csv = 1;
    else return fprintf(stderr, "bench_dist_cube: unknown or incomplete argument '%s'\n", a), 1;
  }
  return o->cells < 1 || o->frames < 1;
}

static double peak_max(void) {
  double mib = bs_peak_rss() / 1048576.0;
  MPI_Allreduce(MPI_IN_PLACE, &mib, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return mib;
}

static int run_petsc(const bs_scene *sc, row *r, bs_error *err) {
  bs_dsim *d = NULL;
  int rc = bs_dsim_create(sc, &d, err);
  double t0 = bs_seconds();
  for (int f = 0; !rc && f < (sc->mode == BS_MODE_STATIC ? 1 : sc->frames); f++) {
    bs_frame_stats fs;
    rc = sc->mode == BS_MODE_STATIC ? bs_dsim_statics(d, &fs, err) : bs_dsim_advance_frame(d, &fs, err);
    r->newton += fs.iterations, r->cg += fs.cg_iterations, r->steps += fs.n_steps;
  }
  r->seconds = bs_seconds() - t0;
  if (!rc) bs_dlin_info(bs_dintegrator_linsolve(d->integrator), &r->levels, &r->setup_s);
  r->backend = "petsc";
  r->ranks = bs_dist_size();
  r->peak_mib = peak_max();
  bs_dsim_destroy(&d);
  return rc;
}

static int run_serial(const bs_scene *sc, row *r, bs_error *err) {
  bs_sim *s = NULL;
  int rc = bs_sim_create(sc, &s, err);
  double t0 = bs_seconds();
  for (int f = 0; !rc && f < (sc->mode == BS_MODE_STATIC ? 1 : sc->frames); f++) {
    bs_frame_stats fs;
    rc = sc->mode == BS_MODE_STATIC ? bs_sim_statics(s, &fs, err) : bs_sim_advance_frame(s, &fs, err);
    r->newton += fs.iterations, r->cg += fs.cg_iterations, r->steps += fs.n_steps;
  }
  r->seconds = bs_seconds() - t0;
  r->backend = "serial";
  r->ranks = 1;
  r->peak_mib = bs_peak_rss() / 1048576.0; /* includes the petsc run before it */
  bs_sim_destroy(&s);
  return rc;
}

static void print_row(const opts *o, const row *r, long dofs) {
  const int frames = o->dynamic ? o->frames : 1;
  const double per_it = r->newton ? r->seconds / r->newton : 0, per_frame = r->seconds / frames;
  if (o->csv)
    printf("%s,%d,%d,%s,%s,%ld,%ld,%ld,%ld,%.6f,%.6f,%d,%.6f,%.1f\n", r->backend, r->ranks, o->cells,
           o->dynamic ? "dynamic" : "static", o->linear, dofs, dofs / r->ranks, r->newton, r->cg, per_it, per_frame,
           r->levels, r->setup_s, r->peak_mib);
  else
    printf("%-7s %5d %5d %-7s %-4s %9ld %9ld %7ld %8ld %10.4f %10.3f %6d %8.3f %9.1f\n", r->backend, r->ranks,
           o->cells, o->dynamic ? "dynamic" : "static", o->linear, dofs, dofs / r->ranks, r->newton, r->cg, per_it,
           per_frame, r->levels, r->setup_s, r->peak_mib);
}

int main(int argc, char **argv) {
  bs_error err = {0};
  opts o;
  if (bs_dist_init(&argc, &argv, &err) || parse(argc, argv, &o)) {
    fprintf(stderr, "bench_dist_cube: %s\n", err.msg[0] ? err.msg : "bad arguments");
    return 2;
  }
  char *json = scene_json(&o);
  bs_scene *sc = NULL;
  int rc = json ? bs_scene_parse(json, "<bench_dist_cube>", 0, NULL, &sc, &err) : BS_ENOMEM;
  long dofs = 3L * o.cells * (o.cells + 1) * (o.cells + 1); /* free vertices: all but the x = 0 face */
  if (!rc && bs_dist_rank() == 0 && !o.csv)
    printf("backend ranks cells mode    lin       dofs  dofs/rank  newton       cg   s/newton    s/frame levels  setup_s  peak_MiB\n");
  row r = {0};
  if (!rc) rc = run_petsc(sc, &r, &err);
  if (!rc && bs_dist_rank() == 0) print_row(&o, &r, dofs);
  if (!rc && o.serial && bs_dist_size() == 1) {
    row s = {0};
    rc = run_serial(sc, &s, &err);
    if (!rc) print_row(&o, &s, dofs);
  }
  if (rc) fprintf(stderr, "bench_dist_cube: %s\n", err.msg);
  bs_scene_destroy(&sc);
  free(json);
  bs_dist_finalize();
  return rc ? 1 : 0;
}
