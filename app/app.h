/* app.h — what the subcommands of `bigstep` share: argument parsing helpers
 * and mesh loading from a path or a structured-box spec.
 *
 * Exit statuses of every subcommand: 0 success, 1 the job failed (bad input
 * file, failed steps, findings of `check`), 2 a usage error (wrong flag or
 * value), reported as one line on stderr; `run` also 128 + the signal when
 * stopped by SIGINT (130) or SIGTERM (143). */
#ifndef BS_APP_H
#define BS_APP_H

#include <signal.h>

#include "bs_base.h"
#include "bs_mesh.h"
#include "bs_scene.h"

#define BS_EXIT_FAIL 1
#define BS_EXIT_USAGE 2

/* Prints "bigstep CMD: message" on stderr and returns BS_EXIT_USAGE. */
int bs_app_usage_error(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;


/* Loads a mesh from a file (through Gmsh) or from a structured box spec
 * "box:NX[xNYxNZ][:LX[xLYxLZ]]" (bs_mesh_load), then refines `refine` times;
 * merge: bs_mesh_read_opts.merge_coincident; min_dihedral: its quality gate
 * (0: the default, < 0: none). Coincident nodes of the file
 * (distinct tags at one position) are reported on stderr: a warning when
 * kept, a note when merged. */
int bs_app_load_mesh(const char *spec, double size, int refine, int merge, double min_dihedral, bs_mesh **out,
                     bs_error *err);

/* The same with all of bs_mesh_read_opts (o may be NULL). */
int bs_app_load_mesh_opts(const char *spec, const bs_mesh_read_opts *o, bs_mesh **out, bs_error *err);

/* Prints what the surface repair of spec did (bs_surface_report) to stdout;
 * nothing when r is NULL or holds no surface (r->tris_in == 0). */
void bs_app_print_surface_report(const char *spec, const struct bs_surface_report *r);

/* A growing list of owned "key=value" strings (the --set list of a run). */
typedef struct bs_app_sets {
  int n, cap;
  char **v;
} bs_app_sets;

/* Appends key=value (value NULL: key is the whole "key=value"); quote 1 puts
 * the value in JSON quotes. 0, or -1 out of memory. */
int bs_app_sets_add(bs_app_sets *s, const char *key, const char *value, int quote);
void bs_app_sets_free(bs_app_sets *s);

/* The flag at argv[*i] ("--flag value", "--flag=value"; "--set" takes
 * "--set=k=v" or "--set k=v"): *flag and *value point into argv or into
 * fbuf; consumes the value argument. -1 when the value is missing (fbuf then
 * holds the flag). */
int bs_app_flag_value(int argc, char **argv, int *i, char *fbuf, size_t n, const char **flag, const char **value);

/* Writes a mesh by the extension of path: .msh (Gmsh) or .vtu. */
int bs_app_write_mesh(const bs_mesh *m, const char *path, bs_error *err);

/* "bigstep CMD ARGS..." with each argument shell-quoted where it needs it
 * (argv[0] is the command name); the caller frees the string. NULL when out
 * of memory. */
char *bs_app_command_line(int argc, char **argv);

/* The stop request of `bigstep run`: 0, or the signal (SIGINT, SIGTERM) that
 * asked the run to stop, set by the handlers that
 * bs_app_install_stop_handlers installs (a second signal of either ends the
 * program at once). The run passes the flag to the library (bs_sim_run_opts,
 * bs_dsim_set_stop). bs_app_signal_name: "SIGINT" or "SIGTERM";
 * bs_app_stop_status: the exit status of a run it stopped (130, 143). */
extern volatile sig_atomic_t bs_app_stop_signal;
void bs_app_install_stop_handlers(void);
const char *bs_app_signal_name(int sig);
int bs_app_stop_status(int sig);

int bs_cmd_mesh(int argc, char **argv);
int bs_cmd_run(int argc, char **argv);
/* bigstep run on the petsc backend (cmd_run_petsc.c): the exit status. The
 * options: --quiet, --replace, --resume (refused: bs_dsim_check_output), the
 * command line (run.txt). */
typedef struct bs_app_petsc_args {
  int quiet, replace, resume;
  const char *command;
} bs_app_petsc_args;
int bs_app_run_petsc(const char *path, const bs_scene *sc, const bs_app_petsc_args *a);
int bs_cmd_study(int argc, char **argv);
int bs_cmd_check(int argc, char **argv);
int bs_cmd_levelset(int argc, char **argv);
int bs_cmd_schema(int argc, char **argv);

#endif
