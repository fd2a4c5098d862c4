/* Convergence studies of issue 6 that must hold:
 *  - space: the static beam_sag tip deflection converges under uniform
 *    refinement at an order P1 tets can show, towards a Richardson limit that
 *    agrees with Timoshenko beam theory (the levels through `bigstep study`,
 *    the tight-tolerance check through the library);
 *  - tolerance: the error against a tight-tolerance run falls monotonically as
 *    the solver tolerance falls (through `bigstep study` and its study.csv).
 * (Time: study.backward_euler_is_first_order_in_time in test_study.c.) */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_runfolder.h"
#include "cli_util.h"
#include "sim_util.h"

/* Mean y displacement (x minus rest) of the vertices among the first n_coarse
 * whose rest x is the beam's free end x_tip. Returns how many were averaged. */
static int tip_from(const double *rest, const double *x, int32_t n, int n_coarse, double x_tip, double *tip) {
  if (n < n_coarse) return 0;
  int found = 0;
  double s = 0;
  for (int i = 0; i < n_coarse; i++)
    if (fabs(rest[3 * i] - x_tip) < 1e-9) {
      s += x[3 * i + 1] - rest[3 * i + 1];
      found++;
    }
  if (found) *tip = s / found;
  return found;
}

/* The same between the first and the last frame of dir/state.bin (0 on a read
 * error or with fewer than two frames). */
static int tip_deflection(const char *dir, int n_coarse, double x_tip, double *tip) {
  bs_state_reader r;
  bs_error err;
  if (bs_state_open(dir, &r, &err)) return 0;
  int found = 0;
  size_t m = 3 * (size_t)r.n;
  double *rest = malloc(sizeof(double) * m);
  int frames = 0;
  if (bs_state_next(&r) == 0) {
    memcpy(rest, r.x, sizeof(double) * m);
    frames = 1;
    while (bs_state_next(&r) == 0) frames++;
  }
  if (frames >= 2) found = tip_from(rest, r.x, r.n, n_coarse, x_tip, tip); /* r.x: the last frame read */
  free(rest);
  bs_state_close(&r);
  return found;
}

/* beam_sag: 1 x 0.1 x 0.1 m, cells [20, 2, 2], E = 1e8 Pa, nu = 0.3, rho = 1000,
 * clamped at x = 0, static under gravity. Uniform refinement 0..3 (540 to
 * 138720 dofs) with CHOLMOD, so that each level takes three Newton steps.
 * Measured (tip deflection, m): -0.0074776, -0.0117462, -0.0137664, -0.0144513;
 * successive differences shrink by 2.11 and 2.95 (orders 1.08 and 1.56: the
 * coarse bending-dominated beam locks and the order rises towards the
 * asymptotic 2 of P1 displacements); Richardson limit -0.014802, the finest
 * level 2.4% from it; Timoshenko: q L^4 / (8 E I) + q L^2 / (2 kappa G A)
 * = 0.014847 m, 0.3% from the limit. */
