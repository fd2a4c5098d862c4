/* The `bigstep` command line: help, version, `mesh` subcommands, exit statuses
 * (0 ok, 1 failed job, 2 usage error) and one-line messages naming the culprit. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "cli_util.h"

Test(cli_mesh, help_and_version) {
  char *out = NULL;
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " --help", &out), 0);
  cr_expect(strstr(out, "mesh") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " --version", &out), 0);
  cr_expect(strstr(out, "bigstep ") == out, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh --help", &out), 0);
  cr_expect(strstr(out, "mesh info FILE") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " frobnicate", &out), 2);
  cr_expect(strstr(out, "unknown command 'frobnicate'") != NULL, "%s", out);
  free(out);
}

Test(cli_mesh, info_box_counts) {
  char *out = NULL;
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:4x3x2 --refine 1", &out), 0, "%s", out);
  /* 8x6x4 cells: 9*7*5 vertices, 6*192 tets */
  cr_expect(strstr(out, "vertices 315 (dofs 945), tets 1152") != NULL, "%s", out);
  cr_expect(strstr(out, "check: ok") != NULL, "%s", out);
  cr_expect(strstr(out, "xmin") != NULL, "%s", out);
  free(out);
}

Test(cli_mesh, info_step_part) {
  char *out = NULL;
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info data/geo/bracket.step", &out), 0, "%s", out);
  cr_expect(strstr(out, "(3, 1) body") != NULL, "%s", out);
  cr_expect(strstr(out, "inverted 0") != NULL, "%s", out);
  cr_expect(strstr(out, "check: ok") != NULL, "%s", out);
  free(out);
}

Test(cli_mesh, refine_reorder_convert_round_trip) {
  char *out = NULL;
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh refine data/geo/cube.geo /tmp/bs_cli_refined.msh", &out), 0, "%s", out);
  free(out);
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh reorder /tmp/bs_cli_refined.msh /tmp/bs_cli_rcm.msh --method rcm", &out),
               0, "%s", out);
  cr_expect(strstr(out, "bandwidth") != NULL, "%s", out);
  free(out);
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh convert /tmp/bs_cli_rcm.msh /tmp/bs_cli_rcm.vtu", &out), 0, "%s", out);
  free(out);
  char *a = NULL, *b = NULL;
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info data/geo/cube.geo --refine 1", &a), 0);
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info /tmp/bs_cli_rcm.msh", &b), 0);
  /* same counts and volume line after refine -> reorder -> write -> read */
  const char *ka = strstr(a, "  vertices"), *kb = strstr(b, "  vertices");
  cr_assert(ka && kb);
  cr_expect(strncmp(ka, kb, strcspn(ka, "\n")) == 0, "%.*s vs %.*s", (int)strcspn(ka, "\n"), ka,
            (int)strcspn(kb, "\n"), kb);
  free(a);
  free(b);
}

Test(cli_mesh, errors) {
  char *out = NULL;
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info /nonexistent/part.msh", &out), 1);
  cr_expect(strstr(out, "/nonexistent/part.msh") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:2 --size -1", &out), 2);
  cr_expect(strstr(out, "--size") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:2 --refine x", &out), 2);
  cr_expect(strstr(out, "--refine") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:2 --frob 1", &out), 2);
  cr_expect(strstr(out, "--frob") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh refine box:2", &out), 2);
  cr_expect(strstr(out, "IN and OUT") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh convert box:2 /tmp/x.txt", &out), 1);
  cr_expect(strstr(out, "/tmp/x.txt") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:0", &out), 1);
  cr_expect(strstr(out, "box:0") != NULL, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh explode box:2", &out), 2);
  cr_expect(strstr(out, "explode") != NULL, "%s", out);
  free(out);
}

/* The quality gate from the command line: a gate the mesh cannot meet is an
 * error (exit 1) giving the angle reached and the worst region; 0 relaxes it;
 * a bad value is a usage error naming the flag. */
Test(cli_mesh, min_dihedral_gate) {
  char *out = NULL;
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info data/geo/cube.geo --min-dihedral 40", &out), 1, "%s", out);
  cr_expect(strstr(out, "data/geo/cube.geo") && strstr(out, "under the gate of 40") && strstr(out, "centred at ("),
            "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info data/geo/sliver.geo --min-dihedral 0", &out), 0, "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info data/geo/sliver.geo", &out), 1, "the sliver plate passed the gate");
  cr_expect(strstr(out, "sliver.geo") && strstr(out, "smallest dihedral angle is"), "%s", out);
  free(out);
  cr_expect_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info box:2 --min-dihedral 80", &out), 2);
  cr_expect(strstr(out, "--min-dihedral") != NULL, "%s", out);
  free(out);
}

/* A .msh with three nodes at the position of others under distinct tags: a
 * warning with the count, or merged with --merge-coincident. */
Test(cli_mesh, coincident_nodes_warned_or_merged) {
  const char *path = "/tmp/bs_cli_coincident.msh";
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f);
  fputs("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 0 0\n6 0 1 0\n"
        "7 0 0 1\n8 1 1 1\n$EndNodes\n$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 5 6 7 8\n$EndElements\n",
        f);
  fclose(f);
  char *out = NULL;
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info /tmp/bs_cli_coincident.msh", &out), 0, "%s", out);
  cr_expect(strstr(out, "warning: /tmp/bs_cli_coincident.msh: 3 nodes lie at the position of another node") != NULL,
            "%s", out);
  cr_expect(strstr(out, "vertices 8 (dofs 24), tets 2") != NULL, "%s", out);
  free(out);
  cr_assert_eq(bs_test_run(BS_BIGSTEP_EXE " mesh info /tmp/bs_cli_coincident.msh --merge-coincident", &out), 0, "%s",
               out);
  cr_expect(strstr(out, "merged 3 coincident nodes") != NULL, "%s", out);
  cr_expect(strstr(out, "vertices 5 (dofs 15), tets 2, boundary faces 6") != NULL, "%s", out);
  free(out);
  remove(path);
}
