/* memory.c — the run's memory estimate and the refusal above the machine's
 * memory (bs_memory.h has the model). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bs_memory.h"

#define BASE_BYTES (64.0 * 1048576.0)

double bs_memory_run_bytes(const bs_scene *sc, int64_t vertices, int64_t tets) {
  const bs_lin_kind lin = sc->solver.min.linear;
  double per_tet = lin == BS_LIN_AMG ? 1600.0 : 1100.0;
  if (sc->self_collision) per_tet *= 1.3;
  double b = BASE_BYTES + per_tet * (double)tets;
  if (lin == BS_LIN_CHOLMOD) b += 190.0 * pow(3.0 * (double)vertices, 4.0 / 3.0);
  return b;
}

int64_t bs_memory_max_tets(const bs_scene *sc) {
  const double mem = bs_machine_memory();
  if (!(mem > 0)) return 0;
  /* Bisect on the tet count (vertices about tets / 5.5, as Gmsh's and boxes). */
  double lo = 0, hi = mem;
  for (int i = 0; i < 200 && hi - lo > 1; i++) {
    const double mid = 0.5 * (lo + hi);
    if (bs_memory_run_bytes(sc, (int64_t)(mid / 5.5), (int64_t)mid) <= mem) lo = mid;
    else hi = mid;
  }
  return lo < 1 ? 1 : (int64_t)lo;
}

/* Vertices and tets of box body b (refinement included). */
static void box_counts(const bs_scene_body *b, double *nv, double *nt) {
  const double r = ldexp(1.0, b->refine);
  *nv = (r * b->box_cells[0] + 1) * (r * b->box_cells[1] + 1) * (r * b->box_cells[2] + 1);
  *nt = 6.0 * b->box_cells[0] * b->box_cells[1] * b->box_cells[2] * r * r * r;
}

static int over(const bs_scene *sc, const bs_memory_estimate *e, const char *what, bs_error *err) {
  if (!(e->machine > 0) || e->bytes <= e->machine) return 0;
  return bs_error_set(err, BS_EINPUT,
                      "%s: %s: %lld vertices and %lld tets need an estimated %.1f GiB, more than this machine's %.1f "
                      "GiB (see bs_memory.h)",
                      sc->path, what, (long long)e->vertices, (long long)e->tets, e->bytes / 1073741824.0,
                      e->machine / 1073741824.0);
}

int bs_scene_memory_estimate(const bs_scene *sc, bs_memory_estimate *e, bs_error *err) {
  double nv = 0, nt = 0;
  int exact = 1, worst = -1;
  double worst_t = 0;
  for (int i = 0; i < sc->n_bodies; i++) {
    const bs_scene_body *b = &sc->bodies[i];
    if (strcmp(b->mesh, "box") != 0) {
      exact = 0;
      continue;
    }
    double v, t;
    box_counts(b, &v, &t);
    nv += v, nt += t;
    if (t > worst_t) worst_t = t, worst = i;
  }
  const double cap = 9.2e18;
  *e = (bs_memory_estimate){.vertices = (int64_t)fmin(nv, cap), .tets = (int64_t)fmin(nt, cap), .exact = exact,
                            .machine = bs_machine_memory()};
  e->bytes = bs_memory_run_bytes(sc, e->vertices, e->tets);
  char what[160];
  snprintf(what, sizeof what, "bodies.%d.box (%d x %d x %d cells, refine %d)", worst,
           worst >= 0 ? sc->bodies[worst].box_cells[0] : 0, worst >= 0 ? sc->bodies[worst].box_cells[1] : 0,
           worst >= 0 ? sc->bodies[worst].box_cells[2] : 0, worst >= 0 ? sc->bodies[worst].refine : 0);
  return worst >= 0 ? over(sc, e, what, err) : 0;
}

int bs_memory_check(const bs_scene *sc, int64_t vertices, int64_t tets, bs_memory_estimate *e, bs_error *err) {
  *e = (bs_memory_estimate){.vertices = vertices, .tets = tets, .exact = 1, .machine = bs_machine_memory()};
  e->bytes = bs_memory_run_bytes(sc, vertices, tets);
  return over(sc, e, "bodies", err);
}
