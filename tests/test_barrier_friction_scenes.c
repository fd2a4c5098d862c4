/* test_barrier_friction_scenes.c — friction of the barrier self-contact
 * (self_collision.model "barrier" with self_collision.friction) in scenes:
 * a box resting on a fixed box under gravity tilted by theta (the incline
 * is the gravity's) sticks for mu > tan(theta) and slides with the
 * acceleration g (sin theta - mu cos theta) within 1% for mu < tan(theta)
 * (as test_barrier_obstacles' incline against a barrier plane). The term
 * itself: test_barrier_friction.c. */
#include <criterion/criterion.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <math.h>
#include <stdio.h>

#include "bs_ipc_friction.h"
#include "bs_scene.h"
#include "bs_sim.h"

/* Box 1 (0.2 x 0.2 x 0.1 m, 2 x 2 x 1 cells) 0.5 mm above box 0 (1 x 0.4
 * x 0.1 m, 4 x 2 x 1 cells, its bottom fixed), dhat 1 mm, both stiff
 * (E = 1e7 Pa), gravity 9.8 m/s^2 tilted by theta about y: the incline is
 * the gravity's, downhill +x. 50 frames/s, one step each. Returns box 1's
 * mean velocity along +x at frames f1 and f2 and its mean x displacement
 * at f2 (and the largest over the frames in *dmax). */
static void slope(double theta_deg, double mu, int f1, int f2, double *v1, double *v2, double *dx, double *dmax) {
  const double th = theta_deg * M_PI / 180;
  char text[2048];
  snprintf(text, sizeof text,
           "{\"time\": {\"fps\": 50, \"frames\": %d, \"steps_per_frame\": 1},\n"
           " \"solver\": {\"method\": \"optimization\", \"tolerance\": 1e-7},\n"
           " \"gravity\": [%.17g, 0, %.17g],\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [4, 2, 1], \"size\": [1, 0.4, 0.1]},\n"
           "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000},\n"
           "   \"scripted\": [{\"group\": \"zmin\", \"fixed\": true}]},\n"
           "  {\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 1], \"size\": [0.2, 0.2, 0.1]},\n"
           "   \"translate\": [0.05, 0.1, 0.1005],\n"
           "   \"material\": {\"model\": \"neo_hookean\", \"youngs\": 1e7, \"poisson\": 0.3, \"density\": 1000}}],\n"
           " \"self_collision\": {\"model\": \"barrier\", \"friction\": %g}, \"contact\": {\"dhat\": 0.001}}\n",
           f2, 9.8 * sin(th), -9.8 * cos(th), mu);
  bs_scene *sc = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_scene_parse(text, "test", 0, NULL, &sc, &err), 0, "%s", err.msg);
  bs_sim *s = NULL;
  cr_assert_eq(bs_sim_create(sc, &s, &err), 0, "%s", err.msg);
  cr_assert_not_null(s->barrier_friction);
  cr_assert_null(s->friction_impulse, "a post-solve friction pass for barrier contact");
  const int32_t b0 = s->vertex_offset[1], b1 = s->vertex_offset[2];
  *dmax = 0;
  for (int f = 1; f <= f2; f++) {
    bs_frame_stats fs;
    cr_assert_eq(bs_sim_advance_frame(s, &fs, &err), 0, "frame %d: %s", f, err.msg);
    cr_assert_eq(fs.failed, 0, "frame %d", f);
    double v = 0, d = 0, mass = 0;
    for (int32_t i = b0; i < b1; i++) {
      const double m = s->fem->mass[i];
      v += m * s->v[3 * i];
      d += m * (s->x[3 * i] - s->x0[3 * i]);
      mass += m;
    }
    v /= mass, d /= mass;
    *dmax = fmax(*dmax, fabs(d));
    if (f == f1) *v1 = v;
    if (f == f2) *v2 = v, *dx = d;
  }
  bs_ipc_friction_stats st;
  cr_assert_eq(bs_term_ipc_friction_stats(s->barrier_friction, &st, &err), 0);
  cr_assert_gt(st.pairs_pt + st.pairs_ee, 0, "no friction pair at the end");
  const double weight = 9.8 * cos(th) * 4.0; /* box 1: 4 kg */
  fprintf(stderr, "mu %g: %lld + %lld pairs, normal force %.4f N (weight's normal part %.4f N)\n", mu,
          (long long)st.pairs_pt, (long long)st.pairs_ee, st.normal_force, weight);
  cr_assert_lt(fabs(st.normal_force - weight), 0.05 * weight); /* the lagged lambdas carry the box */
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

Test(barrier_friction, box_on_a_box_sticks_below_the_friction_angle, .timeout = 900) {
  double v1 = 0, v2 = 0, dx = 0, dmax = 0; /* tan 20 deg = 0.364 < mu = 0.5 */
  slope(20, 0.5, 10, 25, &v1, &v2, &dx, &dmax);
  fprintf(stderr, "stick: v(0.2 s) = %.3e, v(0.5 s) = %.3e m/s, x displacement %.3e m (max %.3e) over 25 frames\n",
          v1, v2, dx, dmax);
  cr_assert_lt(fabs(v2), 1e-3);
  cr_assert_lt(dmax, 5e-4);
}

Test(barrier_friction, box_on_a_box_slides_with_the_coulomb_acceleration, .timeout = 900) {
  double v1 = 0, v2 = 0, dx = 0, dmax = 0; /* tan 20 deg = 0.364 > mu = 0.2 */
  slope(20, 0.2, 10, 30, &v1, &v2, &dx, &dmax);
  const double th = 20 * M_PI / 180, a = (v2 - v1) / 0.4, want = 9.8 * (sin(th) - 0.2 * cos(th));
  fprintf(stderr, "slide: v(0.2 s) = %.6f, v(0.6 s) = %.6f, a = %.6f, analytic %.6f (%.3f%%), x displacement %.4f m\n",
          v1, v2, a, want, 100 * (a - want) / want, dx);
  cr_assert_lt(fabs(a - want), 0.01 * want, "a = %g, want %g", a, want);
}
