/* bigstep levelset SURFACE OUT — a grid level set (collision/bs_levelset.h)
 * sampled from the signed distance to a closed surface.
 *
 * The surface is either a triangle file read as is through the CGAL shim
 * (.off, .obj, .ply, .stl) or the outward boundary triangles of any mesh or
 * geometry bigstep reads (bs_mesh_read: .msh, .geo, .step, .brep, ...; or a
 * structured box spec "box:..."). The surface must be closed: after merging
 * points with identical coordinates, every edge must be shared by an even
 * number (>= 2) of triangles, which is what makes the ray-parity sign of
 * bs_shim_signed_distance meaningful.
 *
 * The grid covers the surface's bounding box grown by the margin on every
 * side: origin = lo - margin, n[k] = ceil((hi[k] - lo[k] + 2 margin) / h) + 1
 * nodes of spacing h, values phi = signed distance (negative inside), sampled
 * one z slice at a time over OpenMP threads (the shim's queries are
 * read-only and thread-safe).
 *
 * OUT ending in ".vti" is written as VTK ImageData (bs_vti_write, point data
 * "phi"); any other name in the .bsls format of bs_levelset_grid_save. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app.h"
#include "bs_levelset.h"
#include "bs_shim.h"

#ifdef _OPENMP
#include <omp.h>
#endif

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

/* Triangle files go to the shim as they are; everything else is meshed. */
static int is_triangle_file(const char *path) {
  const char *dot = strrchr(path, '.');
  if (!dot || strchr(dot, '/')) return 0;
  static const char *const ext[] = {".off", ".obj", ".ply", ".stl", ".OFF", ".OBJ", ".PLY", ".STL", NULL};
  for (int i = 0; ext[i]; i++)
    if (!strcmp(dot, ext[i])) return 1;
  return 0;
}

static const double *cmp_points; /* qsort context for cmp_point_index */

static int cmp_point_index(const void *a, const void *b) {
  const double *p = cmp_points + 3 * *(const int64_t *)a, *q = cmp_points + 3 * *(const int64_t *)b;
  for (int k = 0; k < 3; k++)
    if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
  int64_t i = *(const int64_t *)a, j = *(const int64_t *)b;
  return (i > j) - (i < j);
}

static int cmp_edge(const void *a, const void *b) {
  const int64_t *e = a, *f = b;
  if (e[0] != f[0]) return e[0] < f[0] ? -1 : 1;
  return (e[1] > f[1]) - (e[1] < f[1]);
}

/* Closedness: merges points with identical coordinates, then counts each
 * undirected edge; an edge used by an odd number of triangles (e.g. once: a
 * border) makes the surface open. Names the file and one such edge. */
static int check_closed(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                        bs_error *err) {
  int64_t *order = malloc(sizeof(int64_t) * (size_t)(np > 0 ? np : 1));
  int64_t *rep = malloc(sizeof(int64_t) * (size_t)(np > 0 ? np : 1));
  int64_t *edges = malloc(sizeof(int64_t) * 2 * 3 * (size_t)(nt > 0 ? nt : 1));
  int st = 0;
  if (!order || !rep || !edges) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory checking the surface of '%s'", path);
    goto done;
  }
  for (int64_t i = 0; i < np; i++) order[i] = i;
  cmp_points = pts;
  qsort(order, (size_t)np, sizeof(int64_t), cmp_point_index);
  for (int64_t i = 0; i < np; i++) {
    int same = i > 0 && !memcmp(pts + 3 * order[i], pts + 3 * order[i - 1], 3 * sizeof(double));
    rep[order[i]] = same ? rep[order[i - 1]] : order[i];
  }
  int64_t ne = 0;
  for (int64_t t = 0; t < nt; t++)
    for (int k = 0; k < 3; k++) {
      int64_t a = rep[tris[3 * t + k]], b = rep[tris[3 * t + (k + 1) % 3]];
      if (a == b) continue; /* a collapsed edge bounds nothing */
      edges[2 * ne] = a < b ? a : b;
      edges[2 * ne + 1] = a < b ? b : a;
      ne++;
    }
  qsort(edges, (size_t)ne, 2 * sizeof(int64_t), cmp_edge);
  int64_t n_odd = 0, first_a = -1, first_b = -1;
  for (int64_t i = 0; i < ne;) {
    int64_t j = i;
    while (j < ne && edges[2 * j] == edges[2 * i] && edges[2 * j + 1] == edges[2 * i + 1]) j++;
    if ((j - i) % 2) {
      if (!n_odd) {
        first_a = edges[2 * i];
        first_b = edges[2 * i + 1];
      }
      n_odd++;
    }
    i = j;
  }
  if (n_odd) {
    const double *p = pts + 3 * first_a, *q = pts + 3 * first_b;
    st = bs_error_set(err, BS_EINPUT,
                      "'%s': the surface is not closed: %lld edges bound an odd number of triangles, e.g. the "
                      "edge (%g, %g, %g)-(%g, %g, %g); a signed distance needs a closed surface",
                      path, (long long)n_odd, p[0], p[1], p[2], q[0], q[1], q[2]);
  }
