/* The security rule for Gmsh scripts (bs_mesh.h, mesh/geo_guard.c): a .geo
 * that runs a program — directly, through a file it includes or merges, or
 * through the FILE.opt Gmsh reads beside it — is refused by bs_mesh_read and
 * runs nothing (the marker file its command would create stays absent); the
 * words in comments and strings are not commands; an include of a computed
 * name is refused; bs_mesh_set_geo_system_calls(1) (--allow-geo-system) lets
 * the script run. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "cli_util.h"

static char dir[64], marker[128];

static void setup(void) {
  snprintf(dir, sizeof dir, "/tmp/bs_geo_guard_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
  snprintf(marker, sizeof marker, "%s/ran", dir);
}
static void teardown(void) {
  char cmd[160];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  cr_expect_eq(system(cmd), 0);
  bs_mesh_set_geo_system_calls(0);
}

/* Writes dir/name holding text (%s in text: the marker path); returns the path. */
static const char *put(const char *name, const char *text) {
  static char path[8][256];
  static int k;
  char *p = path[k++ % 8];
  snprintf(p, 256, "%s/%s", dir, name);
  FILE *f = fopen(p, "w");
  cr_assert_not_null(f);
  fprintf(f, text, marker);
  cr_assert_eq(fclose(f), 0);
  return p;
}

#define BOX "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 1};\n"

/* bs_mesh_read refuses path with a message holding `needle`; nothing ran. */
static void refused(const char *path, const char *needle) {
  bs_mesh *m = NULL;
  bs_error err;
  cr_expect_eq(bs_mesh_read(path, NULL, &m, &err), BS_EINPUT, "%s was read", path);
  cr_expect(strstr(err.msg, needle) != NULL, "'%s' not in: %s", needle, err.msg);
  cr_expect(access(marker, F_OK) != 0, "%s: the script's command ran", path);
  bs_mesh_destroy(&m);
}

static void reads(const char *path) {
  bs_mesh *m = NULL;
  bs_error err;
  cr_expect_eq(bs_mesh_read(path, NULL, &m, &err), 0, "%s: %s", path, err.msg);
  cr_expect(m && m->n_tets > 0);
  bs_mesh_destroy(&m);
}

TestSuite(geo_guard, .init = setup, .fini = teardown);

Test(geo_guard, commands_that_run_programs_are_refused) {
  refused(put("a.geo", BOX "SystemCall \"touch %s\";\n"), "a.geo:3: the Gmsh script runs a program (SystemCall)");
  refused(put("b.geo", BOX "\n\nNonBlockingSystemCall \"touch %s\";\n"), "b.geo:5: the Gmsh script runs a program "
                                                                         "(NonBlockingSystemCall)");
  refused(put("c.geo", BOX "/* x */ OnelabRun(\"x\", \"touch %s\");\n"), "(OnelabRun)");
  refused(put("d.geo", BOX "SystemCall StrCat(\"touch \", \"%s\");\n"), "(SystemCall)");
}

Test(geo_guard, through_includes_merges_and_the_opt_file) {
  put("inner.geo", "SystemCall \"touch %s\";\n");
  refused(put("outer.geo", BOX "Include \"inner.geo\";\n"), "inner.geo:1: the Gmsh script runs a program");
  refused(put("merge.geo", BOX "Merge \"inner.geo\";\n"), "inner.geo:1:");
}

Test(geo_guard, opt_file_and_computed_includes) {
  const char *p = put("o.geo", BOX);
  put("o.geo.opt", "SystemCall \"touch %s\";\n");
  refused(p, "o.geo.opt:1: the Gmsh script runs a program");
  refused(put("e.geo", BOX "Include StrCat(\"in\", \"ner.geo\");\n"), "e.geo:3: Include of a computed file name");
  refused(put("f.geo", BOX "Include \"missing.geo\";\n"), "includes 'missing.geo', which cannot be checked");
}

Test(geo_guard, words_in_comments_and_strings_are_not_commands) {
  reads(put("ok.geo", BOX "// SystemCall \"touch %s\";\n/* OnelabRun */\nPrintf(\"SystemCall\");\n"
                          "MySystemCallCount = 1;\n"));
  cr_expect(access(marker, F_OK) != 0);
  put("part.geo", "Point(100) = {5, 5, 5};\n");
  reads(put("inc.geo", BOX "Include \"part.geo\";\n"));
}

Test(geo_guard, allowed_scripts_run) {
  const char *p = put("a.geo", BOX "SystemCall \"touch %s\";\n");
  bs_mesh_set_geo_system_calls(1);
  cr_expect_eq(bs_mesh_geo_system_calls(), 1);
  reads(p);
  cr_expect(access(marker, F_OK) == 0, "the allowed script did not run its command");
}

Test(geo_guard, command_line_refuses_and_allows) {
  const char *p = put("cli.geo", BOX "SystemCall \"touch %s\";\n");
  char cmd[512], *out;
  snprintf(cmd, sizeof cmd, "%s mesh info %s", BS_BIGSTEP_EXE, p);
  cr_expect_eq(bs_test_run(cmd, &out), 1, "%s", out);
  cr_expect(strstr(out, "runs a program (SystemCall)") && strstr(out, "--allow-geo-system"), "%s", out);
  cr_expect(access(marker, F_OK) != 0, "bigstep mesh info ran the script's command");
  free(out);
  snprintf(cmd, sizeof cmd, "%s mesh info %s --allow-geo-system", BS_BIGSTEP_EXE, p);
  cr_expect_eq(bs_test_run(cmd, &out), 0, "%s", out);
  cr_expect(access(marker, F_OK) == 0, "--allow-geo-system did not let the script run");
  free(out);
}
