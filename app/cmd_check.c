/* bigstep check OUTPUT_DIR|FILE.vtu|FILE.pvd [--scene SCENE] [--quiet]
 *
 * Audits saved states. For each VTU file:
 *  - inverted tets: the rest shape is recovered as rest = x - displacement and
 *    the mesh is rebuilt from it (bs_mesh_create orients every tet positively
 *    at rest, and refuses a tet of zero rest volume); a tet is inverted when
 *    the exact orientation of its four current positions (bs_shim_orient3d)
 *    is not positive, i.e. det F <= 0 decided without round-off;
 *  - surface self-intersections: the boundary triangles of that rest mesh,
 *    placed at the current positions, tested pairwise with exact predicates
 *    (bs_shim_self_intersections; degenerate triangles count as a pair);
 *  - vertices inside obstacles (with --scene): the scene is built as
 *    `bigstep run` builds it; the file's points must be its mesh's vertices
 *    (same count, and rest = x - displacement equal to the scene's rest shape
 *    up to 1e-9 of its size), then bs_sim_penetration counts the free
 *    vertices inside some obstacle at the frame's time (the PVD's timestep,
 *    else frame N / fps) and the largest depth -phi.
 * A folder is read as its frame_NNNNN.vtu files in frame order, or, when it
 * holds none, as the files its frames.pvd lists. Exit status: 0 clean, 1 when
 * anything was found or a file could not be read (the message names it),
 * 2 on a usage error. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app.h"
#include "bs_shim.h"
#include "bs_vtu_read.h"
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

typedef struct frame_src {
  char *path;
  int number;      /* N of frame_N.vtu, else the position in the list */
  double time;
  int has_time;
} frame_src;

typedef struct frame_list {
  int n, cap;
  frame_src *f;
  const char *origin; /* how the list was made, for the header line */
} frame_list;

static void list_free(frame_list *L) {
  for (int i = 0; i < L->n; i++) free(L->f[i].path);
  free(L->f);
  L->f = NULL;
  L->n = L->cap = 0;
}

static int list_add(frame_list *L, char *path, int number, double time, int has_time) {
  if (L->n == L->cap) {
    int nc = L->cap ? 2 * L->cap : 64;
    frame_src *nf = realloc(L->f, (size_t)nc * sizeof *nf);
    if (!nf) return -1;
    L->f = nf;
    L->cap = nc;
  }
  L->f[L->n++] = (frame_src){path, number, time, has_time};
  return 0;
}

/* N when name is "frame_N.vtu" (N all digits), else -1. */
static long frame_number(const char *name) {
  if (strncmp(name, "frame_", 6)) return -1;
  const char *p = name + 6, *q = p;
  while (*q >= '0' && *q <= '9') q++;
  if (q == p || q - p > 9 || strcmp(q, ".vtu")) return -1;
  return strtol(p, NULL, 10);
}

static int cmp_frame(const void *a, const void *b) {
  const frame_src *x = a, *y = b;
  if (x->number != y->number) return x->number < y->number ? -1 : 1;
  return strcmp(x->path, y->path);
}

static char *join(const char *dir, const char *name) {
  size_t dl = strlen(dir), nl = strlen(name);
  char *s = malloc(dl + nl + 2);
  if (!s) return NULL;
  memcpy(s, dir, dl);
  size_t k = dl;
  if (dl && dir[dl - 1] != '/') s[k++] = '/';
  memcpy(s + k, name, nl + 1);
  return s;
}

static int ends_with(const char *s, const char *suffix) {
  size_t n = strlen(s), m = strlen(suffix);
  return n >= m && !strcmp(s + n - m, suffix);
}

static int from_pvd(const char *pvd_path, frame_list *L, bs_error *err) {
  bs_pvd *pv = NULL;
  int rc = bs_pvd_read(pvd_path, &pv, err);
  if (rc) return rc;
  for (int i = 0; i < pv->n; i++) {
    const char *base = strrchr(pv->files[i], '/');
    long num = frame_number(base ? base + 1 : pv->files[i]);
    char *p = strdup(pv->files[i]);
    if (!p || list_add(L, p, num >= 0 ? (int)num : i, pv->times[i], 1)) {
      free(p);
      bs_pvd_destroy(&pv);
      return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", pvd_path);
    }
  }
  int n = pv->n;
  bs_pvd_destroy(&pv);
  if (n == 0) return bs_error_set(err, BS_EINPUT, "'%s' lists no data sets", pvd_path);
  return BS_OK;
}