done:
  free(order);
  free(rep);
  free(edges);
  return st;
}

typedef struct surface {
  double *pts;
  int64_t np;
  int32_t *tris;
  int64_t nt;
  int from_shim; /* arrays freed with bs_shim_free, else free */
} surface;

static void surface_free(surface *s) {
  if (s->from_shim) {
    bs_shim_free(s->pts);
    bs_shim_free(s->tris);
  } else {
    free(s->pts);
    free(s->tris);
  }
  s->pts = NULL;
  s->tris = NULL;
}

static int read_surface(const char *path, double size, surface *s, bs_error *err) {
  memset(s, 0, sizeof *s);
  if (is_triangle_file(path)) {
    s->from_shim = 1;
    return bs_shim_read_surface(path, &s->pts, &s->np, &s->tris, &s->nt, err);
  }
  bs_mesh *m = NULL;
  int st = bs_app_load_mesh(path, size, 0, 0, -1, &m, err);
  if (st) return st;
  s->np = m->n_vertices;
  s->nt = m->n_faces;
  s->pts = malloc(sizeof(double) * 3 * (size_t)(s->np > 0 ? s->np : 1));
  s->tris = malloc(sizeof(int32_t) * 3 * (size_t)(s->nt > 0 ? s->nt : 1));
  if (!s->pts || !s->tris) {
    bs_mesh_destroy(&m);
    surface_free(s);
    return bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", path);
  }
  memcpy(s->pts, m->x, sizeof(double) * 3 * (size_t)s->np);
  memcpy(s->tris, m->faces, sizeof(int32_t) * 3 * (size_t)s->nt);
  bs_mesh_destroy(&m);
  return 0;
}

/* Samples the signed distance at every node: one z slice per task. */
static int sample(const bs_shim_tree *tree, const double origin[3], double h, const int32_t n[3], double *values,
                  bs_error *err) {
  const int64_t slice = (int64_t)n[0] * n[1];
  int st = 0;
#pragma omp parallel
  {
    double *q = malloc(sizeof(double) * 3 * (size_t)slice);
    bs_error e;
    int my = q ? 0 : BS_ENOMEM;
    if (my) e.msg[0] = 0;
#pragma omp for schedule(dynamic, 1)
    for (int32_t k = 0; k < n[2]; k++) {
      if (my) continue;
      for (int32_t j = 0; j < n[1]; j++)
        for (int32_t i = 0; i < n[0]; i++) {
          double *p = q + 3 * ((int64_t)i + (int64_t)n[0] * j);
          p[0] = origin[0] + h * i;
          p[1] = origin[1] + h * j;
          p[2] = origin[2] + h * k;
        }
      my = bs_shim_signed_distance(tree, q, slice, values + slice * k, &e);
    }
#pragma omp critical
    if (my && !st) {
      st = my;
      if (my == BS_ENOMEM) bs_error_set(err, BS_ENOMEM, "out of memory sampling the grid");
      else *err = e;
    }
    free(q);
  }
  return st;
}

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

typedef struct grid {
  double lo[3], hi[3]; /* the surface's box */
  double origin[3], h, margin;
  int32_t n[3];
  int64_t total;
} grid;

/* The box of the points triangles use (a soup may carry unused points). */
static void surface_box(const surface *s, double lo[3], double hi[3]) {
  for (int k = 0; k < 3; k++) {
    lo[k] = 1e300;
    hi[k] = -1e300;
  }
  for (int64_t t = 0; t < 3 * s->nt; t++)
    for (int k = 0; k < 3; k++) {
      double c = s->pts[3 * (int64_t)s->tris[t] + k];
      lo[k] = fmin(lo[k], c);
      hi[k] = fmax(hi[k], c);
    }
}

/* The grid over the surface's box grown by the margin (defaults from the
 * box's largest edge when a->h, a->margin are unset). */
