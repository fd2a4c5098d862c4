/* Stability at the extremes (issue 6):
 *  - NaN or Inf injected into a state or a parameter (a scene key through an
 *    override, or a mesh vertex) is refused by bs_scene_load / bs_sim_create
 *    with an error naming it;
 *  - a ball hitting the ground at 1e3 m/s with constraint collisions: no vertex
 *    inside the ground after any step;
 *  - a Gmsh mesh with sliver tets (data/geo/sliver.geo, dihedral angles below
 *    1 degree): `bigstep mesh info` counts them and warns (the one command line
 *    use here), and a scene on it runs (the contract of test_extreme_util.h);
 *    both relax the quality gate (--min-dihedral 0, "min_dihedral": 0). */
#define _POSIX_C_SOURCE 200809L
#include "cli_util.h"
#include "test_extreme_util.h"

#define CUBE BS_SOURCE_DIR "/data/scenes/cube_stretch.json"
#define BALL BS_SOURCE_DIR "/data/scenes/sphere_drop.json"

/* Loads SCENE with one override (then creates the simulation) and expects a
 * refusal (BS_EINPUT) whose message names KEY and contains WHAT: the message
 * `bigstep run` prints after "bigstep run: ". Nothing can have run. */
static void refused(const char *scene, const char *set, const char *key, const char *what) {
  bs_error err;
  int rc = sim_load_error(scene, &set, 1, &err);
  cr_log_info("set %s: %d: %s", set, rc, err.msg);
  cr_expect_eq(rc, BS_EINPUT, "set %s: status %d: %s", set, rc, err.msg);
  cr_expect(strstr(err.msg, key) != NULL, "set %s: the error does not name '%s': %s", set, key, err.msg);
  cr_expect(strstr(err.msg, what) != NULL, "set %s: the error does not say '%s': %s", set, what, err.msg);
}

Test(extreme_input, inf_in_state_refused) {
  refused(CUBE, "bodies.0.velocity=[0,1e999,0]", "bodies.0.velocity", "element 1 must be a finite number");
  refused(CUBE, "bodies.0.angular_velocity=[1e999,0,0]", "bodies.0.angular_velocity",
          "element 0 must be a finite number");
  refused(CUBE, "bodies.0.translate=[0,-1e999,0]", "bodies.0.translate", "element 1 must be a finite number");
  refused(CUBE, "bodies.0.initial_state={\"type\":\"point\",\"point\":[1e999,0,0]}", "bodies.0.initial_state.point",
          "finite");
  refused(CUBE, "bodies.0.initial_state={\"type\":\"random\",\"lo\":[0,0,0],\"hi\":[1,-1e999,1],\"seed\":1}",
          "bodies.0.initial_state.hi", "finite");
  refused(CUBE, "bodies.0.scripted.0.keyframes.1.offset=[1e999,0,0]", "bodies.0.scripted.0.keyframes.1.offset",
          "finite");
  /* JSON has no NaN: the value stays a string, refused for its type. */
  refused(CUBE, "bodies.0.velocity=[0,NaN,0]", "bodies.0.velocity", "must be an array of 3 numbers");
}

Test(extreme_input, inf_in_parameter_refused) {
  refused(CUBE, "bodies.0.material.youngs=1e999", "bodies.0.material.youngs", "must be finite, got inf");
  refused(CUBE, "bodies.0.material.youngs=-1e999", "bodies.0.material.youngs", "must be finite, got -inf");
  refused(CUBE, "bodies.0.material.poisson=1e999", "bodies.0.material.poisson", "must be finite");
  refused(CUBE, "bodies.0.material.density=1e999", "bodies.0.material.density", "must be finite");
  refused(CUBE, "bodies.0.material.rayleigh=1e999", "bodies.0.material.rayleigh", "must be finite");
  refused(CUBE, "gravity=[0,1e999,0]", "gravity", "finite");
  refused(CUBE, "drag=1e999", "drag", "must be finite");
  refused(CUBE, "time.fps=1e999", "time.fps", "must be finite");
  refused(CUBE, "solver.tolerance=1e999", "solver.tolerance", "must be finite");
  refused(BALL, "obstacles.0.offset=1e999", "obstacles.0.offset", "must be finite");
  refused(BALL, "obstacles.0.stiffness=1e999", "obstacles.0.stiffness", "must be finite");
  refused(BALL, "obstacles.0.normal=[0,1e999,0]", "obstacles.0.normal", "finite");
  refused(BALL, "bodies.0.mesh_size=1e999", "bodies.0.mesh_size", "must be finite");
}

