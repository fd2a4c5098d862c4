/* dist_compare.h — the MPI tests' comparison of a petsc-backend run
 * (bs_dsim.h) with the serial run of the same scene (bs_sim.h): vertices
 * matched by their rest positions, positions compared to 1e-9 of max |x|,
 * a group's mean y displacement, and both backends advanced frame by frame
 * with the same Newton iteration counts required on 1 rank (or not). Include after
 * dist_check.h. */
#ifndef DIST_COMPARE_H
#define DIST_COMPARE_H

#include <stdlib.h>

#include "bs_dsim.h"
#include "bs_sim.h"
#include "dist_check.h"
static const double *sort_base;
static int by_position(const void *a, const void *b) {
  const double *p = sort_base + 3 * *(const int32_t *)a, *q = sort_base + 3 * *(const int32_t *)b;
  for (int k = 0; k < 3; k++)
    if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
  return 0;
}

/* For each local vertex of d, the serial vertex at the same rest position
 * (exactly), -1 if none. Caller frees. */
static int32_t *match_vertices(const bs_dsim *d, const bs_sim *s) {
  int32_t n = s->mesh->n_vertices, *idx = malloc(sizeof(int32_t) * (size_t)n);
  int32_t *map = malloc(sizeof(int32_t) * (size_t)d->mesh->n_vertices + 4);
  for (int32_t i = 0; i < n; i++) idx[i] = i;
  sort_base = s->x0;
  qsort(idx, (size_t)n, sizeof *idx, by_position);
  for (int32_t v = 0; v < d->mesh->n_vertices; v++) {
    int32_t lo = 0, hi = n - 1;
    map[v] = -1;
    while (lo <= hi && map[v] < 0) {
      int32_t mid = (lo + hi) / 2, c = 0;
      for (int k = 0; k < 3 && !c; k++) {
        double a = d->mesh->x[3 * v + k], b = s->x0[3 * idx[mid] + k];
        c = a < b ? -1 : a > b ? 1 : 0;
      }
      if (c == 0) map[v] = idx[mid];
      else if (c < 0) hi = mid - 1;
      else lo = mid + 1;
    }
  }
  free(idx);
  return map;
}

/* max |x_d - x_s| over the vertices, at most xtol of max |x_s| (and printed
 * relative to the largest displacement); the mean y displacement of group
 * `group` within tip_tol. */
static void compare_tol(const bs_dsim *d, const bs_sim *s, const char *what, const char *group, double tip_tol,
                        double xtol) {
  int32_t *map = match_vertices(d, s);
  double err = 0, xmax = 0, umax = 0;
  int unmatched = 0;
  for (int32_t i = 0; i < 3 * s->mesh->n_vertices; i++) {
    xmax = fmax(xmax, fabs(s->x[i]));
    umax = fmax(umax, fabs(s->x[i] - s->x0[i]));
  }
  for (int32_t v = 0; v < d->mesh->n_vertices; v++) {
    if (map[v] < 0) {
      unmatched++;
      continue;
    }
    for (int k = 0; k < 3; k++) err = fmax(err, fabs(d->x[3 * v + k] - s->x[3 * map[v] + k]));
  }
  MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  CHECK(unmatched == 0, "%s: %d vertices with no serial twin", what, unmatched);
  CHECK(err <= xtol * xmax, "%s: positions differ by %.3g (max |x| %.3g)", what, err, xmax);
  if (bs_dist_rank() == 0)
    printf("  %s: max |x - x_serial| = %.3e (%.3e of max |x|, %.3e of max |u|)\n", what, err, err / xmax,
           err / fmax(umax, 1e-300));
  if (group) {
    const bs_group *gs = bs_mesh_group(s->mesh, group);
    const bs_dgroup *gd = bs_dmesh_group(d->mesh, group);
    double us = 0, ud[2] = {0, 0};
    for (int32_t i = 0; i < gs->n_vertices; i++) us += s->x[3 * gs->vertices[i] + 1] - s->x0[3 * gs->vertices[i] + 1];
    us /= gs->n_vertices;
    for (int32_t i = 0; i < gd->n_vertices; i++) {
      int32_t v = gd->vertices[i];
      if (!d->mesh->owned[v]) continue;
      ud[0] += d->x[3 * v + 1] - d->mesh->x[3 * v + 1];
      ud[1] += 1;
    }
    MPI_Allreduce(MPI_IN_PLACE, ud, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    CHECK_REL(ud[0] / ud[1], us, tip_tol, "tip deflection");
    if (bs_dist_rank() == 0) printf("  %s: tip deflection %.15e (serial %.15e)\n", what, ud[0] / ud[1], us);
  }
  free(map);
}

/* compare_tol with positions to 1e-9 of max |x_s|. */
static void compare(const bs_dsim *d, const bs_sim *s, const char *what, const char *group, double tip_tol) {
  compare_tol(d, s, what, group, tip_tol, 1e-9);
}

/* Both backends through `frames` frames: no failed step on the backend; on 1
 * rank the Newton iterations of each frame within `slack` of the serial ones
 * (0: the same; < 0: not compared); the sums into *it_s, *it_d. */
static void advance_both(bs_sim *s, bs_dsim *d, int frames, int slack, long *it_s, long *it_d) {
  bs_error err = {0};
  *it_s = *it_d = 0;
  for (int f = 0; s && d && f < frames; f++) {
    bs_frame_stats fs, fd;
    CHECK_OK(bs_sim_advance_frame(s, &fs, &err), err);
    CHECK_OK(bs_dsim_advance_frame(d, &fd, &err), err);
    CHECK(!fd.failed, "frame %d: %s", f + 1, d->steps[0].reason);
    if (bs_dist_size() == 1 && slack >= 0)
      CHECK(labs(fd.iterations - fs.iterations) <= slack, "frame %d: %ld iterations, serial %ld (slack %d)", f + 1,
            fd.iterations, fs.iterations, slack);
    *it_s += fs.iterations, *it_d += fd.iterations;
  }
}

#endif
