/* test_dist_collide: constraint collisions and the relative tolerances on
 * the petsc backend give the serial answers, on 1 and 2 ranks:
 *  - the squeezed cube (data/scenes/box_squeeze.json, friction 0, its first
 *    frames: resting on a constraint plane, the left constraint box reaching
 *    it in frame 5), with cg and pcg: positions to 1e-9, the same Newton
 *    iterations per frame on 1 rank (cg), active pairs in every frame, no
 *    vertex inside an obstacle (as the serial run), no vertex left of the
 *    moving box's face;
 *  - the cantilever (data/scenes/beam_sag.json) resting on a constraint
 *    plane below its tip, statics: positions, iterations, active pairs;
 *  - solver.load_rtol and solver.rtol on the cantilever: the same tolerance
 *    as the serial solve, iterations and positions. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dsim.h"
#include "bs_sim.h"
#include "dist_check.h"
#include "dist_compare.h"

/* The scene with its settings on both backends (NULL when it failed). */
static void create_both(const char *path, int n, const char **sets, bs_scene **sc, bs_sim **s, bs_dsim **d) {
  bs_error err = {0};
  *s = NULL, *d = NULL;
  CHECK_OK(bs_scene_load(path, n, sets, sc, &err), err);
  if (!*sc) return;
  CHECK_OK(bs_sim_create(*sc, s, &err), err);
  CHECK_OK(bs_dsim_create(*sc, d, &err), err);
}

static void destroy_both(bs_scene **sc, bs_sim **s, bs_dsim **d) {
  bs_dsim_destroy(d);
  bs_sim_destroy(s);
  bs_scene_destroy(sc);
}

/* Penetration on the backend: none, and the serial count. */
static void check_penetration(bs_dsim *d, const bs_sim *s, const char *what) {
  bs_error err = {0};
  int64_t pd = -1;
  int32_t ps = -1;
  double dd = 0, ds = 0;
  CHECK_OK(bs_dsim_penetration(d, &pd, &dd, &err), err);
  bs_sim_penetration(s, &ps, &ds);
  CHECK(pd == 0 && ps == 0, "%s: %lld vertices inside obstacles (serial %d)", what, (long long)pd, ps);
  CHECK(dd <= 1e-10 * d->size, "%s: max depth %g", what, dd);
}

