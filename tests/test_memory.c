/* Refusals before allocation (bs_memory.h, bs_mesh.h limits): a scene whose
 * box would need more memory than the machine has is refused by
 * bs_sim_create with the key and the estimate; a refinement or a Gmsh mesh
 * size that would make more tets than fit is refused by the reader before it
 * refines or meshes; the estimate grows with the mesh and is larger with
 * CHOLMOD's factor. */
#define _GNU_SOURCE
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_memory.h"
#include "bs_mesh.h"
#include "bs_sim.h"
#include "scene_fixture.h"

Test(memory, a_box_beyond_the_machine_is_refused_with_the_estimate) {
  bs_scene *sc = bs_test_box_scene(1, 24, 1);
  sc->bodies[0].box_cells[0] = sc->bodies[0].box_cells[1] = sc->bodies[0].box_cells[2] = 4000;
  bs_sim *s = NULL;
  bs_error err;
  cr_expect_eq(bs_sim_create(sc, &s, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "bodies.0.box (4000 x 4000 x 4000 cells, refine 0): 64048012001 vertices and "
                            "384000000000 tets need an estimated") &&
                strstr(err.msg, "GiB, more than this machine's"),
            "%s", err.msg);
  cr_expect_null(s);
  sc->bodies[0].box_cells[0] = sc->bodies[0].box_cells[1] = sc->bodies[0].box_cells[2] = 100;
  sc->bodies[0].refine = 4; /* 6e6 tets x 4096 */
  cr_expect_eq(bs_sim_create(sc, &s, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "refine 4"), "%s", err.msg);
  bs_scene_destroy(&sc);
}

Test(memory, estimate_grows_and_cholmod_costs_more) {
  bs_scene *sc = bs_test_box_scene(1, 24, 1);
  bs_memory_estimate a, b, c;
  bs_error err;
  cr_assert_eq(bs_scene_memory_estimate(sc, &a, &err), 0, "%s", err.msg);
  cr_expect_eq(a.tets, 48);
  cr_expect_eq(a.vertices, 27);
  cr_expect_eq(a.exact, 1);
  sc->bodies[0].refine = 2;
  cr_assert_eq(bs_scene_memory_estimate(sc, &b, &err), 0, "%s", err.msg);
  cr_expect_eq(b.tets, 48 * 64);
  cr_expect_eq(b.vertices, 9 * 9 * 9);
  cr_expect_gt(b.bytes, a.bytes);
  const int64_t cap_cg = bs_memory_max_tets(sc);
  sc->solver.min.linear = BS_LIN_CHOLMOD;
  cr_assert_eq(bs_scene_memory_estimate(sc, &c, &err), 0, "%s", err.msg);
  cr_expect_gt(c.bytes, b.bytes);
  const int64_t cap_chol = bs_memory_max_tets(sc);
  cr_expect(cap_chol > 0 && cap_chol < cap_cg, "max tets: cholmod %lld, cg %lld", (long long)cap_chol,
            (long long)cap_cg);
  /* The largest count that fits does fit, and twice it does not. */
  cr_expect_leq(bs_memory_run_bytes(sc, (int64_t)(cap_chol / 5.5), cap_chol), 1.0001 * bs_machine_memory());
  bs_memory_estimate d;
  cr_expect_eq(bs_memory_check(sc, 2 * cap_chol / 5, 2 * cap_chol, &d, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "bodies: "), "%s", err.msg);
  bs_scene_destroy(&sc);
}

/* A file mesh refined past the limit is refused before the first refinement,
 * naming the file, the counts and the limit. */
Test(memory, refinement_past_the_limit_is_refused_before_it_runs) {
  bs_mesh *m = NULL;
  bs_error err;
  const char *path = BS_SOURCE_DIR "/data/geo/beam.geo";
  bs_mesh_read_opts o = {.refine = 3, .max_tets = 1000};
  int st = bs_mesh_read(path, &o, &m, &err);
  cr_expect_eq(st, BS_EINPUT, "%s", st ? err.msg : "read");
  cr_expect(strstr(err.msg, "beam.geo: ") && strstr(err.msg, "refined 3 times") && strstr(err.msg, "more than the 1000"),
            "%s", err.msg);
  bs_mesh_destroy(&m);
  o.refine = 0;
  cr_expect_eq(bs_mesh_read(path, &o, &m, &err), 0, "%s", err.msg);
  bs_mesh_destroy(&m);
  cr_expect_eq(bs_mesh_load("box:50", &(bs_mesh_read_opts){.refine = 6}, &m, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "box of 50 x 50 x 50 cells: 750000 tets refined 6 times"), "%s", err.msg);
}

/* A mesh size far too small for the geometry is refused before Gmsh meshes
 * (it would otherwise mesh for minutes and run out of memory), with the size
 * that fits. */
Test(memory, a_mesh_size_far_too_small_is_refused_before_meshing) {
  char path[] = "/tmp/bs_mem_sphere_XXXXXX.geo";
  int fd = mkstemps(path, 4);
  cr_assert(fd >= 0);
  FILE *f = fdopen(fd, "w");
  fputs("SetFactory(\"OpenCASCADE\");\nSphere(1) = {0, 0, 0, 1};\n", f);
  fclose(f);
  bs_mesh *m = NULL;
  bs_error err;
  cr_expect_eq(bs_mesh_read(path, &(bs_mesh_read_opts){.size = 1e-4}, &m, &err), BS_EINPUT);
  cr_expect(strstr(err.msg, "mesh size 0.0001 m in a volume of 4.18879 m^3 makes about 2.51e+13 tets") &&
                strstr(err.msg, "the smallest size that fits is about"),
            "%s", err.msg);
  cr_expect_eq(bs_mesh_read(path, &(bs_mesh_read_opts){.size = 0.2, .max_tets = 100000}, &m, &err), 0, "%s",
               err.msg);
  cr_expect(m && m->n_tets > 0);
  bs_mesh_destroy(&m);
  unlink(path);
}