/* The files to audit for the command's argument. */
static int list_frames(const char *arg, frame_list *L, bs_error *err) {
  struct stat sb;
  if (stat(arg, &sb)) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot read '%s': %s", arg, strerror(e));
  }
  if (!S_ISDIR(sb.st_mode)) {
    if (ends_with(arg, ".pvd")) {
      L->origin = "listed by the PVD file";
      return from_pvd(arg, L, err);
    }
    char *p = strdup(arg);
    const char *base = strrchr(arg, '/');
    long num = frame_number(base ? base + 1 : arg);
    if (!p || list_add(L, p, num >= 0 ? (int)num : 0, 0, 0)) {
      free(p);
      return bs_error_set(err, BS_ENOMEM, "out of memory");
    }
    L->origin = "one file";
    return BS_OK;
  }
  DIR *d = opendir(arg);
  if (!d) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot list folder '%s': %s", arg, strerror(e));
  }
  struct dirent *de;
  while ((de = readdir(d))) {
    long num = frame_number(de->d_name);
    if (num < 0) continue;
    char *p = join(arg, de->d_name);
    if (!p || list_add(L, p, (int)num, 0, 0)) {
      free(p);
      closedir(d);
      return bs_error_set(err, BS_ENOMEM, "out of memory");
    }
  }
  closedir(d);
  if (L->n > 0) {
    qsort(L->f, (size_t)L->n, sizeof *L->f, cmp_frame);
    L->origin = "frame_*.vtu";
    return BS_OK;
  }
  char *pvd = join(arg, "frames.pvd");
  if (!pvd) return bs_error_set(err, BS_ENOMEM, "out of memory");
  int rc;
  if (stat(pvd, &sb) == 0) {
    L->origin = "listed by frames.pvd";
    rc = from_pvd(pvd, L, err);
  } else {
    rc = bs_error_set(err, BS_EINPUT, "folder '%s' holds no frame_*.vtu files and no frames.pvd", arg);
  }
  free(pvd);
  return rc;
}

/* ---- one frame ---------------------------------------------------------- */

typedef struct audit {
  int32_t n_tets;
  int32_t inverted;
  int64_t self_pairs;
  int32_t penetrating; /* with a scene */
  double max_depth;
} audit;

/* The rest mesh of the previous frame, reused while the connectivity and the
 * rest positions stay the same (the usual case along a run). */
typedef struct mesh_cache {
  bs_mesh *mesh;
  int32_t n_points, n_cells;
  double *rest;     /* 3 n_points, as read */
  int32_t *tets;    /* 4 n_cells, as read  */
  int32_t *newid;   /* n_points: compacted vertex id, -1 when no tet uses it */
} mesh_cache;

static void cache_free(mesh_cache *c) {
  bs_mesh_destroy(&c->mesh);
  free(c->rest);
  free(c->tets);
  free(c->newid);
  memset(c, 0, sizeof *c);
}

static int cache_mesh(const bs_vtu *v, double *rest, const char *path, mesh_cache *c, bs_error *err) {
  const size_t np = (size_t)v->n_points, nc = (size_t)v->n_cells;
  if (c->mesh && c->n_points == v->n_points && c->n_cells == v->n_cells &&
      !memcmp(c->tets, v->tets, 4 * nc * sizeof(int32_t)) && !memcmp(c->rest, rest, 3 * np * sizeof(double))) {
    free(rest);
    return BS_OK;
  }
  cache_free(c);
  c->rest = rest;
  c->n_points = v->n_points;
  c->n_cells = v->n_cells;
  c->tets = malloc(4 * nc * sizeof(int32_t));
  c->newid = malloc(np * sizeof(int32_t) + 1);
  if (!c->tets || !c->newid) return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
  memcpy(c->tets, v->tets, 4 * nc * sizeof(int32_t));
  /* bs_mesh_create keeps the vertices some tet uses, in input order: the
   * same compaction maps the current positions. */
  for (size_t i = 0; i < np; i++) c->newid[i] = -1;
  for (size_t i = 0; i < 4 * nc; i++) c->newid[v->tets[i]] = 0;
  int32_t k = 0;
  for (size_t i = 0; i < np; i++)
    if (c->newid[i] == 0) c->newid[i] = k++;
  int rc = bs_mesh_create(v->n_points, rest, v->n_cells, v->tets, 0, NULL, &c->mesh, err);
  if (rc) {
    bs_error_prefix(err, "'%s': rest shape (x - displacement)", path);
    cache_free(c);
    return rc;
  }
  if (c->mesh->n_vertices != k) {
    cache_free(c);
    return bs_error_set(err, BS_EINTERNAL, "'%s': rest mesh has %d vertices, expected %d", path, c->mesh->n_vertices,
                        k);
  }
  return BS_OK;
}

