/* bigstep levelset SURFACE OUT — a grid level set (collision/bs_levelset.h)
 * sampled from the signed distance to a closed surface (collision/
 * bs_ls_sample.h: closedness, the grid, the sampling, the file).
 *
 * The surface is either a triangle file read as is (.off, .obj, .ply, .stl)
 * or the outward boundary triangles of any mesh or geometry bigstep reads
 * (bs_app_load_mesh: .msh, .geo, .step, .brep, ...; or a structured box spec
 * "box:..."). OUT ending in ".vti" is written as VTK ImageData (point data
 * "phi"); any other name in the .bsls format of bs_levelset_grid_save.
 * Prints what was made and the time of each stage. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "app.h"
#include "bs_levelset.h"
#include "bs_ls_sample.h"

static const char *levelset_help =
    "usage: bigstep levelset SURFACE OUT [--h H] [--margin M] [--size S]\n"
    "\n"
    "Samples the signed distance to a closed surface (negative inside) on a\n"
    "regular grid and writes it: OUT.vti as VTK image data (point data \"phi\",\n"
    "for ParaView: Contour at 0 shows the surface); any other name (OUT.bsls) as\n"
    "a grid level set file, the 'file' of a scene obstacle of shape \"grid\"\n"
    "(collision \"penalty\").\n"
    "SURFACE: a triangle surface (.off, .obj, .ply, .stl, read as is), or any\n"
    "         mesh or geometry bigstep reads (.msh, .geo, .step, .brep, box:...),\n"
    "         whose boundary triangles are used. It must be closed.\n"
    "  --h H        grid spacing in metres [largest box edge / 40]\n"
    "  --margin M   grid margin around the surface's box in metres [max(0.1 x\n"
    "               largest box edge, 2 H)]\n"
    "  --size S     target mesh size (m) when meshing a geometry input\n";

typedef struct levelset_args {
  const char *in, *out;
  double h, margin, size; /* h, size 0 and margin < 0: the defaults */
} levelset_args;

/* The value of --h, --margin or --size. 0, or the usage status. */
static int parse_length(const char *flag, const char *val, levelset_args *a) {
  double v;
  if (bs_parse_double(val, &v)) return bs_app_usage_error("levelset", "%s '%s': not a number", flag, val);
  if (!strcmp(flag, "--margin")) {
    if (v < 0) return bs_app_usage_error("levelset", "--margin %s: must be >= 0 (m)", val);
    a->margin = v;
  } else {
    if (!(v > 0)) return bs_app_usage_error("levelset", "%s %s: must be > 0 (m)", flag, val);
    if (!strcmp(flag, "--h")) a->h = v;
    else a->size = v;
  }
  return 0;
}

/* 0, the usage status, or -1 when --help was printed. */
static int parse_args(int argc, char **argv, levelset_args *a) {
  *a = (levelset_args){NULL, NULL, 0, -1, 0};
  for (int i = 1; i < argc; i++) {
    const char *arg = argv[i];
    if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
      fputs(levelset_help, stdout);
      return -1;
    }
    if (!strcmp(arg, "--h") || !strcmp(arg, "--margin") || !strcmp(arg, "--size")) {
      if (i + 1 >= argc) return bs_app_usage_error("levelset", "%s needs a value", arg);
      int rc = parse_length(arg, argv[i + 1], a);
      if (rc) return rc;
      i++;
    } else if (arg[0] == '-' && arg[1] == '-') {
      return bs_app_usage_error("levelset", "unknown option '%s'", arg);
    } else if (!a->in) {
      a->in = arg;
    } else if (!a->out) {
      a->out = arg;
    } else {
      return bs_app_usage_error("levelset", "unexpected argument '%s'", arg);
    }
  }
  if (!a->in || !a->out)
    return bs_app_usage_error("levelset", "expected SURFACE and OUT");
  return 0;
}

/* The surface at path: a triangle file as is, else a mesh's boundary. */
static int read_surface(const char *path, double size, bs_ls_soup *s, bs_error *err) {
  memset(s, 0, sizeof *s);
  if (bs_ls_soup_is_file(path)) return bs_ls_soup_read(path, s, err);
  bs_mesh *m = NULL;
  int st = bs_app_load_mesh(path, size, 0, 0, -1, &m, err);
  if (st) return st;
  st = bs_ls_soup_from_mesh(m, s, err);
  bs_mesh_destroy(&m);
  if (st) bs_error_set(err, st, "out of memory reading '%s'", path);
  return st;
}

/* Seconds of reading and of the whole job. */
typedef struct stage_times {
  double read, total;
} stage_times;

static void print_summary(const levelset_args *a, const bs_ls_soup *s, const bs_ls_grid_plan *g,
                          const bs_ls_sample_info *in, const stage_times *t) {
  printf("levelset %s -> %s\n", a->in, a->out);
  printf("  surface: %lld points, %lld triangles, box [%g, %g] x [%g, %g] x [%g, %g]\n", (long long)s->n_points,
         (long long)s->n_tris, g->lo[0], g->hi[0], g->lo[1], g->hi[1], g->lo[2], g->hi[2]);
  printf("  grid: %d x %d x %d = %lld nodes, h %g m, margin %g m, origin (%g, %g, %g)\n", g->n[0], g->n[1], g->n[2],
         (long long)g->total, g->h, g->margin, g->origin[0], g->origin[1], g->origin[2]);
  printf("  phi: [%g, %g] m, %lld nodes inside\n", in->phi_min, in->phi_max, (long long)in->n_inside);
  struct stat sb;
  if (!stat(a->out, &sb)) printf("  file: %lld bytes\n", (long long)sb.st_size);
  double write = t->total - t->read - in->t_tree - in->t_sample; /* the level set and its file */
  printf("  time: read %.3f s, tree %.3f s, sample %.3f s (%d threads), write %.3f s, total %.3f s\n", t->read,
         in->t_tree, in->t_sample, in->threads, write, t->total);
}

/* Reads, checks, samples and writes; prints the summary on success. */
static int make_levelset(const levelset_args *a, bs_error *err) {
  stage_times t;
  double t0 = bs_seconds();
  bs_ls_soup s;
  bs_ls_grid_plan g;
  bs_ls_sample_info info;
  bs_levelset *ls = NULL;
  int st = read_surface(a->in, a->size, &s, err);
  t.read = bs_seconds() - t0;
  if (!st && !(st = bs_ls_from_surface(&s, a->in, a->h, a->margin, &g, &info, &ls, err)) &&
      !(st = bs_ls_sample_write(ls, a->out, err))) {
    t.total = bs_seconds() - t0;
    print_summary(a, &s, &g, &info, &t);
  }
  bs_levelset_destroy(&ls);
  bs_ls_soup_free(&s);
  return st;
}

int bs_cmd_levelset(int argc, char **argv) {
  /* argv[0] = "levelset" */
  levelset_args a;
  int rc = parse_args(argc, argv, &a);
  if (rc) return rc < 0 ? 0 : rc;
  bs_error err;
  err.msg[0] = 0;
  if (make_levelset(&a, &err)) {
    fprintf(stderr, "bigstep levelset: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  return 0;
}