Test(convergence, static_beam_tip_converges_under_refinement) {
  char dir[] = "/tmp/bs_conv_XXXXXX";
  cr_assert_not_null(mkdtemp(dir));
  const int n_coarse = 21 * 3 * 3;
  char cmd[4096], *out = NULL, p[512];
  snprintf(cmd, sizeof cmd,
           "%s study %s/data/scenes/beam_sag.json --out %s/study --set solver.linear=cholmod --vary refine=0,1,2,3 --qoi tip_y",
           BS_BIGSTEP_EXE, BS_SOURCE_DIR, dir);
  int rc = bs_test_run(cmd, &out);
  cr_assert_eq(rc, 0, "%s", out);
  const char *s = strstr(out, "order in space (error ~ h^p, vs refine): method optimization p = ");
  cr_expect_not_null(s, "the study summary should give the order in space:\n%s", out);
  cr_expect(strstr(out, "4 runs (0 failed, 0 timed out)") != NULL, "every level must converge:\n%s", out);
  /* the scene's quantity tip_y (mean y displacement of the xmax group): GCI of refine 1-3 */
  const char *g = strstr(out, "tip_y along refine");
  const char *x = g ? strstr(g, "Richardson extrapolated ") : NULL;
  double ext = x ? atof(x + strlen("Richardson extrapolated ")) : NAN;
  cr_expect(fabs(ext + 0.014802) < 2e-6, "the extrapolated tip deflection %.7g m, expected -0.014802:\n%s", ext, out);
  cr_expect(g && strstr(g, "observed order p = 1.5"), "the observed order of refine 1-3 is 1.56:\n%s", out);
  free(out);
  double u[4];
  for (int r = 0; r < 4; r++) {
    snprintf(p, sizeof p, "%s/study/refine=%d", dir, r);
    cr_assert_eq(tip_deflection(p, n_coarse, 1.0, &u[r]), 9, "%s: the 9 tip vertices of the coarse mesh", p);
  }
  /* the solver error is far below the discretization error: refine 2 again at
     a tighter tolerance (at 1e-6 it stops at |grad E| 4.5e-7 after 3 Newton
     steps; round-off keeps |grad E| near 1e-8, so 5e-8 forces one more step) */
  double u2_tight = NAN;
  {
    sim_rec rec;
    bs_run_totals T;
    bs_scene *sc = NULL;
    bs_sim *s = sim_run_scene(BS_SOURCE_DIR "/data/scenes/beam_sag.json",
                              "bodies.0.refine=2 solver.linear=cholmod solver.tolerance=5e-8 solver.max_iterations=30",
                              NULL, &rec, &T, 1, &sc);
    cr_assert_eq(T.failed, 0, "tight: %s", T.first_fail_reason);
    cr_assert_eq(tip_from(s->x0, s->x, s->mesh->n_vertices, n_coarse, 1.0, &u2_tight), 9);
    bs_sim_destroy(&s);
    bs_scene_destroy(&sc);
  }
  double d01 = u[0] - u[1], d12 = u[1] - u[2], d23 = u[2] - u[3];
  double p1 = log2(d01 / d12), p2 = log2(d12 / d23);
  double u_inf = u[3] - d23 / (pow(2.0, p2) - 1); /* Richardson with the observed order */
  double q = 1000 * 9.8 * 0.1 * 0.1, EI = 1e8 * 0.1 * pow(0.1, 3) / 12, G = 1e8 / (2 * 1.3);
  double kappa = 10 * 1.3 / (12 + 11 * 0.3), timoshenko = -(q / (8 * EI) + q / (2 * kappa * G * 0.01));
  fprintf(stderr,
          "beam_sag tip deflection (m) at refine 0..3: %.7g %.7g %.7g %.7g; orders %.3f %.3f; Richardson limit %.7g "
          "(errors %.3g%% %.3g%% %.3g%% %.3g%%); Timoshenko %.7g; solver error at refine 2: %.3g m\n",
          u[0], u[1], u[2], u[3], p1, p2, u_inf, 100 * fabs(u[0] / u_inf - 1), 100 * fabs(u[1] / u_inf - 1),
          100 * fabs(u[2] / u_inf - 1), 100 * fabs(u[3] / u_inf - 1), timoshenko, fabs(u[2] - u2_tight));

  /* the beam sags, more with every level (P1 tets are too stiff in bending) */
  cr_expect(u[0] < 0 && d01 > 0 && d12 > 0 && d23 > 0, "the deflection must grow under refinement: %g %g %g %g", u[0],
            u[1], u[2], u[3]);
  /* P1: displacement error ~ h^2 asymptotically; a coarse locking beam is
     pre-asymptotic (order between 1 and 2), rising with refinement */
  cr_expect(p1 >= 0.8 && p1 <= 2.3 && p2 >= 0.8 && p2 <= 2.3, "observed orders %g, %g outside P1's 0.8..2.3", p1, p2);
  cr_expect(p2 > p1, "the observed order should rise towards 2 under refinement: %g then %g", p1, p2);
  /* towards the extrapolated limit */
  double e[4];
  for (int r = 0; r < 4; r++) e[r] = fabs(u[r] - u_inf);
  cr_expect(e[0] > e[1] && e[1] > e[2] && e[2] > e[3], "errors against the limit must fall: %g %g %g %g", e[0], e[1],
            e[2], e[3]);
  cr_expect(e[3] < 0.05 * fabs(u_inf), "the finest level is %.3g%% from the Richardson limit (want < 5%%)",
            100 * e[3] / fabs(u_inf));
  cr_expect(fabs(u_inf / timoshenko - 1) < 0.03, "Richardson limit %g vs Timoshenko beam theory %g", u_inf, timoshenko);
  /* the solver error is negligible next to the finest discretization error */
  cr_expect(fabs(u[2] - u2_tight) < 1e-3 * e[3], "solver error %g against discretization error %g",
            fabs(u[2] - u2_tight), e[3]);
}

