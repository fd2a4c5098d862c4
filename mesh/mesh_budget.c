/* mesh_budget.c — the meshing time budget of bs_mesh_read
 * (bs_mesh_read_opts.time_budget): a deadline per thread, set when a read
 * begins and checked between the meshing stages (bs__budget_check) and, as a
 * bs_seconds() time, inside the long CGAL loops that take one; and the
 * read's report (opts->report), for the stages that record into it from
 * below the calls that carry opts (the tetrahedral remeshing).
 *
 * Inside the stages (CGAL 5.5, Gmsh 4.8.4):
 *   Mesh_3's refinement   stopped by its stop flag, which a watchdog thread
 *                         sets at the deadline (shim_mesh3.cpp); its
 *                         optimisers get the time left as their time_limit.
 *                         CGAL checks the flag between points, and in the
 *                         protection of sharp edges between vertices only:
 *                         one vertex's curve repopulated with ever smaller
 *                         balls (feature curves nearly touching) runs on;
 *   the alpha wrap        its visitor, before each facet (every 256th);
 *   tetrahedral remeshing its visitor, before each split or flip (every
 *                         256th), and between rounds; CGAL's visitor has no
 *                         hook in the collapses and the smoothing;
 *   no hook at all        the surface repair and isotropic remeshing
 *                         (Polygon_mesh_processing), Mesh_3's domain (search
 *                         tree, sharp edges), Gmsh's meshers and optimisers:
 *                         checked before and after only. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mesh_internal.h"

static _Thread_local double deadline_;
static _Thread_local double budget_;
static _Thread_local struct bs_surface_report *report_;

void bs__budget_begin(const bs_mesh_read_opts *opts) {
  report_ = opts ? opts->report : NULL;
  double b = opts ? opts->time_budget : 0.0;
  if (b == 0) b = BS_MESH_TIME_BUDGET;
  budget_ = b > 0 && isfinite(b) ? b : 0.0;
  deadline_ = budget_ > 0 ? bs_seconds() + budget_ : 0.0;
}

void bs__budget_end(void) {
  deadline_ = budget_ = 0.0;
  report_ = NULL;
}

struct bs_surface_report *bs__read_report(void) { return report_; }

double bs__budget_deadline(void) { return deadline_; }

int bs__budget_check(const char *path, const char *stage, bs_error *err) {
  if (!(deadline_ > 0) || bs_seconds() <= deadline_) return BS_OK;
  return bs_error_set(err, BS_EINPUT,
                      "%s: the meshing time budget of %g s (bs_mesh_read_opts.time_budget, bigstep mesh --time-budget) was exceeded before %s",
                      path, budget_, stage);
}

int bs__budget_exceeded(const bs_error *err) {
  return err && err->code == BS_EINPUT && (strstr(err->msg, "time budget") != NULL);
}

void bs__budget_note(bs_error *err) {
  if (!bs__budget_exceeded(err) || strstr(err->msg, "time budget of") || !(budget_ > 0)) return;
  const size_t n = strlen(err->msg);
  snprintf(err->msg + n, sizeof err->msg - n,
           " (the budget: %g s, bs_mesh_read_opts.time_budget, bigstep mesh --time-budget)", budget_);
}
