/* bench/terms.c — each energy term's value and gradient at a scene's initial
 * state, in ms per evaluation (medians), and the self-collision term's parts
 * (refit, detection, closest primitives) from its statistics: where an
 * evaluation's time goes on a large scene, without running it.
 *
 *   bench_terms SCENE [REPEATS] [key.path=value]...
 *
 * Each evaluation alternates between the initial positions and the same
 * shifted by 1e-9 m per component pattern, so that the self-collision
 * term's cache of its last detection (same positions, bitwise) never
 * answers. Uses as many threads as OMP_NUM_THREADS gives. Never run by the
 * test suite. Measured: bench/README.md (fig1). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_median.h"
#include "bs_scene.h"
#include "bs_selfcollide.h"
#include "bs_sim.h"

/* Median ms of reps evaluations of t at xa / xb alternately (gradient when g). */
static double time_term(bs_term *t, const double *xa, const double *xb, double *g, size_t n3, int reps) {
  double ms[64];
  for (int r = 0; r < reps; r++) {
    double E, t0 = bs_seconds();
    if (g) {
      memset(g, 0, n3 * sizeof(double));
      t->ops->gradient(t, (r & 1) ? xb : xa, &E, g);
    } else {
      t->ops->value(t, (r & 1) ? xb : xa, &E);
    }
    ms[r] = 1e3 * (bs_seconds() - t0);
  }
  return bench_median(ms, reps);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: bench_terms SCENE [REPEATS<=64] [key.path=value]...\n");
    return 2;
  }
  int reps = argc > 2 ? atoi(argv[2]) : 10;
  if (reps < 1 || reps > 64) reps = 10;
  bs_error err;
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  if (bs_scene_load(argv[1], argc > 3 ? argc - 3 : 0, (const char *const *)(argv + 3), &sc, &err) ||
      bs_sim_create(sc, &s, &err)) {
    fprintf(stderr, "bench_terms: %s\n", err.msg);
    return 1;
  }
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  double *xa = malloc(n3 * sizeof(double)), *xb = malloc(n3 * sizeof(double)), *g = malloc(n3 * sizeof(double));
  for (size_t i = 0; i < n3; i++) xa[i] = s->x[i], xb[i] = s->x[i] + 1e-9 * (double)(i % 7);
  s->step.x_n = xa;
  printf("%s: %d vertices, %d tets; medians of %d\n", argv[1], s->mesh->n_vertices, s->mesh->n_tets, reps);
  printf("%-20s %14s %14s\n", "term", "gradient ms", "value ms");
  for (int i = 0; i < s->n_terms; i++) {
    bs_term *t = s->terms[i];
    if (t->ops->begin_step && t->ops->begin_step(t, &err)) {
      fprintf(stderr, "bench_terms: %s\n", err.msg);
      return 1;
    }
    if (t == s->self) bs_term_self_reset_stats(t);
    const double tg = time_term(t, xa, xb, g, n3, reps), tv = time_term(t, xa, xb, NULL, n3, reps);
    printf("%-20s %14.2f %14.2f\n", t->name, tg, tv);
  }
  bs_self_stats st;
  if (s->self && !bs_term_self_stats(s->self, &st, &err) && st.evaluations > 0) {
    const double e = (double)(st.evaluations - st.reused);
    printf("self-collision per detection (means of %lld): refit %.2f ms, detection %.2f ms, closest %.2f ms; "
           "%d colliding vertices\n",
           (long long)(st.evaluations - st.reused), 1e3 * st.t_refit / e, 1e3 * st.t_detect / e,
           1e3 * st.t_closest / e, st.colliding);
  }
  free(xa);
  free(xb);
  free(g);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return 0;
}