/* Column `name` of every data row of a study.csv (the run name, first,
 * holds commas, so fields are counted from the right end). Returns rows. */
static int csv_column(const char *path, const char *name, char vals[][64], int max_rows) {
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  char line[8192];
  int n_head = 0, idx = -1, rows = 0;
  if (fgets(line, sizeof line, f)) {
    line[strcspn(line, "\n")] = 0;
    for (char *t = strtok(line, ","); t; t = strtok(NULL, ","), n_head++)
      if (!strcmp(t, name)) idx = n_head;
  }
  while (idx >= 0 && rows < max_rows && fgets(line, sizeof line, f)) {
    line[strcspn(line, "\n")] = 0;
    char *cell[128];
    int n = 0;
    for (char *t = strtok(line, ","); t && n < 128; t = strtok(NULL, ",")) cell[n++] = t;
    int c = n - (n_head - idx);
    snprintf(vals[rows++], 64, "%s", c >= 0 && c < n ? cell[c] : "");
  }
  fclose(f);
  return idx >= 0 ? rows : -1;
}

/* cube_stretch at 4^3 cells, 6 frames: the study's position and velocity
 * errors against the tau = 1e-9 reference fall monotonically with tau.
 * Measured position errors (max over frames / body size): 5.6e-9, 1.2e-10,
 * 4.8e-13 at tau = 1e-2, 1e-4, 1e-6 (falling 45x and 255x per 100x in tau). */
Test(convergence, error_falls_with_solver_tolerance) {
  char dir[] = "/tmp/bs_conv_XXXXXX";
  cr_assert_not_null(mkdtemp(dir));
  char cmd[4096], *out = NULL, p[512];
  snprintf(cmd, sizeof cmd,
           "%s study %s/data/scenes/cube_stretch.json --out %s/study --set 'bodies.0.box.cells=[4,4,4]' "
           "--set time.frames=6 --vary solver.tolerance=1e-2,1e-4,1e-6,1e-9",
           BS_BIGSTEP_EXE, BS_SOURCE_DIR, dir);
  int rc = bs_test_run(cmd, &out);
  cr_assert_eq(rc, 0, "%s", out);
  free(out);
  static char tol[8][64], exitc[8][64], ref[8][64], pos[8][64], vel[8][64];
  snprintf(p, sizeof p, "%s/study/study.csv", dir);
  cr_assert_eq(csv_column(p, "solver.tolerance", tol, 8), 4, "study.csv: 4 runs");
  cr_assert_eq(csv_column(p, "exit", exitc, 8), 4);
  cr_assert_eq(csv_column(p, "reference", ref, 8), 4);
  cr_assert_eq(csv_column(p, "pos_err_max", pos, 8), 4);
  cr_assert_eq(csv_column(p, "vel_err_max", vel, 8), 4);
  static const char *order[4] = {"1e-2", "1e-4", "1e-6", "1e-9"};
  double ex[4] = {NAN, NAN, NAN, NAN}, ev[4] = {NAN, NAN, NAN, NAN};
  for (int r = 0; r < 4; r++)
    for (int k = 0; k < 4; k++)
      if (!strcmp(tol[r], order[k])) {
        cr_expect_str_eq(exitc[r], "0", "tolerance %s: the run failed", order[k]);
        cr_expect_str_eq(ref[r], k == 3 ? "1" : "0", "the reference is the tightest tolerance");
        ex[k] = atof(pos[r]);
        ev[k] = atof(vel[r]);
      }
  fprintf(stderr, "cube_stretch 4^3: position errors %g %g %g %g, velocity errors %g %g %g %g at tau 1e-2..1e-9\n",
          ex[0], ex[1], ex[2], ex[3], ev[0], ev[1], ev[2], ev[3]);
  cr_expect(ex[3] == 0 && ev[3] == 0, "the reference has zero error: %g %g", ex[3], ev[3]);
  for (int k = 0; k < 2; k++) {
    cr_expect(ex[k] > 0 && ex[k + 1] > 0, "a looser tolerance has a positive error: %g %g", ex[k], ex[k + 1]);
    cr_expect(ex[k + 1] < ex[k] / 5, "the position error must fall with tau (%s: %g, %s: %g)", order[k], ex[k],
              order[k + 1], ex[k + 1]);
    cr_expect(ev[k + 1] < ev[k], "the velocity error must fall with tau (%s: %g, %s: %g)", order[k], ev[k],
              order[k + 1], ev[k + 1]);
  }
}
