/* bigstep check OUTPUT_DIR|FILE.vtu|FILE.pvd [--scene SCENE] [--quiet]
 *
 * Audits saved states with runfolder/bs_audit.h (what is checked and how is
 * described there): inverted tets, surface self-intersections and, with
 * --scene, vertices inside the obstacles of the scene, built as `bigstep run`
 * builds it. Prints a header, a line per frame (unless --quiet; an
 * unreadable frame's message goes to stderr) and a total line. Exit status:
 * 0 clean, 1 when anything was found or a file could not be read (the
 * message names it), 2 on a usage error. */
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "bs_audit.h"
#include "bs_scene.h"
#include "bs_sim.h"

static const char *check_help =
    "usage: bigstep check OUTPUT_DIR|FILE.vtu|FILE.pvd [--scene SCENE] [--quiet]\n"
    "\n"
    "Audits saved states: inverted tets (exact orientation at the current positions,\n"
    "against the rest shape x - displacement), surface self-intersections (exact\n"
    "triangle-triangle tests on the boundary of the tet mesh) and, with --scene,\n"
    "vertices inside the scene's obstacles. OUTPUT_DIR: its frame_*.vtu files in\n"
    "order, or the files its frames.pvd lists. Prints a line per frame and a total.\n"
    "Exit status: 0 clean, 1 something found or a file unreadable, 2 usage error.\n"
    "  --scene SCENE   the scene that produced the states (for its obstacles)\n"
    "  --quiet         only the total line\n";

/* ---- command --------------------------------------------------------------- */

typedef struct check_args {
  const char *target, *scene;
  int quiet;
} check_args;

/* 0, the usage status, or -1 when --help was printed. */
static int parse_args(int argc, char **argv, check_args *ca) {
  *ca = (check_args){NULL, NULL, 0};
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      fputs(check_help, stdout);
      return -1;
    }
    if (!strcmp(a, "--quiet")) {
      ca->quiet = 1;
    } else if (!strncmp(a, "--scene", 7) && (a[7] == '\0' || a[7] == '=')) {
      char fbuf[16];
      const char *flag, *val;
      if (bs_app_flag_value(argc, argv, &i, fbuf, sizeof fbuf, &flag, &val) || !*val)
        return bs_app_usage_error("check", "flag --scene needs a value");
      ca->scene = val;
    } else if (!strncmp(a, "--", 2)) {
      return bs_app_usage_error("check", "unknown flag '%s'", a);
    } else {
      if (ca->target) return bs_app_usage_error("check", "unexpected argument '%s' (one folder or file)", a);
      ca->target = a;
    }
  }
  if (!ca->target) return bs_app_usage_error("check", "missing OUTPUT_DIR or FILE.vtu");
  return 0;
}

static const char *base_name(const char *path) {
  const char *base = strrchr(path, '/');
  return base ? base + 1 : path;
}

typedef struct print_ctx {
  const bs_sim *sim;
  int quiet;
} print_ctx;

/* A frame's line (bs_audit_frame_fn); an unreadable frame's message first. */
static void print_frame(void *ctx, const bs_audit_entry *e, int status, const bs_audit_counts *a,
                        const bs_error *err) {
  const print_ctx *pc = ctx;
  if (status) {
    fflush(stdout);
    fprintf(stderr, "bigstep check: %s\n", err->msg);
    fflush(stderr);
    if (!pc->quiet)
      printf("%7d %12s %10s %10s %12s %12s %10s  %s (unreadable)\n", e->number, "-", "-", "-", "-", "-", "-",
             base_name(e->path));
    return;
  }
  if (pc->quiet) return;
  char tbuf[32];
  if (e->has_time) snprintf(tbuf, sizeof tbuf, "%.6g", e->time);
  else snprintf(tbuf, sizeof tbuf, "-");
  char pbuf[32] = "-", dbuf[32] = "-";
  if (pc->sim) {
    snprintf(pbuf, sizeof pbuf, "%d", a->penetrating);
    snprintf(dbuf, sizeof dbuf, "%.3g", a->max_depth);
  }
  printf("%7d %12s %10d %10d %12lld %12s %10s  %s\n", e->number, tbuf, a->n_tets, a->inverted,
         (long long)a->self_pairs, pbuf, dbuf, base_name(e->path));
}

