/* app.h — what the subcommands of `bigstep` share: argument parsing helpers
 * and mesh loading from a path or a structured-box spec.
 *
 * Exit statuses of every subcommand: 0 success, 1 the job failed (bad input
 * file, failed steps, findings of `check`), 2 a usage error (wrong flag or
 * value), reported as one line on stderr. */
#ifndef BS_APP_H
#define BS_APP_H

#include "bs_base.h"
#include "bs_mesh.h"

#define BS_EXIT_FAIL 1
#define BS_EXIT_USAGE 2

/* Prints "bigstep CMD: message" on stderr and returns BS_EXIT_USAGE. */
int bs_app_usage_error(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Strict number parsing: the whole string must be a finite number. 0 on success. */
int bs_app_parse_double(const char *s, double *out);
int bs_app_parse_int(const char *s, long lo, long hi, int *out);

/* Loads a mesh from a file (through Gmsh) or from a structured box spec
 * "box:NX[xNYxNZ][:LX[xLYxLZ]]" (cells, then edge lengths in metres; default
 * 1 m), then refines `refine` times. */
int bs_app_load_mesh(const char *spec, double size, int refine, bs_mesh **out, bs_error *err);

/* Writes a mesh by the extension of path: .msh (Gmsh) or .vtu. */
int bs_app_write_mesh(const bs_mesh *m, const char *path, bs_error *err);

int bs_cmd_mesh(int argc, char **argv);
int bs_cmd_run(int argc, char **argv);
int bs_cmd_study(int argc, char **argv);
int bs_cmd_check(int argc, char **argv);
int bs_cmd_levelset(int argc, char **argv);

#endif