/* The smallest x over the vertices (all ranks). */
static double min_x(const bs_dsim *d) {
  double m = INFINITY;
  for (int32_t v = 0; v < d->mesh->n_vertices; v++) m = fmin(m, d->x[3 * v]);
  MPI_Allreduce(MPI_IN_PLACE, &m, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  return m;
}

/* box_squeeze without friction, 6 frames, with solver.linear = linear and
 * solver.tolerance = tol: the floor holds the cube from the first frame, the
 * left box's face (x = -0.05 + 0.25 t) pushes it from t = 0.2 on. The same
 * Newton iterations per frame on 1 rank when same_iterations. */
static void box_squeeze_with(const char *linear, double tol, int same_iterations) {
  char lin[64], tl[64];
  snprintf(lin, sizeof lin, "solver.linear=%s", linear);
  snprintf(tl, sizeof tl, "solver.tolerance=%g", tol);
  const char *sets[] = {"time.frames=6", "obstacles.0.friction=0", lin, tl};
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_dsim *d = NULL;
  bs_error err = {0};
  create_both("data/scenes/box_squeeze.json", 4, sets, &sc, &s, &d);
  long it_s = 0, it_d = 0, pairs_min = -1;
  for (int f = 0; s && d && f < sc->frames; f++) {
    long is = 0, id = 0;
    advance_both(s, d, 1, same_iterations ? 0 : -1, &is, &id);
    it_s += is, it_d += id;
    int64_t pairs = 0;
    CHECK_OK(bs_dsim_active_pairs(d, &pairs, &err), err);
    CHECK(pairs > 0, "frame %d: no active pair", f + 1);
    if (pairs_min < 0 || pairs < pairs_min) pairs_min = (long)pairs;
  }
  if (s && d) {
    compare(d, s, lin, NULL, 0);
    check_penetration(d, s, lin);
    const double face = -0.05 + 0.25 * d->time, xl = min_x(d);
    CHECK(xl > 0 && xl >= face - 1e-9, "leftmost x %.6g, the box's face at %.6g", xl, face);
    if (bs_dist_rank() == 0)
      printf("  box_squeeze (%s): Newton iterations %ld (serial %ld), active pairs >= %ld per frame, leftmost x %.6f "
             "(face %.6f)\n",
             linear, it_d, it_s, pairs_min, xl, face);
  }
  destroy_both(&sc, &s, &d);
}

static void box_squeeze_frames(void) { box_squeeze_with("cg", 1e-3, 1); }

/* Point-block Jacobi: the blocks an active constraint leaves singular get
 * the serial pcg's fallback (the identity) on both backends. Its solves are
 * long (about 2000 CG iterations a frame, 180 without it), so the two
 * backends' roundings (vertex orders, sums) give other CG iterates: at the
 * scene's tolerance the answers are 7e-9 of the positions apart on 2 ranks,
 * and a step can take other Newton iterations (frame 3 at 1e-6: 5 serial, 2
 * petsc, both converged). So a tighter tolerance, the answers compared, not
 * the iteration counts. */
static void box_squeeze_pcg(void) { box_squeeze_with("pcg", 1e-6, 0); }

/* Statics of the two backends: converged, on 1 rank within one Newton
 * iteration of each other (the two backends' CG reductions round
 * differently, PETSc's against bs_sum's: beam_sag's rtol and load_rtol
 * cases take 8 serial and 7 distributed iterations on one machine, the
 * same count on another; as cube_stretch's adaptive forcing in
 * test_dist_solve). */
static void statics_both(bs_sim *s, bs_dsim *d, const char *what, bs_frame_stats *fs) {
  bs_error err = {0};
  bs_frame_stats fd;
  CHECK_OK(bs_sim_statics(s, fs, &err), err);
  CHECK_OK(bs_dsim_statics(d, &fd, &err), err);
  const bs_step_stats *st = &d->steps[0].st;
  CHECK(!st->failed, "%s: the distributed solve failed: %s", what, st->min.reason_text);
  if (bs_dist_size() == 1)
    CHECK(labs(st->min.iterations - fs->iterations) <= 1, "%s: %d Newton iterations, serial %ld", what,
          st->min.iterations, fs->iterations);
  if (bs_dist_rank() == 0)
    printf("  %s: Newton iterations %d (serial %ld), tolerance used %.6e (serial %.6e)\n", what, st->min.iterations,
           fs->iterations, st->min.tol_used, s->steps[0].st.min.tol_used);
}

/* The cantilever (tip deflection 7.5 mm free) on a constraint plane 4 mm
 * below its bottom face. */
static void beam_on_plane(void) {
  const char *sets[] = {"qoi=[]", "obstacles=[{\"shape\":\"plane\",\"normal\":[0,1,0],\"offset\":-0.004}]"};
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_dsim *d = NULL;
  bs_error err = {0};
  create_both("data/scenes/beam_sag.json", 2, sets, &sc, &s, &d);
  if (s && d) {
    bs_frame_stats fs;
    statics_both(s, d, "beam on a plane", &fs);
    compare(d, s, "beam on a plane", "xmax", 1e-9);
    int64_t pairs = 0;
    CHECK_OK(bs_dsim_active_pairs(d, &pairs, &err), err);
    CHECK(pairs > 0, "no active pair: the beam does not reach the plane");
    check_penetration(d, s, "beam on a plane");
    if (bs_dist_rank() == 0) printf("  beam on a plane: %lld active pairs\n", (long long)pairs);
  }
  destroy_both(&sc, &s, &d);
}

/* The cantilever with a relative tolerance `set` that sets the solve's
 * tolerance above solver.tolerance (1e-9 here). */
static void beam_relative(const char *set, const char *what) {
  const char *sets[] = {"qoi=[]", "solver.tolerance=1e-9", set};
  bs_scene *sc = NULL;
  bs_sim *s = NULL;
  bs_dsim *d = NULL;
  create_both("data/scenes/beam_sag.json", 3, sets, &sc, &s, &d);
  if (s && d) {
    bs_frame_stats fs;
    statics_both(s, d, what, &fs);
    const double td = d->steps[0].st.min.tol_used, ts = s->steps[0].st.min.tol_used;
    CHECK(td > 10 * 1e-9, "%s: tolerance used %g: the relative tolerance is not in effect", what, td);
    CHECK_REL(td, ts, 1e-9, "tolerance used");
    compare(d, s, what, "xmax", 1e-9);
  }
  destroy_both(&sc, &s, &d);
}

static void beam_load_rtol(void) { beam_relative("solver.load_rtol=1e-7", "beam_sag load_rtol"); }
static void beam_rtol(void) { beam_relative("solver.rtol=1e-7", "beam_sag rtol"); }

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"box_squeeze_frames", box_squeeze_frames},
                                    {"box_squeeze_pcg", box_squeeze_pcg},
                                    {"beam_on_plane", beam_on_plane},
                                    {"beam_load_rtol", beam_load_rtol},
                                    {"beam_rtol", beam_rtol}};
  return dist_check_main(argc, argv, tests, 5);
}