/* Vertices inside the scene's obstacles at time t for the file's positions. */
static int audit_obstacles(const bs_vtu *v, const double *rest, const char *path, double t, bs_sim *s, audit *a,
                           bs_error *err) {
  const bs_mesh *m = s->mesh;
  if (v->n_points != m->n_vertices)
    return bs_error_set(err, BS_EINPUT, "'%s' has %d points but the scene's mesh has %d vertices: not a state of this scene",
                        path, v->n_points, m->n_vertices);
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int32_t i = 0; i < m->n_vertices; i++)
    for (int k = 0; k < 3; k++) {
      double r = m->x[3 * (size_t)i + k];
      if (r < lo[k]) lo[k] = r;
      if (r > hi[k]) hi[k] = r;
    }
  double size = 0;
  for (int k = 0; k < 3; k++) size = hi[k] - lo[k] > size ? hi[k] - lo[k] : size;
  for (int32_t i = 0; i < m->n_vertices; i++)
    for (int k = 0; k < 3; k++)
      if (fabs(rest[3 * (size_t)i + k] - m->x[3 * (size_t)i + k]) > 1e-9 * size)
        return bs_error_set(err, BS_EINPUT,
                            "'%s': point %d rests at (%g, %g, %g) but the scene's vertex %d rests at (%g, %g, %g): "
                            "not a state of this scene",
                            path, i, rest[3 * (size_t)i], rest[3 * (size_t)i + 1], rest[3 * (size_t)i + 2], i,
                            m->x[3 * (size_t)i], m->x[3 * (size_t)i + 1], m->x[3 * (size_t)i + 2]);
  memcpy(s->x, v->x, 3 * (size_t)m->n_vertices * sizeof(double));
  s->time = t;
  bs_sim_penetration(s, &a->penetrating, &a->max_depth);
  return BS_OK;
}

static int audit_frame(const char *path, double t, bs_sim *sim, mesh_cache *c, double **xc_buf, size_t *xc_cap,
                       audit *a, bs_error *err) {
  bs_vtu *v = NULL;
  int rc = bs_vtu_read(path, &v, err);
  if (rc) return rc;
  if (v->n_cells == 0) {
    bs_vtu_destroy(&v);
    return bs_error_set(err, BS_EINPUT, "'%s' has no cells: nothing to audit", path);
  }
  double *rest = malloc(3 * (size_t)v->n_points * sizeof(double) + 1);
  if (!rest) {
    bs_vtu_destroy(&v);
    return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
  }
  if ((rc = bs_vtu_rest(v, path, rest, err)) || (sim && (rc = audit_obstacles(v, rest, path, t, sim, a, err)))) {
    free(rest);
    bs_vtu_destroy(&v);
    return rc;
  }
  if ((rc = cache_mesh(v, rest, path, c, err))) { /* takes rest */
    bs_vtu_destroy(&v);
    return rc;
  }
  const bs_mesh *m = c->mesh;
  size_t need = 3 * (size_t)m->n_vertices;
  if (need > *xc_cap) {
    double *nb = realloc(*xc_buf, need * sizeof(double));
    if (!nb) {
      bs_vtu_destroy(&v);
      return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", path);
    }
    *xc_buf = nb;
    *xc_cap = need;
  }
  double *xc = *xc_buf;
  for (int32_t i = 0; i < v->n_points; i++)
    if (c->newid[i] >= 0) memcpy(xc + 3 * (size_t)c->newid[i], v->x + 3 * (size_t)i, 3 * sizeof(double));
  bs_vtu_destroy(&v);

  /* inverted: exact orientation of each (positively oriented at rest) tet */
  a->n_tets = m->n_tets;
  a->inverted = 0;
  for (int32_t t = 0; t < m->n_tets; t++) {
    const int32_t *tv = m->tets + 4 * (size_t)t;
    int o = bs_shim_orient3d(xc + 3 * (size_t)tv[0], xc + 3 * (size_t)tv[1], xc + 3 * (size_t)tv[2],
                             xc + 3 * (size_t)tv[3]);
    if (o < -1) return bs_error_set(err, BS_EINTERNAL, "'%s': orientation test failed on tet %d", path, t);
    a->inverted += o <= 0;
  }

  /* surface self-intersections at the current positions */
  int32_t *pairs = NULL;
  int64_t np = 0;
  rc = bs_shim_self_intersections(xc, m->n_vertices, m->faces, m->n_faces, &pairs, &np, err);
  bs_shim_free(pairs);
  if (rc) {
    bs_error_prefix(err, "'%s': self-intersection test", path);
    return rc;
  }
  a->self_pairs = np;
  return BS_OK;
}

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

/* What the audit finds over all frames. */
typedef struct totals {
  long long inverted, pairs, penetrating;
  double max_depth;
  int bad_frames, unreadable;
} totals;

static const char *base_name(const char *path) {
  const char *base = strrchr(path, '/');
  return base ? base + 1 : path;
}