/* A mesh file whose vertex 7 (of box:1) has a NaN or Inf coordinate. */
static void bad_vertex(const char *token) {
  char msh[128], json[128], path[256];
  snprintf(msh, sizeof msh, "/tmp/bs_extreme_%s.msh", token);
  snprintf(json, sizeof json, "/tmp/bs_extreme_%s.json", token);
  bs_mesh *box = NULL;
  bs_error err;
  cr_assert_eq(bs_mesh_load("box:1", NULL, &box, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_mesh_write_msh(box, NULL, msh, &err), 0, "%s", err.msg);
  bs_mesh_destroy(&box);
  /* The last node line "1 1 1" (vertex 8 in the file, 7 counted from 0) becomes "1 TOKEN 1". */
  FILE *f = fopen(msh, "r");
  cr_assert_not_null(f);
  char *text = calloc(1 << 16, 1);
  size_t n = fread(text, 1, (1 << 16) - 1, f);
  fclose(f);
  text[n] = '\0';
  char *p = strstr(text, "\n1 1 1\n");
  cr_assert_not_null(p, "no node '1 1 1' in %s", msh);
  f = fopen(msh, "w");
  cr_assert_not_null(f);
  fprintf(f, "%.*s\n1 %s 1\n%s", (int)(p - text), text, token, p + 7);
  fclose(f);
  free(text);
  f = fopen(json, "w");
  cr_assert_not_null(f);
  fprintf(f, "{\"time\": {\"fps\": 24, \"frames\": 1}, \"gravity\": [0, 0, 0],\n"
             " \"bodies\": [{\"mesh\": \"%s\",\n"
             "   \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}]}\n",
          msh);
  fclose(f);
  int rc = sim_load_error(json, NULL, 0, &err);
  snprintf(path, sizeof path, "node 8 has a non-finite coordinate (1, %s, 1)", token); /* vertex 7 */
  cr_log_info("mesh vertex %s: %d: %s", token, rc, err.msg);
  cr_expect_eq(rc, BS_ENUMERIC, "status %d: %s", rc, err.msg);
  cr_expect(strstr(err.msg, msh) != NULL, "the error does not name %s: %s", msh, err.msg);
  cr_expect(strstr(err.msg, path) != NULL, "the error does not say '%s': %s", path, err.msg);
}

Test(extreme_input, nan_and_inf_mesh_vertex_refused) {
  bad_vertex("nan");
  bad_vertex("inf");
}

/* The ball of sphere_drop thrown at the ground at 1e3 m/s: in the first 1/24 s
 * step it would travel 42 m, so the constraint holds every vertex on the ground
 * (the body flattens: all its tets degenerate) and it must recover. */
static ext_run impact(const char *method, const char *fps, int frames) {
  char sets[512], tag[96];
  snprintf(sets, sizeof sets,
           "bodies.0.mesh_size=0.2 bodies.0.velocity=[0,-1000,0] solver.method=%s time.frames=%d time.fps=%s "
           "solver.max_iterations=%d",
           method, frames, fps, strcmp(method, "newton") ? 200 : 30);
  snprintf(tag, sizeof tag, "impact_%s_fps%s", method, fps);
  ext_run r = ext_run_scene(BALL, sets, tag);
  cr_expect_eq(r.max_penetrating, 0, "%s at %s fps: %d vertices inside the ground", method, fps, r.max_penetrating);
  return r;
}

Test(extreme_input, impact_1e3_m_per_s_constraint_no_penetration, .timeout = 600) {
  ext_run r = impact("optimization", "24", 4);
  cr_expect_eq(r.failed, 0, "%ld failed steps [%s]", r.failed, r.reason);
  cr_expect_eq(r.last_inverted, 0, "%d tets still inverted after 4 frames", r.last_inverted);
  ext_run_free(&r);
  r = impact("optimization", "240", 3);
  cr_expect_eq(r.failed, 0, "%ld failed steps [%s]", r.failed, r.reason);
  ext_run_free(&r);
  r = impact("newton", "24", 3);
  ext_run_free(&r);
  r = impact("newton", "240", 3);
  ext_run_free(&r);
}

Test(extreme_input, sliver_mesh_warns_and_runs, .timeout = 600) {
  char *out = NULL, cmd[1024];
  snprintf(cmd, sizeof cmd, "LSAN_OPTIONS=suppressions=%s/tests/lsan.supp:print_suppressions=0 %s mesh info "
           "%s/data/geo/sliver.geo --min-dihedral 0", BS_SOURCE_DIR, BS_BIGSTEP_EXE, BS_SOURCE_DIR);
  int rc = bs_test_run(cmd, &out);
  cr_log_info("%s", out);
  cr_assert_eq(rc, 0, "%s", out);
  const char *q = strstr(out, "slivers (dihedral < 1 deg) ");
  cr_assert_not_null(q, "no sliver count in:\n%s", out);
  int slivers = atoi(q + strlen("slivers (dihedral < 1 deg) "));
  cr_expect_gt(slivers, 0, "sliver.geo has no sliver:\n%s", out);
  const char *d = strstr(out, "dihedral angles     [");
  cr_assert_not_null(d, "%s", out);
  double dmin = strtod(d + strlen("dihedral angles     ["), NULL);
  cr_expect(dmin > 0 && dmin < 1.0, "smallest dihedral angle %g degrees is not below 1", dmin);
  cr_expect(strstr(out, "warning") != NULL && strstr(out, "sliver") != NULL, "no warning about slivers:\n%s", out);
  free(out);

  /* The plate clamped along x = 0, sagging under gravity along -z. */
  FILE *f = fopen("/tmp/bs_extreme_sliver.json", "w");
  cr_assert_not_null(f);
  fprintf(f, "{\"time\": {\"fps\": 24, \"frames\": 4}, \"gravity\": [0, 0, -9.8],\n"
             " \"bodies\": [{\"mesh\": \"%s/data/geo/sliver.geo\", \"min_dihedral\": 0,\n"
             "   \"material\": {\"youngs\": 1e6, \"poisson\": 0.3, \"density\": 1000},\n"
             "   \"scripted\": [{\"group\": \"left\", \"fixed\": true}]}]}\n",
          BS_SOURCE_DIR);
  fclose(f);
  ext_run r = ext_run_scene("/tmp/bs_extreme_sliver.json", "solver.method=optimization", "sliver_optimization");
  cr_expect_eq(r.failed, 0, "%ld failed steps [%s]", r.failed, r.reason);
  cr_expect_eq(r.last_inverted, 0, "%d inverted tets", r.last_inverted);
  ext_run_free(&r);
  r = ext_run_scene("/tmp/bs_extreme_sliver.json", "solver.method=newton solver.max_iterations=30", "sliver_newton");
  ext_run_free(&r);
}