static int plan_grid(const char *in, const surface *s, const levelset_args *a, grid *g, bs_error *err) {
  surface_box(s, g->lo, g->hi);
  const double *lo = g->lo, *hi = g->hi;
  double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
  if (!(ext > 0)) return bs_error_set(err, BS_EINPUT, "'%s': the surface has no extent", in);
  g->h = a->h > 0 ? a->h : ext / 40;
  g->margin = a->margin >= 0 ? a->margin : fmax(0.1 * ext, 2 * g->h);
  g->total = 1;
  for (int k = 0; k < 3; k++) {
    g->origin[k] = lo[k] - g->margin;
    double cells = ceil((hi[k] - lo[k] + 2 * g->margin) / g->h);
    if (cells < 1) cells = 1;
    if (cells + 1 > 1e9) return bs_error_set(err, BS_EINPUT, "--h %g: too many grid nodes along axis %d", g->h, k);
    g->n[k] = (int32_t)cells + 1;
    g->total *= g->n[k];
    if (g->total > INT32_MAX)
      return bs_error_set(err, BS_EINPUT, "--h %g: the grid would have more than 2^31 - 1 nodes", g->h);
  }
  return 0;
}

/* .vti (ImageData) for OUT.vti, else the .bsls grid file. */
static int write_grid(const bs_levelset *ls, const char *out, bs_error *err) {
  const char *dot = strrchr(out, '.');
  if (!dot || strchr(dot, '/') || strcmp(dot, ".vti")) return bs_levelset_grid_save(ls, out, err);
  bs_vti_grid g = {.name = "phi"};
  g.values = bs_levelset_grid_values(ls, g.n, g.origin, &g.h);
  return bs_vti_write(&g, out, err);
}

/* bs_seconds() at the start and after each stage. */
typedef struct stage_times {
  double t0, read, tree, sample, end;
} stage_times;

static void print_summary(const levelset_args *a, const surface *s, const grid *g, const double *values,
                          const stage_times *t) {
  double vmin = values[0], vmax = values[0];
  int64_t n_inside = 0;
  for (int64_t i = 0; i < g->total; i++) {
    vmin = fmin(vmin, values[i]);
    vmax = fmax(vmax, values[i]);
    n_inside += values[i] < 0;
  }
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  printf("levelset %s -> %s\n", a->in, a->out);
  printf("  surface: %lld points, %lld triangles, box [%g, %g] x [%g, %g] x [%g, %g]\n", (long long)s->np,
         (long long)s->nt, g->lo[0], g->hi[0], g->lo[1], g->hi[1], g->lo[2], g->hi[2]);
  printf("  grid: %d x %d x %d = %lld nodes, h %g m, margin %g m, origin (%g, %g, %g)\n", g->n[0], g->n[1], g->n[2],
         (long long)g->total, g->h, g->margin, g->origin[0], g->origin[1], g->origin[2]);
  printf("  phi: [%g, %g] m, %lld nodes inside\n", vmin, vmax, (long long)n_inside);
  struct stat sb;
  if (!stat(a->out, &sb)) printf("  file: %lld bytes\n", (long long)sb.st_size);
  printf("  time: read %.3f s, tree %.3f s, sample %.3f s (%d threads), write %.3f s, total %.3f s\n",
         t->read - t->t0, t->tree - t->read, t->sample - t->tree, threads, t->end - t->sample, t->end - t->t0);
}

/* Reads, checks, samples and writes; prints the summary on success. */
static int make_levelset(const levelset_args *a, bs_error *err) {
  stage_times t;
  t.t0 = bs_seconds();
  surface s;
  int st = read_surface(a->in, a->size, &s, err);
  t.read = bs_seconds();
  bs_shim_tree *tree = NULL;
  bs_levelset *ls = NULL;
  double *values = NULL;
  grid g;
  if (st) goto done;
  if (s.nt < 1) {
    st = bs_error_set(err, BS_EINPUT, "'%s': no triangles", a->in);
    goto done;
  }
  if ((st = check_closed(a->in, s.pts, s.np, s.tris, s.nt, err)) || (st = plan_grid(a->in, &s, a, &g, err)) ||
      (st = bs_shim_tree_create(s.pts, s.np, s.tris, s.nt, &tree, err)))
    goto done;
  t.tree = bs_seconds();
  values = malloc(sizeof(double) * (size_t)g.total);
  if (!values) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory: a grid of %lld nodes", (long long)g.total);
    goto done;
  }
  if ((st = sample(tree, g.origin, g.h, g.n, values, err))) goto done;
  t.sample = bs_seconds();
  if ((st = bs_levelset_grid_from_values(g.origin, g.h, g.n, values, &ls, err)) || (st = write_grid(ls, a->out, err)))
    goto done;
  t.end = bs_seconds();
  print_summary(a, &s, &g, values, &t);
done:
  free(values);
  bs_levelset_destroy(&ls);
  bs_shim_tree_destroy(&tree);
  surface_free(&s);
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