/* The total line; returns the exit status. */
static int print_total(const bs_audit_totals *T, const bs_sim *sim) {
  int found = T->inverted > 0 || T->self_pairs > 0 || T->penetrating > 0;
  char pbuf[32] = "-", dbuf[32] = "-";
  if (sim) {
    snprintf(pbuf, sizeof pbuf, "%lld", T->penetrating);
    snprintf(dbuf, sizeof dbuf, "%.3g m", T->max_depth);
  }
  printf("total: %d frames, inverted %lld, self-intersecting pairs %lld, penetrating %s, max depth %s, unreadable %d: ",
         T->n_frames, T->inverted, T->self_pairs, pbuf, dbuf, T->unreadable);
  if (found) printf("problems in %d frame%s\n", T->bad_frames, T->bad_frames == 1 ? "" : "s");
  else if (T->unreadable) printf("%d file%s could not be audited\n", T->unreadable, T->unreadable == 1 ? "" : "s");
  else printf("clean\n");
  return found || T->unreadable ? BS_EXIT_FAIL : 0;
}

static const char *origin_text(bs_audit_origin o) {
  switch (o) {
  case BS_AUDIT_FRAME_FILES: return "frame_*.vtu";
  case BS_AUDIT_FOLDER_PVD: return "listed by frames.pvd";
  case BS_AUDIT_PVD_FILE: return "listed by the PVD file";
  default: return "one file";
  }
}

/* The header: the target, its frames and what is known of obstacles. */
static void print_header(const char *target, const bs_audit_list *L, const bs_sim *sim) {
  char obst[160];
  if (!sim) snprintf(obst, sizeof obst, "obstacles not checked (no --scene)");
  else if (!sim->obstacles) snprintf(obst, sizeof obst, "the scene has no obstacles");
  else snprintf(obst, sizeof obst, "%d obstacle%s of the scene", bs_obstacles_count(sim->obstacles),
                bs_obstacles_count(sim->obstacles) == 1 ? "" : "s");
  printf("bigstep check %s: %d frame%s (%s); %s\n", target, L->n, L->n == 1 ? "" : "s", origin_text(L->origin), obst);
  printf("%7s %12s %10s %10s %12s %12s %10s  %s\n", "frame", "time", "tets", "inverted", "self_pairs",
         "penetrating", "max_depth", "file");
}

int bs_cmd_check(int argc, char **argv) {
  /* argv[0] = "check" */
  check_args ca;
  int rc = parse_args(argc, argv, &ca);
  if (rc) return rc < 0 ? 0 : rc;
  bs_error err;
  bs_error_clear(&err);
  bs_audit_list L = {0};
  bs_scene *sc = NULL;
  bs_sim *sim = NULL;
  bs_audit_totals T;
  if (bs_audit_list_frames(ca.target, &L, &err) ||
      (ca.scene && (bs_scene_load(ca.scene, 0, NULL, &sc, &err) || bs_sim_create(sc, &sim, &err)))) {
    fprintf(stderr, "bigstep check: %s\n", err.msg);
    bs_scene_destroy(&sc);
    bs_audit_list_free(&L);
    return BS_EXIT_FAIL;
  }
  if (!ca.quiet) print_header(ca.target, &L, sim);
  print_ctx pc = {sim, ca.quiet};
  if (bs_audit_run(&L, sim, print_frame, &pc, &T, &err)) {
    fprintf(stderr, "bigstep check: %s\n", err.msg);
    rc = BS_EXIT_FAIL;
  } else {
    rc = print_total(&T, sim);
  }
  bs_audit_list_free(&L);
  bs_sim_destroy(&sim);
  bs_scene_destroy(&sc);
  return rc;
}
