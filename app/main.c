/* bigstep — finite elements for deformable solids at large time steps. */
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "bs_mesh.h"

#ifndef BS_VERSION
#define BS_VERSION "unknown"
#endif

static const char *main_help =
    "usage: bigstep COMMAND [ARGS]\n"
    "\n"
    "commands:\n"
    "  run SCENE                          simulate a scene (JSON) and report per frame\n"
    "  study SCENE --vary KEY=v1,v2,...   measure speed against accuracy over settings\n"
    "  check DIR|FILE.vtu|FILE.pvd        audit saved states (inverted tets, self-intersections, obstacles)\n"
    "  mesh info|refine|reorder|convert   read, inspect, refine, renumber and convert meshes\n"
    "  levelset SURFACE OUT               a grid level set (signed distance) from a closed surface\n"
    "  schema [--markdown]                the scene schema as a JSON Schema (for editors), or the key reference\n"
    "\n"
    "  bigstep COMMAND --help   help on a command\n"
    "  bigstep --version        the version\n"
    "\n"
    "  --allow-geo-system       (with any command) let Gmsh scripts (.geo) run programs\n"
    "                           (SystemCall, NonBlockingSystemCall, OnelabRun); refused\n"
    "                           by default: only give it for files you trust\n";

/* Takes --allow-geo-system out of argv (anywhere after the command). */
static int take_geo_flag(int argc, char **argv) {
  int n = 0;
  for (int i = 0; i < argc; i++)
    if (!strcmp(argv[i], "--allow-geo-system")) bs_mesh_set_geo_system_calls(1);
    else argv[n++] = argv[i];
  argv[n] = NULL;
  return n;
}

int main(int argc, char **argv) {
  argc = take_geo_flag(argc, argv);
  if (argc < 2) {
    fputs(main_help, stderr);
    return BS_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    fputs(main_help, stdout);
    return 0;
  }
  if (!strcmp(cmd, "--version")) {
    printf("bigstep %s\n", BS_VERSION);
    return 0;
  }
  if (!strcmp(cmd, "mesh")) return bs_cmd_mesh(argc - 1, argv + 1);
  if (!strcmp(cmd, "run")) return bs_cmd_run(argc - 1, argv + 1);
  if (!strcmp(cmd, "study")) return bs_cmd_study(argc - 1, argv + 1);
  if (!strcmp(cmd, "check")) return bs_cmd_check(argc - 1, argv + 1);
  if (!strcmp(cmd, "levelset")) return bs_cmd_levelset(argc - 1, argv + 1);
  if (!strcmp(cmd, "schema")) return bs_cmd_schema(argc - 1, argv + 1);
  fprintf(stderr, "bigstep: unknown command '%s' (see 'bigstep --help')\n", cmd);
  return BS_EXIT_USAGE;
}