static void print_frame_row(const frame_src *f, const audit *a, const bs_sim *sim) {
  char tbuf[32];
  if (f->has_time) snprintf(tbuf, sizeof tbuf, "%.6g", f->time);
  else snprintf(tbuf, sizeof tbuf, "-");
  char pbuf[32] = "-", dbuf[32] = "-";
  if (sim) {
    snprintf(pbuf, sizeof pbuf, "%d", a->penetrating);
    snprintf(dbuf, sizeof dbuf, "%.3g", a->max_depth);
  }
  printf("%7d %12s %10d %10d %12lld %12s %10s  %s\n", f->number, tbuf, a->n_tets, a->inverted,
         (long long)a->self_pairs, pbuf, dbuf, base_name(f->path));
}

/* Audits every frame of L, a line each unless quiet; sums into T. */
static void audit_frames(const frame_list *L, const bs_scene *sc, bs_sim *sim, int quiet, totals *T) {
  mesh_cache cache = {0};
  double *xc = NULL;
  size_t xc_cap = 0;
  bs_error err;
  for (int i = 0; i < L->n; i++) {
    const frame_src *f = &L->f[i];
    audit a = {0};
    bs_error_clear(&err);
    /* the frame's time: the PVD's, else frame N of `bigstep run` at N / fps */
    double t = f->has_time ? f->time : (sc && sc->mode == BS_MODE_DYNAMIC ? f->number / sc->fps : 0.0);
    if (audit_frame(f->path, t, sim, &cache, &xc, &xc_cap, &a, &err)) {
      fflush(stdout);
      fprintf(stderr, "bigstep check: %s\n", err.msg);
      fflush(stderr);
      T->unreadable++;
      if (!quiet)
        printf("%7d %12s %10s %10s %12s %12s %10s  %s (unreadable)\n", f->number, "-", "-", "-", "-", "-", "-",
               base_name(f->path));
      continue;
    }
    T->inverted += a.inverted;
    T->pairs += a.self_pairs;
    T->penetrating += a.penetrating;
    if (a.max_depth > T->max_depth) T->max_depth = a.max_depth;
    T->bad_frames += a.inverted > 0 || a.self_pairs > 0 || a.penetrating > 0;
    if (!quiet) print_frame_row(f, &a, sim);
  }
  cache_free(&cache);
  free(xc);
}

/* The total line; returns the exit status. */
static int print_total(int n_frames, const totals *T, const bs_sim *sim) {
  int found = T->inverted > 0 || T->pairs > 0 || T->penetrating > 0;
  char pbuf[32] = "-", dbuf[32] = "-";
  if (sim) {
    snprintf(pbuf, sizeof pbuf, "%lld", T->penetrating);
    snprintf(dbuf, sizeof dbuf, "%.3g m", T->max_depth);
  }
  printf("total: %d frames, inverted %lld, self-intersecting pairs %lld, penetrating %s, max depth %s, unreadable %d: ",
         n_frames, T->inverted, T->pairs, pbuf, dbuf, T->unreadable);
  if (found) printf("problems in %d frame%s\n", T->bad_frames, T->bad_frames == 1 ? "" : "s");
  else if (T->unreadable) printf("%d file%s could not be audited\n", T->unreadable, T->unreadable == 1 ? "" : "s");
  else printf("clean\n");
  return found || T->unreadable ? BS_EXIT_FAIL : 0;
}

/* The header: the target, its frames and what is known of obstacles. */
static void print_header(const char *target, const frame_list *L, const bs_sim *sim) {
  char obst[160];
  if (!sim) snprintf(obst, sizeof obst, "obstacles not checked (no --scene)");
  else if (!sim->obstacles) snprintf(obst, sizeof obst, "the scene has no obstacles");
  else snprintf(obst, sizeof obst, "%d obstacle%s of the scene", bs_obstacles_count(sim->obstacles),
                bs_obstacles_count(sim->obstacles) == 1 ? "" : "s");
  printf("bigstep check %s: %d frame%s (%s); %s\n", target, L->n, L->n == 1 ? "" : "s", L->origin, obst);
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
  frame_list L = {0};
  bs_scene *sc = NULL;
  bs_sim *sim = NULL;
  if (list_frames(ca.target, &L, &err) ||
      (ca.scene && (bs_scene_load(ca.scene, 0, NULL, &sc, &err) || bs_sim_create(sc, &sim, &err)))) {
    fprintf(stderr, "bigstep check: %s\n", err.msg);
    bs_scene_destroy(&sc);
    list_free(&L);
    return BS_EXIT_FAIL;
  }
  if (!ca.quiet) print_header(ca.target, &L, sim);
  totals T = {0};
  audit_frames(&L, sc, sim, ca.quiet, &T);
  rc = print_total(L.n, &T, sim);
  list_free(&L);
  bs_sim_destroy(&sim);
  bs_scene_destroy(&sc);
  return rc;
}
