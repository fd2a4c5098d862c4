/* test_mesh_load.c — one home for small helpers: box specs, "box or file,
 * then refine" (bs_mesh_load), bounding boxes, bs_mkdir_p. */
#define _GNU_SOURCE
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bs_base.h"
#include "bs_mesh.h"

Test(mesh_load, box_specs_parse_and_bad_ones_are_named) {
  int n[3];
  double len[3];
  bs_error err;
  cr_assert_eq(bs_mesh_box_spec_parse("box:8", n, len, &err), 0);
  cr_expect(n[0] == 8 && n[1] == 8 && n[2] == 8 && len[0] == 1 && len[1] == 1 && len[2] == 1);
  cr_assert_eq(bs_mesh_box_spec_parse("box:8x4x2:1x0.5x0.25", n, len, &err), 0);
  cr_expect(n[0] == 8 && n[1] == 4 && n[2] == 2 && len[0] == 1 && len[1] == 0.5 && len[2] == 0.25);
  cr_assert_eq(bs_mesh_box_spec_parse("box:3:2", n, len, &err), 0);
  cr_expect(len[0] == 2 && len[1] == 2 && len[2] == 2);
  static const char *const bad[] = {"box:", "box:0", "box:4097", "box:2x2", "box:2x2x2x2", "box:a", "box:2:0",
                                    "box:2:-1", "box:2:1x1", "box:2:nan", "cube:2"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    bs_error_clear(&err);
    cr_expect_eq(bs_mesh_box_spec_parse(bad[i], n, len, &err), BS_EINPUT, "%s accepted", bad[i]);
    cr_expect(strstr(err.msg, bad[i]) != NULL, "the message should name '%s': %s", bad[i], err.msg);
  }
}

Test(mesh_load, box_then_refine_counts) {
  bs_mesh *m = NULL;
  bs_error err;
  bs_mesh_read_opts o = {.refine = 1};
  cr_assert_eq(bs_mesh_load("box:2x3x4:2x3x4", &o, &m, &err), 0, "%s", err.msg);
  /* 2x3x4 cells of 6 tets, refined once: 8 x 144 tets; vertices of the 4x6x8 grid */
  cr_expect_eq(m->n_tets, 8 * 6 * 24);
  double lo[3], hi[3];
  bs_bbox(m->n_vertices, m->x, lo, hi);
  cr_expect(lo[0] == 0 && lo[1] == 0 && lo[2] == 0 && hi[0] == 2 && hi[1] == 3 && hi[2] == 4);
  cr_expect_float_eq(bs_bbox_diagonal(lo, hi), sqrt(29.0), 1e-15);
  bs_mesh *b = NULL;
  const double size[3] = {2, 3, 4};
  const int cells[3] = {2, 3, 4};
  cr_assert_eq(bs_mesh_create_box_refined(size, cells, 1, &b, &err), 0, "%s", err.msg);
  cr_expect_eq(b->n_vertices, m->n_vertices);
  cr_expect_eq(memcmp(b->x, m->x, sizeof(double) * 3 * (size_t)m->n_vertices), 0, "the same mesh both ways");
  bs_mesh_destroy(&b);
  bs_mesh_destroy(&m);
  cr_expect_eq(bs_mesh_load("box:2x2", NULL, &m, &err), BS_EINPUT);
  cr_expect_null(m);
}

Test(mesh_load, bbox_of_points) {
  const double x[9] = {1, -2, 3, -4, 5, 0.5, 2, 2, -6};
  double lo[3], hi[3];
  bs_bbox(3, x, lo, hi);
  cr_expect(lo[0] == -4 && lo[1] == -2 && lo[2] == -6 && hi[0] == 2 && hi[1] == 5 && hi[2] == 3);
  cr_expect_float_eq(bs_bbox_diagonal(lo, hi), sqrt(36.0 + 49.0 + 81.0), 1e-14);
  bs_bbox(0, x, lo, hi);
  cr_expect(lo[0] == 0 && hi[2] == 0, "no points: a zero box");
}

Test(mesh_load, mkdir_p_makes_parents_and_names_what_fails) {
  char dir[] = "/tmp/bs_mkdir_XXXXXX", p[256];
  cr_assert_not_null(mkdtemp(dir));
  bs_error err;
  snprintf(p, sizeof p, "%s/a/b/c", dir);
  cr_assert_eq(bs_mkdir_p(p, &err), 0, "%s", err.msg);
  struct stat st;
  cr_expect(stat(p, &st) == 0 && S_ISDIR(st.st_mode));
  cr_expect_eq(bs_mkdir_p(p, &err), 0, "an existing folder is fine");
  snprintf(p, sizeof p, "%s/file", dir);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fclose(f);
  snprintf(p, sizeof p, "%s/file/sub", dir);
  cr_expect_eq(bs_mkdir_p(p, &err), BS_EIO);
  cr_expect(strstr(err.msg, "file/sub") != NULL, "%s", err.msg);
  cr_expect_eq(bs_mkdir_p("", &err), BS_EINPUT);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  cr_expect_eq(system(cmd), 0);
}
