/* gmsh_io.c — meshes in and out through the Gmsh C API (deal.II's GridIn /
 * GridOut): bs_mesh_read and bs_mesh_write_msh.
 *
 * Gmsh keeps one global state. Every use of it here runs under one mutex,
 * between gmshInitialize (no configuration files) and gmshFinalize, with
 * General.Terminal = 0 so that the library prints nothing (and stdout pointed
 * at /dev/null, for the reports Gmsh prints regardless); Gmsh's messages go
 * to its logger, and its last error is copied into the bs_error. Gmsh sets
 * LC_NUMERIC to "C" and the OpenMP thread count (omp_set_num_threads, from
 * General.NumThreads); the caller's settings of both are restored afterwards.
 *
 * Inputs, by extension (case-insensitive):
 *   .msh                              taken as is (v2 / v4, ASCII / binary), once
 *                                     msh_check.c has checked it (Gmsh's .msh
 *                                     readers trust their input);
 *   .geo .step .stp .brep .iges .igs  meshed in 3-D; STEP and IGES lengths are
 *                                     converted to metres (OCCTargetUnit "M");
 *   .stl .off .obj .ply               a surface read by the shim (OFF by its own
 *                                     reader, STL / OBJ / PLY by CGAL), repaired
 *                                     (bs_surface_prepare: closed, outward, no
 *                                     self-intersection).
 * A closed surface is meshed into a volume: with opts->size > 0 by CGAL's
 * Mesh_3 (surface_mesh.c; Gmsh is not involved) unless opts->surface_mesher
 * asks for Gmsh, which classifies it into patches (40 degree feature angle),
 * reparametrizes and remeshes them at that size (with size <= 0 Gmsh keeps
 * its triangles as the boundary of the volume mesh, as it does for a
 * surface given no size and no gate); with size <= 0 and a gate (and not the
 * Gmsh mesher) at the size bigstep chooses (bs_surface_auto_size).
 * Every input but .msh has a time budget (opts->time_budget, mesh_budget.c)
 * and, when Gmsh's or Mesh_3's mesh misses the gate, is lifted by CGAL's
 * tetrahedral remeshing (tet_lift.c).
 * Meshes made here (not a .msh) are optimised by Gmsh towards the quality
 * gate (gmsh_optimize.c; a CAD assembly at its own size still under it is
 * meshed again with smaller elements, cad_assembly.c) and then held to it
 * (bs_mesh_dihedral_gate). For
 * geometry, size > 0 sets Mesh.MeshSizeMin = Mesh.MeshSizeMax = size after
 * the file is read (so it overrides the file's settings).
 *
 * The model becomes a bs_mesh: node tags (possibly sparse) map to vertex
 * indices in increasing tag order; the 4-node tets of every volume entity, in
 * entity order, become tets; any other 3-D element is an error. Physical groups
 * become bs_group (3-D: the tets of the group's entities; 2-D / 1-D / 0-D: the
 * triangles / lines / points of its entities as vertex tuples). A model with no
 * physical group at all gets default groups: (3, 1, "body") for a single volume
 * entity or (3, tag, "volume_<tag>") per volume entity when there are several,
 * and (2, tag, "surface_<tag>") per surface entity; a CAD file (STEP, IGES,
 * BREP) of several solids is first fragmented into a conformal model with one
 * named 3-D group per part (cad_assembly.c). Nodes at exactly the
 * position of another node (distinct tags) are counted in n_coincident and,
 * with opts->merge_coincident, mapped to the vertex of the smallest tag there.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <locale.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gmshc.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "bs_mesh.h"
#include "bs_shim.h"
#include "mesh_internal.h"

#define BS_PI 3.14159265358979323846

/* Gmsh element types used here (Gmsh's numbering). */
enum { GMSH_LINE = 1, GMSH_TRIANGLE = 2, GMSH_TET = 4, GMSH_TET10 = 11, GMSH_POINT = 15 };

/* First-order simplex of dimension d: point, line, triangle, tet. */
static const int simplex_type[4] = {GMSH_POINT, GMSH_LINE, GMSH_TRIANGLE, GMSH_TET};
/* Second-order simplex of dimension d (Gmsh's 1-node point, 3-node line,
 * 6-node triangle, 10-node tet) and its node count. */
static const int simplex2_type[4] = {GMSH_POINT, 8, 9, 11};
static const int simplex2_nodes[4] = {1, 3, 6, 10};

/* ---- the Gmsh session --------------------------------------------------- */

static pthread_mutex_t gmsh_mutex = PTHREAD_MUTEX_INITIALIZER;
static char gmsh_saved_locale[256]; /* guarded by gmsh_mutex */

/* The last error Gmsh logged in this session (or a note that there is none)
 * into buf. The session's own log is used, not gmshLoggerGetLastError, which
 * keeps the last error of any earlier session. */
static void gmsh_last_error(char *buf, size_t n) {
  char **log = NULL;
  size_t n_log = 0;
  int ierr = 0;
  static const char prefix[] = "Error: ";
  snprintf(buf, n, "%s", "Gmsh gave no message");
  gmshLoggerGet(&log, &n_log, &ierr);
  for (size_t i = 0; !ierr && i < n_log; i++)
    if (log[i] && strncmp(log[i], prefix, sizeof prefix - 1) == 0)
      snprintf(buf, n, "%s", log[i] + sizeof prefix - 1);
  for (size_t i = 0; i < n_log; i++)
    if (log && log[i]) gmshFree(log[i]);
  if (log) gmshFree(log);
  size_t len = strlen(buf);
  while (len > 0 && (buf[len - 1] == ' ' || buf[len - 1] == '\n' || buf[len - 1] == '\r')) buf[--len] = '\0';
}

/* Records "<path>: Gmsh could not <what>: <Gmsh's last error>". */
static int gmsh_fail(bs_error *err, int code, const char *path, const char *what) {
  char msg[800];
  gmsh_last_error(msg, sizeof msg);
  return bs_error_set(err, code, "%s: Gmsh could not %s: %s", path, what, msg);
}

int bs__gmsh_fail(bs_error *err, int code, const char *path, const char *what) {
  return gmsh_fail(err, code, path, what);
}

/* Silences Gmsh (the options a file may have changed are set again after it is read). */
static void gmsh_quiet(void) {
  int ierr = 0;
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshOptionSetNumber("General.Verbosity", 1, &ierr); /* errors only, and only to the logger */
}

/* The caller's OpenMP thread count, saved by gmsh_begin (under the lock):
 * Gmsh sets it from General.NumThreads (1 by default) with
 * omp_set_num_threads, which outlives gmshFinalize; without the restore every
 * parallel region after a Gmsh call ran on one thread. */
static int gmsh_saved_threads = 1;

/* Gmsh 4.8.4's TetGen boundary recovery (HXT's and Delaunay's) reports
 * nearly overlapping facets with printf on stdout whatever General.Terminal
 * says ("Found two nearly self-intersecting facets ..."): a JSON report
 * printed after it (bigstep mesh info --json) was no longer JSON. stdout's
 * descriptor points at /dev/null for the session (flushed on both sides, so
 * what was printed before goes out and what Gmsh printed is dropped);
 * stderr is left alone (a sanitizer's report must get out). Process-wide,
 * like Gmsh's state: nothing else in bigstep prints while a library call
 * runs. gmsh_stdout_fd: the saved descriptor, -1 when not silenced (no
 * /dev/null or no descriptor left: Gmsh may then print). */
static int gmsh_stdout_fd = -1;

static void gmsh_stdout_off(void) {
  fflush(stdout);
  const int null_fd = open("/dev/null", O_WRONLY);
  if (null_fd < 0) return;
  gmsh_stdout_fd = dup(STDOUT_FILENO);
  if (gmsh_stdout_fd >= 0 && dup2(null_fd, STDOUT_FILENO) < 0) close(gmsh_stdout_fd), gmsh_stdout_fd = -1;
  close(null_fd);
}

static void gmsh_stdout_on(void) {
  if (gmsh_stdout_fd < 0) return;
  fflush(stdout);
  dup2(gmsh_stdout_fd, STDOUT_FILENO);
  close(gmsh_stdout_fd);
  gmsh_stdout_fd = -1;
}

static void gmsh_end(void) {
  int ierr = 0;
  gmshLoggerStop(&ierr);
  gmshFinalize(&ierr);
  gmsh_stdout_on();
  setlocale(LC_NUMERIC, gmsh_saved_locale);
#ifdef _OPENMP
  omp_set_num_threads(gmsh_saved_threads);
#endif
  pthread_mutex_unlock(&gmsh_mutex);
}

/* Takes the Gmsh lock and initializes Gmsh; on failure the lock is released. */
static int gmsh_begin(const char *path, bs_error *err) {
  pthread_mutex_lock(&gmsh_mutex);
  gmsh_stdout_off();
  const char *loc = setlocale(LC_NUMERIC, NULL);
  snprintf(gmsh_saved_locale, sizeof gmsh_saved_locale, "%s", loc ? loc : "C");
#ifdef _OPENMP
  gmsh_saved_threads = omp_get_max_threads();
#endif
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  if (ierr) {
    gmsh_end();
    return bs_error_set(err, BS_EGMSH, "%s: Gmsh failed to initialize", path);
  }
  gmsh_quiet();
  gmshLoggerStart(&ierr);
  return BS_OK;
}

/* ---- small helpers ------------------------------------------------------ */

/* The extension of path (after the last '.' of its last component), or "". */
static const char *file_ext(const char *path) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  const char *dot = strrchr(base, '.');
  return dot ? dot + 1 : "";
}

static int ext_is(const char *ext, const char *const *list) {
  for (; *list; list++)
    if (strcasecmp(ext, *list) == 0) return 1;
  return 0;
}

typedef enum { IN_MESH, IN_GEOMETRY, IN_SOUP, IN_UNKNOWN } input_kind;

static input_kind classify_input(const char *path) {
  static const char *const mesh[] = {"msh", NULL};
  static const char *const geometry[] = {"geo", "step", "stp", "brep", "iges", "igs", NULL};
  static const char *const soup[] = {"off", "obj", "ply", "stl", NULL};
  const char *ext = file_ext(path);
  if (ext_is(ext, mesh)) return IN_MESH;
  if (ext_is(ext, geometry)) return IN_GEOMETRY;
  if (ext_is(ext, soup)) return IN_SOUP;
  return IN_UNKNOWN;
}

/* A growable int32 array. */
typedef struct ivec {
  int32_t *a;
  size_t n, cap;
} ivec;

static int ivec_reserve(ivec *v, size_t extra, bs_error *err) {
  if (v->n + extra <= v->cap) return BS_OK;
  size_t cap = v->cap ? v->cap : 64;
  while (cap < v->n + extra) cap *= 2;
  int32_t *a = realloc(v->a, cap * sizeof *a);
  if (!a) return bs_error_set(err, BS_ENOMEM, "out of memory for %zu mesh indices", cap);
  v->a = a;
  v->cap = cap;
  return BS_OK;
}

/* ---- node tags -> vertex indices ---------------------------------------- */

/* Vertices are numbered in increasing node-tag order. Lookup goes through a
 * dense table when the tags are dense enough, else by binary search. */
typedef struct node_map {
  size_t n;
  size_t *tags;   /* n, sorted ascending                */
  int32_t *dense; /* max tag + 1 entries (-1: no node) or NULL */
  size_t dense_n;
  int32_t *rep;   /* n: the vertex each node maps to (merged coincident
                     nodes), or NULL (node i is vertex i) */
} node_map;

typedef struct tag_pos {
  size_t tag;
  size_t pos;
} tag_pos;

static int cmp_tag_pos(const void *a, const void *b) {
  const tag_pos *p = a, *q = b;
  return (p->tag > q->tag) - (p->tag < q->tag);
}

static void node_map_free(node_map *nm) {
  free(nm->tags);
  free(nm->dense);
  free(nm->rep);
  memset(nm, 0, sizeof *nm);
}

static int32_t node_map_find(const node_map *nm, size_t tag) {
  int32_t i = -1;
  if (nm->dense) {
    i = tag < nm->dense_n ? nm->dense[tag] : -1;
  } else {
    size_t lo = 0, hi = nm->n;
    while (lo < hi) {
      size_t mid = lo + (hi - lo) / 2;
      if (nm->tags[mid] < tag) lo = mid + 1;
      else hi = mid;
    }
    if (lo < nm->n && nm->tags[lo] == tag) i = (int32_t)lo;
  }
  return (i >= 0 && nm->rep) ? nm->rep[i] : i;
}

/* Counts the nodes at the position of another node (distinct tags: a tag
 * is defined once, read_nodes checks it); with merge, maps each of them to
 * the vertex of the smallest tag at its position. */
static int coincident_nodes(const char *path, node_map *nm, const double *x, int merge, int32_t *count,
                            bs_error *err) {
  int32_t *rep = malloc((nm->n ? nm->n : 1) * sizeof *rep);
  if (!rep) return bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu nodes", path, nm->n);
  int64_t c = bs__coincident((int64_t)nm->n, x, rep, err);
  if (c < 0) {
    free(rep);
    return BS_ENOMEM;
  }
  *count = (int32_t)c;
  if (merge && c > 0) nm->rep = rep;
  else free(rep);
  return BS_OK;
}

/* All nodes of the model: *x (3 per vertex, tag order) and the map. */
static int read_nodes(const char *path, node_map *nm, double **x_out, bs_error *err) {
  size_t *tags = NULL, n_tags = 0, n_coord = 0, n_par = 0;
  double *coord = NULL, *par = NULL;
  int ierr = 0, rc = BS_OK;
  tag_pos *tp = NULL;
  double *x = NULL;
  gmshModelMeshGetNodes(&tags, &n_tags, &coord, &n_coord, &par, &n_par, -1, -1, 0, 0, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the mesh nodes");
    goto done;
  }
  if (n_coord != 3 * n_tags) {
    rc = bs_error_set(err, BS_EINTERNAL, "%s: Gmsh returned %zu coordinates for %zu nodes", path, n_coord, n_tags);
    goto done;
  }
  if (n_tags > (size_t)INT32_MAX) {
    rc = bs_error_set(err, BS_EINPUT, "%s: %zu nodes exceed the 32-bit index range", path, n_tags);
    goto done;
  }
  tp = malloc((n_tags ? n_tags : 1) * sizeof *tp);
  x = malloc((n_tags ? 3 * n_tags : 1) * sizeof *x);
  nm->tags = malloc((n_tags ? n_tags : 1) * sizeof *nm->tags);
  if (!tp || !x || !nm->tags) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu nodes", path, n_tags);
    goto done;
  }
  for (size_t i = 0; i < n_tags; i++) tp[i] = (tag_pos){tags[i], i};
  qsort(tp, n_tags, sizeof *tp, cmp_tag_pos);
  size_t max_tag = 0;
  for (size_t i = 0; i < n_tags; i++) {
    if (i > 0 && tp[i].tag == tp[i - 1].tag) {
      rc = bs_error_set(err, BS_EINPUT, "%s: node tag %zu is defined twice", path, tp[i].tag);
      goto done;
    }
    nm->tags[i] = tp[i].tag;
    for (int k = 0; k < 3; k++) x[3 * i + k] = coord[3 * tp[i].pos + k];
    if (tp[i].tag > max_tag) max_tag = tp[i].tag;
  }
  nm->n = n_tags;
  if (n_tags > 0 && max_tag <= 4 * n_tags + 1024) {
    nm->dense_n = max_tag + 1;
    nm->dense = malloc(nm->dense_n * sizeof *nm->dense);
    if (!nm->dense) {
      rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the node table", path);
      goto done;
    }
    for (size_t t = 0; t < nm->dense_n; t++) nm->dense[t] = -1;
    for (size_t i = 0; i < n_tags; i++) nm->dense[nm->tags[i]] = (int32_t)i;
  }
  *x_out = x;
  x = NULL;
done:
  free(tp);
  free(x);
  if (tags) gmshFree(tags);
  if (coord) gmshFree(coord);
  if (par) gmshFree(par);
  return rc;
}

/* Appends the elements of type `type` (n_nodes nodes each) on entity `tag`
 * to v as vertex indices, the first `keep` nodes of each (its corners for a
 * second-order element); element tags to etags if non-NULL. */
static int append_elements(const char *path, int type, int n_nodes, int keep, int tag, const node_map *nm, ivec *v,
                           size_t **etags_out, size_t *n_etags_out, bs_error *err) {
  size_t *etags = NULL, ne = 0, *ntags = NULL, nn = 0;
  int ierr = 0, rc = BS_OK;
  gmshModelMeshGetElementsByType(type, &etags, &ne, &ntags, &nn, tag, 0, 1, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the elements");
    goto done;
  }
  if (nn != (size_t)n_nodes * ne) {
    rc = bs_error_set(err, BS_EINTERNAL, "%s: Gmsh returned %zu nodes for %zu elements of type %d", path, nn, ne,
                      type);
    goto done;
  }
  if ((rc = ivec_reserve(v, nn, err))) goto done;
  for (size_t e = 0; e < ne; e++)
    for (int k = 0; k < keep; k++) {
      size_t nt = ntags[(size_t)n_nodes * e + k];
      int32_t i = node_map_find(nm, nt);
      if (i < 0) {
        rc = bs_error_set(err, BS_EINPUT, "%s: element %zu refers to node %zu, which is not defined", path, etags[e],
                          nt);
        goto done;
      }
      v->a[v->n++] = i;
    }
  if (etags_out) {
    *etags_out = etags;
    *n_etags_out = ne;
    etags = NULL;
  }
done:
  if (etags) gmshFree(etags);
  if (ntags) gmshFree(ntags);
  return rc;
}

/* The Gmsh name of an element type ("Tetrahedron 10", ...). */
static void element_name(int type, char *buf, size_t n) {
  char *name = NULL;
  int dim = 0, order = 0, nn = 0, np = 0, ierr = 0;
  double *lc = NULL;
  size_t nlc = 0;
  gmshModelMeshGetElementProperties(type, &name, &dim, &order, &nn, &lc, &nlc, &np, &ierr);
  snprintf(buf, n, "%s", (!ierr && name) ? name : "unknown");
  if (name) gmshFree(name);
  if (lc) gmshFree(lc);
}

/* Number of elements of a type in the whole model (0 on error). */
static size_t count_elements(int type) {
  size_t *etags = NULL, ne = 0, *ntags = NULL, nn = 0;
  int ierr = 0;
  gmshModelMeshGetElementsByType(type, &etags, &ne, &ntags, &nn, -1, 0, 1, &ierr);
  if (etags) gmshFree(etags);
  if (ntags) gmshFree(ntags);
  return ierr ? 0 : ne;
}

/* Only 4-node tets, or 10-node tets alone (*quadratic = 1), are read: any
 * other 3-D element type is an error naming the types and counts; no 3-D
 * element at all is an error too. */
static int check_volume_types(const char *path, int *quadratic, bs_error *err) {
  int *types = NULL, ierr = 0, rc = BS_OK;
  size_t n = 0;
  gmshModelMeshGetElementTypes(&types, &n, 3, -1, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the element types");
    goto done;
  }
  if (n == 0) {
    rc = bs_error_set(err, BS_EINPUT, "%s: no volume elements (the file holds no 3-D mesh, only %s)", path,
                      "lower-dimensional elements or none");
    goto done;
  }
  char list[700] = "";
  size_t used = 0;
  int bad = 0;
  *quadratic = n == 1 && types[0] == GMSH_TET10;
  for (size_t i = 0; i < n; i++) {
    if (types[i] == GMSH_TET || *quadratic) continue;
    char name[64];
    element_name(types[i], name, sizeof name);
    int w = snprintf(list + used, sizeof list - used, "%s%zu \"%s\" (Gmsh type %d)", bad ? ", " : "",
                     count_elements(types[i]), name, types[i]);
    if (w > 0 && (size_t)w < sizeof list - used) used += (size_t)w;
    bad++;
  }
  if (bad)
    rc = bs_error_set(err, BS_EINPUT,
                      "%s: unsupported volume elements: %s; only 4-node tetrahedra (\"Tetrahedron 4\") or 10-node ones "
                      "alone (\"Tetrahedron 10\") are read (mesh with no recombination)",
                      path, list);
done:
  if (types) gmshFree(types);
  return rc;
}

/* ---- closed surfaces into volumes --------------------------------------- */

/* Hands a triangle soup to Gmsh as the discrete surface (2, 1). */
static int add_discrete_surface(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                                bs_error *err) {
  int ierr = 0, rc = BS_OK;
  size_t *ntag = malloc((size_t)(np > 0 ? np : 1) * sizeof *ntag);
  size_t *etag = malloc((size_t)(nt > 0 ? nt : 1) * sizeof *etag);
  size_t *enodes = malloc((size_t)(nt > 0 ? 3 * nt : 1) * sizeof *enodes);
  if (!ntag || !etag || !enodes) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the surface", path);
    goto done;
  }
  for (int64_t i = 0; i < np; i++) ntag[i] = (size_t)i + 1;
  for (int64_t e = 0; e < nt; e++) {
    etag[e] = (size_t)e + 1;
    for (int k = 0; k < 3; k++) enodes[3 * e + k] = (size_t)tris[3 * e + k] + 1;
  }
  gmshModelAdd("surface", &ierr);
  if (!ierr) gmshModelAddDiscreteEntity(2, 1, NULL, 0, &ierr);
  if (!ierr) gmshModelMeshAddNodes(2, 1, ntag, (size_t)np, (double *)pts, 3 * (size_t)np, NULL, 0, &ierr);
  if (!ierr) gmshModelMeshAddElementsByType(1, GMSH_TRIANGLE, etag, (size_t)nt, enodes, 3 * (size_t)nt, &ierr);
  if (ierr) rc = gmsh_fail(err, BS_EGMSH, path, "take the surface triangles");
done:
  free(ntag);
  free(etag);
  free(enodes);
  return rc;
}

/* Meshes the volume bounded by the model's surfaces (see the file comment). */
/* The volume (m^3) of the model's 3-D entities (OpenCASCADE's mass), or of
 * its bounding box when it has none or the kernel cannot say; 0 if unknown. */
static double model_volume(void) {
  int ierr = 0, *dt = NULL;
  size_t n = 0;
  double v = 0;
  gmshModelGetEntities(&dt, &n, 3, &ierr);
  for (size_t i = 0; !ierr && i + 1 < n; i += 2) {
    double m = 0;
    gmshModelOccGetMass(3, dt[i + 1], &m, &ierr);
    v += m;
  }
  gmshFree(dt);
  if (!ierr && v > 0 && isfinite(v)) return v;
  double lo[3], hi[3];
  ierr = 0;
  gmshModelGetBoundingBox(-1, -1, &lo[0], &lo[1], &lo[2], &hi[0], &hi[1], &hi[2], &ierr);
  v = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  return !ierr && isfinite(v) && v > 0 ? v : 0;
}

static int surface_to_volume(const char *path, double size, const bs_mesh_read_opts *opts, bs_error *err) {
  int ierr = 0, rc = BS_OK;
  int *dt = NULL, *tags = NULL;
  size_t ndt = 0;
  if (size > 0 && (rc = bs__check_mesh_size(model_volume(), size, opts, path, err))) return rc;
  if (size > 0) {
    gmshModelMeshClassifySurfaces(40.0 * BS_PI / 180.0, 1, 1, BS_PI, 0, &ierr);
    if (ierr) return gmsh_fail(err, BS_EGMSH, path, "classify the surface into patches");
    gmshModelMeshCreateGeometry(NULL, 0, &ierr);
    if (ierr) return gmsh_fail(err, BS_EGMSH, path, "parametrize the surface patches");
  }
  gmshModelGetEntities(&dt, &ndt, 2, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the surfaces");
    goto done;
  }
  size_t ns = ndt / 2;
  if (ns == 0) {
    rc = bs_error_set(err, BS_EINPUT, "%s: no surface triangles to mesh a volume from", path);
    goto done;
  }
  tags = malloc(ns * sizeof *tags);
  if (!tags) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory", path);
    goto done;
  }
  for (size_t i = 0; i < ns; i++) tags[i] = dt[2 * i + 1];
  int loop = gmshModelGeoAddSurfaceLoop(tags, ns, -1, &ierr);
  if (!ierr) gmshModelGeoAddVolume(&loop, 1, -1, &ierr);
  if (!ierr) gmshModelGeoSynchronize(&ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "make a volume bounded by the surface");
    goto done;
  }
  if (size > 0) {
    gmshOptionSetNumber("Mesh.MeshSizeMin", size, &ierr);
    gmshOptionSetNumber("Mesh.MeshSizeMax", size, &ierr);
  }
  gmshModelMeshGenerate(3, &ierr);
  if (ierr) rc = gmsh_fail(err, BS_EGMSH, path, "mesh the volume inside the surface (is it closed?)");
done:
  if (dt) gmshFree(dt);
  free(tags);
  return rc;
}

/* ---- the model as a bs_mesh --------------------------------------------- */

typedef struct volume_range {
  int tag;
  size_t first, count; /* tets [first, first + count) */
} volume_range;

/* Elements of dimension dim < 3 on the given entities as vertex tuples. */
static int group_simplices(const char *path, int dim, const int *ents, size_t n_ents, const char *gname, int gtag,
                           const node_map *nm, ivec *v, bs_error *err) {
  int rc = BS_OK;
  for (size_t i = 0; i < n_ents && !rc; i++) {
    int *types = NULL, ierr = 0;
    size_t nt = 0;
    gmshModelMeshGetElementTypes(&types, &nt, dim, ents[i], &ierr);
    if (ierr) {
      rc = gmsh_fail(err, BS_EGMSH, path, "list the element types of a group");
      break;
    }
    for (size_t k = 0; k < nt && !rc; k++) {
      const int second = types[k] == simplex2_type[dim] && dim > 0; /* a quadratic mesh's: its corners */
      if (types[k] != simplex_type[dim] && !second) {
        char name[64];
        element_name(types[k], name, sizeof name);
        rc = bs_error_set(err, BS_EINPUT,
                          "%s: physical group \"%s\" (dim %d, tag %d) holds \"%s\" elements (Gmsh type %d); groups "
                          "may hold only points, 2- or 3-node lines and 3- or 6-node triangles",
                          path, gname, dim, gtag, name, types[k]);
        break;
      }
      rc = append_elements(path, types[k], second ? simplex2_nodes[dim] : dim + 1, dim + 1, ents[i], nm, v, NULL, NULL,
                           err);
    }
    if (types) gmshFree(types);
  }
  return rc;
}

/* Tet indices of the given volume entities. */
static int group_tets(const int *ents, size_t n_ents, const volume_range *vr, size_t n_vol, ivec *v, bs_error *err) {
  for (size_t i = 0; i < n_ents; i++)
    for (size_t j = 0; j < n_vol; j++) {
      if (vr[j].tag != ents[i]) continue;
      int rc = ivec_reserve(v, vr[j].count, err);
      if (rc) return rc;
      for (size_t t = 0; t < vr[j].count; t++) v->a[v->n++] = (int32_t)(vr[j].first + t);
    }
  return BS_OK;
}

/* Moves v into a new group (dim, tag, name). */
static int push_group(bs_group *groups, int *n_groups, int dim, int tag, const char *name, ivec *v, bs_error *err) {
  bs_group *g = &groups[*n_groups];
  memset(g, 0, sizeof *g);
  g->name = bs__strdup(name);
  if (!g->name) return bs_error_set(err, BS_ENOMEM, "out of memory for group \"%s\"", name);
  g->dim = dim;
  g->tag = tag;
  g->n_elems = (int32_t)(v->n / (size_t)bs__group_elem_size(dim));
  g->elems = v->a;
  memset(v, 0, sizeof *v);
  (*n_groups)++;
  return BS_OK;
}

/* The model's physical groups, or the default groups when it has none. */
static int read_groups(const char *path, const node_map *nm, const volume_range *vr, size_t n_vol,
                       bs_group **groups_out, int *n_groups_out, bs_error *err) {
  int *pg = NULL, *sdt = NULL, ierr = 0, rc = BS_OK, n_groups = 0;
  size_t npg = 0, nsdt = 0;
  bs_group *groups = NULL;
  ivec v = {0};
  gmshModelGetPhysicalGroups(&pg, &npg, -1, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the physical groups");
    goto done;
  }
  npg /= 2;
  if (npg > 0) {
    groups = calloc(npg, sizeof *groups);
    if (!groups) {
      rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu groups", path, npg);
      goto done;
    }
    for (size_t i = 0; i < npg && !rc; i++) {
      int dim = pg[2 * i], tag = pg[2 * i + 1];
      char *name = NULL;
      int *ents = NULL;
      size_t n_ents = 0;
      gmshModelGetPhysicalName(dim, tag, &name, &ierr);
      if (!ierr) gmshModelGetEntitiesForPhysicalGroup(dim, tag, &ents, &n_ents, &ierr);
      if (ierr) rc = gmsh_fail(err, BS_EGMSH, path, "read a physical group");
      else if (dim == 3) rc = group_tets(ents, n_ents, vr, n_vol, &v, err);
      else if (dim >= 0 && dim < 3)
        rc = group_simplices(path, dim, ents, n_ents, name ? name : "", tag, nm, &v, err);
      else
        rc = bs_error_set(err, BS_EINPUT, "%s: physical group %d has dimension %d", path, tag, dim);
      if (!rc) rc = push_group(groups, &n_groups, dim, tag, name ? name : "", &v, err);
      if (name) gmshFree(name);
      if (ents) gmshFree(ents);
    }
    goto done;
  }

  /* Default groups: the volumes, then one group per surface entity. */
  gmshModelGetEntities(&sdt, &nsdt, 2, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the surfaces");
    goto done;
  }
  nsdt /= 2;
  groups = calloc(n_vol + nsdt + 1, sizeof *groups);
  if (!groups) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the default groups", path);
    goto done;
  }
  for (size_t j = 0; j < n_vol && !rc; j++) {
    char name[64];
    int tag = n_vol == 1 ? 1 : vr[j].tag;
    snprintf(name, sizeof name, n_vol == 1 ? "body" : "volume_%d", vr[j].tag);
    rc = group_tets(&vr[j].tag, 1, vr, n_vol, &v, err);
    if (!rc) rc = push_group(groups, &n_groups, 3, tag, name, &v, err);
  }
  for (size_t j = 0; j < nsdt && !rc; j++) {
    char name[64];
    int tag = sdt[2 * j + 1];
    snprintf(name, sizeof name, "surface_%d", tag);
    rc = group_simplices(path, 2, &tag, 1, name, tag, nm, &v, err);
    if (!rc) rc = push_group(groups, &n_groups, 2, tag, name, &v, err);
  }
done:
  free(v.a);
  if (pg) gmshFree(pg);
  if (sdt) gmshFree(sdt);
  if (rc) {
    bs__groups_free(groups, n_groups);
    groups = NULL;
    n_groups = 0;
  }
  *groups_out = groups;
  *n_groups_out = n_groups;
  return rc;
}

/* A tet whose |volume| <= 1e-14 (longest edge)^3 is degenerate (the threshold
 * of bs_mesh_finalize); named here by its Gmsh element and node tags. */
static int check_zero_volume(const char *path, const double *x, const ivec *tets, const size_t *etags,
                             const node_map *nm, bs_error *err) {
  size_t nt = tets->n / 4;
  for (size_t t = 0; t < nt; t++) {
    const int32_t *v = tets->a + 4 * t;
    const double *p0 = x + 3 * v[0];
    double e[3][3], l2max = 0;
    for (int i = 0; i < 3; i++)
      for (int k = 0; k < 3; k++) e[i][k] = x[3 * v[i + 1] + k] - p0[k];
    for (int a = 0; a < 4; a++)
      for (int b = a + 1; b < 4; b++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
          double d = x[3 * v[a] + k] - x[3 * v[b] + k];
          d2 += d * d;
        }
        if (d2 > l2max) l2max = d2;
      }
    double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                 e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                 e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
    double vol = fabs(det) / 6.0;
    if (vol <= 1e-14 * l2max * sqrt(l2max))
      return bs_error_set(err, BS_EINPUT,
                          "%s: tetrahedron element %zu (tet %zu, nodes %zu %zu %zu %zu) has zero volume (%.3g m^3)",
                          path, etags[t], t, nm->tags[v[0]], nm->tags[v[1]], nm->tags[v[2]], nm->tags[v[3]], vol);
  }
  return BS_OK;
}

/* The file's midside nodes of a mesh of 10-node tets (t10: 10 node indices
 * per tet, Gmsh's order; tets: their corners) into m's midside list
 * (bs_mesh.midside_edge / midside_x), with m's vertex numbering: the nodes
 * some tet uses, in input order (as bs_mesh_create numbers them). */
static int attach_midside(bs_mesh *m, int32_t n_nodes, const double *x, const ivec *tets, const ivec *t10,
                          bs_error *err) {
  static const int ends[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}}; /* VTK's edges 4..9 */
  const size_t nt = tets->n / 4;
  int32_t *newid = bs_calloc((size_t)n_nodes + 1, sizeof(int32_t), "midside renumbering", err);
  m->midside_edge = bs_calloc(12 * nt + 1, sizeof(int32_t), "midside edges", err);
  m->midside_x = bs_calloc(18 * nt + 1, sizeof(double), "midside nodes", err);
  if (!newid || !m->midside_edge || !m->midside_x) {
    free(newid);
    return BS_ENOMEM;
  }
  for (size_t i = 0; i < tets->n; i++) newid[tets->a[i]] = 1;
  for (int32_t v = 0, k = 0; v < n_nodes; v++) newid[v] = newid[v] ? k++ : -1;
  for (size_t i = 0; i < t10->n; i++) /* the midside nodes are not dropped vertices */
    if (newid[t10->a[i]] == -1) newid[t10->a[i]] = -2, m->n_dropped--;
  for (size_t e = 0; e < nt; e++)
    for (int k = 0; k < 6; k++) {
      const int g = 4 + k == 8 ? 9 : 4 + k == 9 ? 8 : 4 + k; /* VTK's node 4 + k in Gmsh's order */
      const size_t i = 6 * e + (size_t)k;
      m->midside_edge[2 * i] = newid[t10->a[10 * e + (size_t)ends[k][0]]];
      m->midside_edge[2 * i + 1] = newid[t10->a[10 * e + (size_t)ends[k][1]]];
      memcpy(m->midside_x + 3 * i, x + 3 * (size_t)t10->a[10 * e + (size_t)g], 3 * sizeof(double));
    }
  m->n_midside = (int32_t)(6 * nt);
  free(newid);
  return BS_OK;
}

/* The current Gmsh model as a bs_mesh (coincident nodes merged with merge). */
static int model_to_mesh(const char *path, int merge, bs_mesh **out, bs_error *err) {
  int rc, ierr = 0;
  node_map nm = {0};
  double *x = NULL;
  int *vdt = NULL;
  size_t nvdt = 0, n_vol = 0, *etags = NULL, n_etags = 0;
  volume_range *vr = NULL;
  ivec tets = {0}, t10 = {0};
  bs_group *groups = NULL;
  int n_groups = 0, quad = 0;
  int32_t n_coincident = 0;

  if ((rc = check_volume_types(path, &quad, err))) goto done;
  if ((rc = read_nodes(path, &nm, &x, err))) goto done;
  if ((rc = coincident_nodes(path, &nm, x, merge, &n_coincident, err))) goto done;

  gmshModelGetEntities(&vdt, &nvdt, 3, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "list the volumes");
    goto done;
  }
  n_vol = nvdt / 2;
  vr = calloc(n_vol ? n_vol : 1, sizeof *vr);
  if (!vr) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory", path);
    goto done;
  }
  for (size_t j = 0; j < n_vol; j++) {
    size_t *et = NULL, ne = 0;
    vr[j].tag = vdt[2 * j + 1];
    vr[j].first = tets.n / 4;
    const int type = quad ? GMSH_TET10 : GMSH_TET, nn = quad ? 10 : 4;
    if ((rc = append_elements(path, type, nn, 4, vr[j].tag, &nm, &tets, &et, &ne, err))) goto done;
    if (quad && (rc = append_elements(path, type, nn, nn, vr[j].tag, &nm, &t10, NULL, NULL, err))) goto done;
    vr[j].count = ne;
    size_t *grown = realloc(etags, (n_etags + ne + 1) * sizeof *etags);
    if (!grown) {
      gmshFree(et);
      rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for %zu element tags", path, n_etags + ne);
      goto done;
    }
    etags = grown;
    if (ne) memcpy(etags + n_etags, et, ne * sizeof *et);
    n_etags += ne;
    gmshFree(et);
  }
  if (tets.n == 0) {
    rc = bs_error_set(err, BS_EINPUT, "%s: no volume elements (no tetrahedra in any volume)", path);
    goto done;
  }
  if (tets.n / 4 > (size_t)INT32_MAX) {
    rc = bs_error_set(err, BS_EINPUT, "%s: %zu tets exceed the 32-bit index range", path, tets.n / 4);
    goto done;
  }
  if ((rc = check_zero_volume(path, x, &tets, etags, &nm, err))) goto done;
  if ((rc = read_groups(path, &nm, vr, n_vol, &groups, &n_groups, err))) goto done;

  rc = bs_mesh_create((int32_t)nm.n, x, (int32_t)(tets.n / 4), tets.a, n_groups, groups, out, err);
  if (rc) bs_error_prefix(err, "%s", path);
  if (!rc) {
    (*out)->n_coincident = n_coincident;
    (*out)->coincident_merged = nm.rep != NULL;
    if (nm.rep) (*out)->n_dropped -= n_coincident; /* the merged nodes are no tet's now */
    if (quad) rc = attach_midside(*out, (int32_t)nm.n, x, &tets, &t10, err);
  }
done:
  node_map_free(&nm);
  free(x);
  free(t10.a);
  if (vdt) gmshFree(vdt);
  free(vr);
  free(tets.a);
  free(etags);
  bs__groups_free(groups, n_groups);
  return rc;
}

/* ---- bs_mesh_read ------------------------------------------------------- */

/* Refines the mesh read from path `refine` times (what the read found out
 * about coincident nodes is carried over). */
static int refine_read(const char *path, int refine, bs_mesh **m, bs_error *err) {
  for (int level = 0; level < refine; level++) {
    bs_mesh *fine = NULL;
    int rc = bs_mesh_refine(*m, &fine, err);
    if (rc) {
      bs_error_prefix(err, "%s: refinement %d of %d", path, level + 1, refine);
      return rc;
    }
    fine->n_coincident = (*m)->n_coincident;
    fine->coincident_merged = (*m)->coincident_merged;
    fine->auto_size = (*m)->auto_size;
    bs_mesh_destroy(m);
    *m = fine;
  }
  return BS_OK;
}

/* The file exists, is a regular readable file, and its extension is one
 * bs_mesh_read takes (Gmsh silently accepts a missing file: check first). */
static int input_file(const char *path, input_kind *kind, bs_error *err) {
  struct stat st;
  if (stat(path, &st) != 0)
    return bs_error_set(err, BS_EIO, "%s: cannot open the mesh file: %s", path, strerror(errno));
  if (!S_ISREG(st.st_mode)) return bs_error_set(err, BS_EIO, "%s: not a regular file", path);
  FILE *f = fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "%s: cannot read the mesh file: %s", path, strerror(errno));
  fclose(f);
  *kind = classify_input(path);
  if (*kind == IN_UNKNOWN)
    return bs_error_set(err, BS_EINPUT,
                        "%s: unsupported mesh format '.%s' (expected .msh, .geo, .step, .stp, .brep, .iges, .igs, "
                        ".stl, .off, .obj or .ply)",
                        path, file_ext(path));
  return 0;
}

/* Geometry (.geo, STEP, BREP, IGES) opened and meshed in 3-D at size (> 0:
 * Mesh.MeshSizeMin = Max = size, after a check that the tets would fit);
 * *assembly = 1 for a CAD assembly made conformal (cad_assembly.c). */
static int mesh_geometry(const char *path, double size, const bs_mesh_read_opts *opts, int *assembly,
                         bs_error *err) {
  int ierr = 0, rc;
  static const char *const cad[] = {"step", "stp", "iges", "igs", "brep", NULL};
  gmshOpen(path, &ierr);
  if (ierr) return gmsh_fail(err, BS_EGMSH, path, "read the file");
  gmsh_quiet();
  if (ext_is(file_ext(path), cad) && (rc = bs__cad_assembly(path, size, assembly, err))) return rc;
  if (size > 0 && (rc = bs__check_mesh_size(model_volume(), size, opts, path, err))) return rc;
  if (size > 0) {
    gmshOptionSetNumber("Mesh.MeshSizeMin", size, &ierr);
    gmshOptionSetNumber("Mesh.MeshSizeMax", size, &ierr);
  }
  gmshModelMeshGenerate(3, &ierr);
  return ierr ? gmsh_fail(err, BS_EGMSH, path, "mesh the geometry in 3-D") : 0;
}

/* Second-order nodes on the geometry (curved boundary edges), then Gmsh's
 * high-order optimiser, which untangles curved elements the placement
 * folded (Mesh.HighOrderOptimize 2: elastic analogy and optimisation). */
static int second_order(const char *path, bs_error *err) {
  int ierr = 0;
  gmshOptionSetNumber("Mesh.HighOrderOptimize", 2, &ierr);
  gmshModelMeshSetOrder(2, &ierr);
  return ierr ? gmsh_fail(err, BS_EGMSH, path, "place second-order nodes on the geometry") : 0;
}

/* Gmsh's optimisers towards the gate (gmsh_optimize.c); with finer (an
 * assembly at its own size) a mesh still under it is meshed again with
 * smaller elements (bs__cad_assembly_finer) and optimised again. */
static int optimise(const char *path, double gate, int finer, bs_error *err) {
  double got = 0;
  int done = 0, rc = bs__gmsh_optimize_to_gate(path, gate, &got, err);
  if (!rc && finer && got >= 0 && got < gate) rc = bs__cad_assembly_finer(path, &done, err);
  if (!rc && done) rc = bs__gmsh_optimize_to_gate(path, gate, NULL, err);
  return rc;
}

/* The volume inside a closed soup whose triangles are kept as the boundary
 * (see mesh_internal.h), meshed by Gmsh with Mesh.Algorithm3D = algo3d on
 * `threads` threads and optimised towards the gate (not held to it). */
int bs__gmsh_surface_volume(const char *path, const double *pts, int64_t np, const int32_t *tris, int64_t nt,
                            const bs_mesh_read_opts *opts, int algo3d, int threads, bs_mesh **out, bs_error *err) {
  *out = NULL;
  int rc = gmsh_begin(path, err), ierr = 0;
  if (rc) return rc;
  gmshOptionSetNumber("General.NumThreads", threads > 0 ? threads : 1, &ierr);
  gmshOptionSetNumber("Mesh.Algorithm3D", algo3d, &ierr);
  rc = add_discrete_surface(path, pts, np, tris, nt, err);
  if (!rc) rc = surface_to_volume(path, 0.0, opts, err);
  const double gate = bs__mesh_gate(opts);
  if (!rc && gate > 0) rc = optimise(path, gate, 0, err);
  gmsh_quiet();
  if (!rc) rc = model_to_mesh(path, 0, out, err);
  gmsh_end();
  /* A void in the volume shows as boundary faces the soup does not have. */
  if (!rc && (*out)->n_faces != nt)
    rc = bs_error_set(err, BS_EGMSH,
                      "%s: Gmsh's volume mesh has %d boundary triangles where the surface has %lld (it left a void "
                      "inside)",
                      path, (*out)->n_faces, (long long)nt);
  if (rc) bs_mesh_destroy(out);
  return rc;
}

/* A Gmsh mesh under the gate lifted by CGAL's tetrahedral remeshing
 * (bs__mesh_lift at size, <= 0: the mean edge length; its groups kept);
 * BS_OK when the lift passes the gate, else BS_EINPUT with the gate's
 * first message (the budget's when spent). */
static int lift_gmsh(const char *path, bs_mesh **m, double size, double gate, int *refused, bs_error *err) {
  bs_error e2;
  bs_error_clear(&e2);
  int rc = bs__mesh_lift(path, m, size, gate, &e2);
  *refused = rc == BS_EINPUT && !bs__budget_exceeded(&e2);
  if (rc) {
    if (rc != BS_EINPUT || bs__budget_exceeded(&e2)) *err = e2;
    return rc;
  }
  if (bs_mesh_dihedral_gate(*m, gate, path, &e2)) return bs__lift_note(*m, err);
  bs_error_clear(err);
  return BS_OK;
}

/* lift_gmsh, then for a geometry still under the gate its boundary meshed
 * again by CGAL's surface path, groups kept (bs__mesh_cad_by_surface, which
 * declines parts much thinner than the size). */
static int lift_or_from_boundary(const char *path, bs_mesh **m, double size, double gate, int geometry,
                                 const bs_mesh_read_opts *opts, bs_error *err) {
  int refused = 0, rc = lift_gmsh(path, m, size, gate, &refused, err);
  if (rc == BS_EINPUT && geometry && !bs__budget_exceeded(err)) rc = bs__mesh_cad_by_surface(path, m, size, opts, err);
  return rc;
}

static int read_mesh(const char *path, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  if (!out) return bs_error_set(err, BS_EINPUT, "bs_mesh_read: NULL output pointer");
  *out = NULL;
  if (opts && opts->report) memset(opts->report, 0, sizeof *opts->report);
  if (!path || !path[0]) return bs_error_set(err, BS_EINPUT, "bs_mesh_read: no file name given");
  double size = opts ? opts->size : 0.0;
  int refine = opts ? opts->refine : 0;
  if (!isfinite(size)) return bs_error_set(err, BS_EINPUT, "%s: mesh size %g is not finite", path, size);
  if (refine < 0) return bs_error_set(err, BS_EINPUT, "%s: refine = %d (must be >= 0)", path, refine);

  input_kind kind = IN_UNKNOWN;
  int rc = input_file(path, &kind, err);
  if (rc) return rc;

  /* Surfaces Gmsh does not read: CGAL reads and repairs them (surface_repair.c), before Gmsh is locked. */
  double *pts = NULL;
  int32_t *tris = NULL;
  int64_t np = 0, ntri = 0;
  bs_surface_report *rep = opts ? opts->report : NULL;
  if (kind == IN_SOUP && (rc = bs_surface_prepare(path, &pts, &np, &tris, &ntri, opts, rep, err))) return rc;
  /* Gmsh's .msh readers trust the file (msh_check.c lists what fuzzing
   * found in them): only a file that passed the check reaches Gmsh. */
  if (kind == IN_MESH && (rc = bs__msh_check(path, err))) return rc;

  static const char *const script[] = {"geo", NULL};
  if (ext_is(file_ext(path), script) && (rc = bs__geo_check(path, err))) return rc;

  bs_mesh *m = NULL;
  if (kind != IN_MESH && (rc = bs__budget_check(path, "meshing the volume", err))) goto out;
  /* A surface at a size: CGAL's paths. With no size it keeps its own
   * triangles (Gmsh below) when that mesh passes the gate, else it is meshed
   * at a size chosen from it (bs__mesh_surface_auto, after the Gmsh path). */
  const int cgal_soup = kind == IN_SOUP && !(opts && opts->surface_mesher == BS_SURFACE_GMSH);
  if (cgal_soup && size > 0) {
    rc = bs__mesh_closed_surface(path, pts, np, tris, ntri, opts, &m, err);
    goto refine;
  }
  if ((rc = gmsh_begin(path, err))) goto out;
  int ierr = 0, assembly = 0;
  gmshOptionSetString("Geometry.OCCTargetUnit", "M", &ierr);
  switch (kind) {
  case IN_MESH:
    gmshOpen(path, &ierr);
    if (ierr) rc = gmsh_fail(err, BS_EGMSH, path, "read the file");
    break;
  case IN_GEOMETRY:
    rc = mesh_geometry(path, size, opts, &assembly, err);
    break;
  case IN_SOUP:
    rc = add_discrete_surface(path, pts, np, tris, ntri, err);
    if (!rc) rc = surface_to_volume(path, size, opts, err);
    break;
  case IN_UNKNOWN:
    break;
  }
  const double gate = kind == IN_MESH ? 0.0 : bs__mesh_gate(opts);
  if (!rc && gate > 0) rc = optimise(path, gate, assembly && size <= 0, err);
  if (!rc && kind == IN_GEOMETRY && opts && opts->element_order == 2) rc = second_order(path, err);
  gmsh_quiet();
  if (!rc) rc = model_to_mesh(path, opts && opts->merge_coincident, &m, err);
  gmsh_end();
  if (!rc) rc = bs_mesh_dihedral_gate(m, gate, path, err);
  /* Under the gate: lifted, but not a surface's own triangles (no size): too slow on scans; the size below. */
  if (rc == BS_EINPUT && m && gate > 0 && !(cgal_soup && size <= 0))
    rc = lift_or_from_boundary(path, &m, size, gate, kind == IN_GEOMETRY, opts, err);
  if (rc == BS_EINPUT && cgal_soup && gate > 0 && !bs__budget_exceeded(err)) {
    bs_mesh_destroy(&m);
    rc = bs__mesh_surface_auto(path, pts, np, tris, ntri, opts, &m, err);
  }

refine:
  if (!rc && refine > 0) rc = bs__check_refined_count(m->n_tets, refine, opts, path, err);
  if (!rc) rc = refine_read(path, refine, &m, err);
out:
  bs_shim_free(pts);
  bs_shim_free(tris);
  if (rc) bs_mesh_destroy(&m);
  else *out = m;
  return rc;
}

int bs_mesh_read(const char *path, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err) {
  bs__budget_begin(opts);
  const int rc = read_mesh(path, opts, out, err);
  if (rc) bs__budget_note(err);
  bs__budget_end();
  return rc;
}

/* ---- bs_mesh_write_msh -------------------------------------------------- */

/* Tets are grouped into classes of equal 3-D group membership; each class is
 * one discrete volume entity, so that every 3-D physical group is exactly a
 * union of entities (with non-overlapping 3-D groups, one class per
 * material). Groups of lower dimension get one discrete entity each, holding
 * exactly their elements. Nodes are tagged vertex + 1. */
typedef struct tet_classes {
  int n3;          /* number of 3-D groups                       */
  size_t words;    /* 64-bit words per membership signature      */
  uint64_t *sig;   /* n_tets * words                             */
  int32_t *cls;    /* n_tets: class of each tet                  */
  int32_t n_cls;
  int32_t *rep;    /* n_cls: a tet of each class                 */
} tet_classes;

static int sig_equal(const tet_classes *c, int32_t a, int32_t b) {
  return c->words == 0 || memcmp(c->sig + (size_t)a * c->words, c->sig + (size_t)b * c->words,
                                 c->words * sizeof(uint64_t)) == 0;
}

static int build_classes(const bs_mesh *m, tet_classes *c, bs_error *err) {
  memset(c, 0, sizeof *c);
  for (int g = 0; g < m->n_groups; g++) c->n3 += m->groups[g].dim == 3;
  c->words = (size_t)(c->n3 + 63) / 64;
  size_t nt = (size_t)m->n_tets;
  c->sig = calloc(nt * c->words + 1, sizeof *c->sig);
  c->cls = malloc((nt + 1) * sizeof *c->cls);
  c->rep = malloc((nt + 1) * sizeof *c->rep);
  if (!c->sig || !c->cls || !c->rep) return bs_error_set(err, BS_ENOMEM, "out of memory for %zu tets", nt);
  int k = 0;
  for (int g = 0; g < m->n_groups; g++) {
    const bs_group *gr = &m->groups[g];
    if (gr->dim != 3) continue;
    for (int32_t e = 0; e < gr->n_elems; e++) {
      int32_t t = gr->elems[e];
      if (t < 0 || t >= m->n_tets)
        return bs_error_set(err, BS_EINPUT, "group \"%s\" (dim 3, tag %d) refers to tet %d of %d", gr->name, gr->tag,
                            t, m->n_tets);
      c->sig[(size_t)t * c->words + (size_t)k / 64] |= (uint64_t)1 << (k % 64);
    }
    k++;
  }
  for (int32_t t = 0; t < m->n_tets; t++) {
    int32_t found = -1;
    if (t > 0 && sig_equal(c, t, c->rep[c->cls[t - 1]])) found = c->cls[t - 1];
    for (int32_t j = 0; j < c->n_cls && found < 0; j++)
      if (sig_equal(c, t, c->rep[j])) found = j;
    if (found < 0) {
      found = c->n_cls++;
      c->rep[found] = t;
    }
    c->cls[t] = found;
  }
  return BS_OK;
}

static void free_classes(tet_classes *c) {
  free(c->sig);
  free(c->cls);
  free(c->rep);
  memset(c, 0, sizeof *c);
}

/* Builds the Gmsh model of m at positions x (inside a Gmsh session). */
/* The elements of a 0-, 1- or 2-D group as Gmsh element tags (from
 * *next_tag on) and 1-based node tags; BS_EINPUT for a vertex out of range. */
static int group_elements(const bs_mesh *m, const bs_group *gr, size_t *etag, size_t *enodes, size_t *next_tag,
                          const char *path, bs_error *err) {
  const size_t nn = (size_t)gr->dim + 1, n = (size_t)gr->n_elems;
  const size_t per = m->tets10 ? (size_t)simplex2_nodes[gr->dim] : nn;
  for (size_t e = 0; e < n; e++) {
    etag[e] = (*next_tag)++;
    for (size_t k = 0; k < nn; k++) {
      int32_t v = gr->elems[nn * e + k];
      if (v < 0 || v >= m->n_vertices)
        return bs_error_set(err, BS_EINPUT, "%s: group \"%s\" (dim %d, tag %d) refers to vertex %d of %d", path,
                            gr->name, gr->dim, gr->tag, v, m->n_vertices);
      enodes[per * e + k] = (size_t)v + 1;
    }
    /* a quadratic mesh: the midside nodes, Gmsh's order (0,1), (1,2), (2,0) */
    for (size_t k = 0; k + nn < per; k++) {
      const int32_t a = gr->elems[nn * e + k], b = gr->elems[nn * e + (k + 1) % nn];
      const int32_t c = bs_mesh_edge_node(m, a, b);
      if (c < 0)
        return bs_error_set(err, BS_EINPUT, "%s: group \"%s\" (dim %d, tag %d): no tet has the edge (%d, %d)", path,
                            gr->name, gr->dim, gr->tag, a, b);
      enodes[per * e + nn + k] = (size_t)c + 1;
    }
  }
  return 0;
}

/* The tets of class j as element tags (from *next_tag on) and 1-based node
 * tags (a quadratic mesh: 10 per tet in Gmsh's order, VTK's with nodes 8 and
 * 9 swapped); their count. */
static size_t class_elements(const bs_mesh *m, const tet_classes *c, int32_t j, size_t *etag, size_t *enodes,
                             size_t *next_tag) {
  size_t n = 0;
  for (size_t t = 0; t < (size_t)m->n_tets; t++) {
    if (c->cls[t] != j) continue;
    etag[n] = (*next_tag)++;
    if (m->tets10)
      for (int k = 0; k < 10; k++) enodes[10 * n + k] = (size_t)m->tets10[10 * t + (k == 8 ? 9 : k == 9 ? 8 : k)] + 1;
    else
      for (int k = 0; k < 4; k++) enodes[4 * n + k] = (size_t)m->tets[4 * t + k] + 1;
    n++;
  }
  return n;
}

static int build_model(const bs_mesh *m, const double *x, const tet_classes *c, const char *path, bs_error *err) {
  int ierr = 0, rc = BS_OK;
  size_t nv = (size_t)m->n_vertices, nt = (size_t)m->n_tets;
  size_t max_elems = nt;
  for (int g = 0; g < m->n_groups; g++)
    if (m->groups[g].dim < 3 && (size_t)m->groups[g].n_elems > max_elems) max_elems = (size_t)m->groups[g].n_elems;
  size_t *ntag = malloc((nv + 1) * sizeof *ntag);
  size_t *etag = malloc((max_elems + 1) * sizeof *etag);
  const int q = m->tets10 != NULL; /* quadratic: Gmsh's second-order elements */
  size_t *enodes = malloc(((q ? 10 : 4) * max_elems + 1) * sizeof *enodes);
  int *ents = malloc(((size_t)c->n_cls + 1) * sizeof *ents);
  if (!ntag || !etag || !enodes || !ents) {
    rc = bs_error_set(err, BS_ENOMEM, "%s: out of memory for the Gmsh model", path);
    goto done;
  }
  gmshModelAdd("bigstep", &ierr);
  for (int32_t j = 0; j < c->n_cls && !ierr; j++) gmshModelAddDiscreteEntity(3, j + 1, NULL, 0, &ierr);
  if (c->n_cls == 0 && !ierr) gmshModelAddDiscreteEntity(3, 1, NULL, 0, &ierr);
  for (size_t i = 0; i < nv; i++) ntag[i] = i + 1;
  if (!ierr) gmshModelMeshAddNodes(3, 1, ntag, nv, (double *)x, 3 * nv, NULL, 0, &ierr);
  if (ierr) {
    rc = gmsh_fail(err, BS_EGMSH, path, "take the mesh nodes");
    goto done;
  }

  /* Tets, class by class; element tags run over all entities. */
  size_t next_tag = 1;
  for (int32_t j = 0; j < c->n_cls; j++) {
    const size_t n = class_elements(m, c, j, etag, enodes, &next_tag);
    gmshModelMeshAddElementsByType(j + 1, q ? simplex2_type[3] : GMSH_TET, etag, n, enodes, (q ? 10 : 4) * n, &ierr);
    if (ierr) {
      rc = gmsh_fail(err, BS_EGMSH, path, "take the tetrahedra");
      goto done;
    }
  }

  /* Groups. */
  int k3 = 0, next_ent[3] = {1, 1, 1};
  for (int g = 0; g < m->n_groups; g++) {
    const bs_group *gr = &m->groups[g];
    int pdim = gr->dim;
    if (pdim == 3) {
      size_t n = 0;
      for (int32_t j = 0; j < c->n_cls; j++)
        if (c->sig[(size_t)c->rep[j] * c->words + (size_t)k3 / 64] >> (k3 % 64) & 1) ents[n++] = j + 1;
      k3++;
      gmshModelAddPhysicalGroup(3, ents, n, gr->tag, &ierr);
    } else if (pdim >= 0 && pdim < 3) {
      int ent = next_ent[pdim]++;
      size_t nn = q ? (size_t)simplex2_nodes[pdim] : (size_t)pdim + 1, n = (size_t)gr->n_elems;
      if ((rc = group_elements(m, gr, etag, enodes, &next_tag, path, err))) goto done;
      gmshModelAddDiscreteEntity(pdim, ent, NULL, 0, &ierr);
      if (!ierr)
        gmshModelMeshAddElementsByType(ent, q ? simplex2_type[pdim] : simplex_type[pdim], etag, n, enodes, nn * n, &ierr);
      if (!ierr) gmshModelAddPhysicalGroup(pdim, &ent, 1, gr->tag, &ierr);
    } else {
      rc = bs_error_set(err, BS_EINPUT, "%s: group \"%s\" has dimension %d", path, gr->name, pdim);
      goto done;
    }
    if (!ierr && gr->name && gr->name[0]) gmshModelSetPhysicalName(pdim, gr->tag, gr->name, &ierr);
    if (ierr) {
      rc = gmsh_fail(err, BS_EGMSH, path, "take a physical group");
      goto done;
    }
  }
done:
  free(ntag);
  free(etag);
  free(enodes);
  free(ents);
  return rc;
}

int bs_mesh_write_msh(const bs_mesh *m, const double *x, const char *path, bs_error *err) {
  if (!m) return bs_error_set(err, BS_EINPUT, "bs_mesh_write_msh: NULL mesh");
  if (!path || !path[0]) return bs_error_set(err, BS_EINPUT, "bs_mesh_write_msh: no file name given");
  if (strcasecmp(file_ext(path), "msh") != 0)
    return bs_error_set(err, BS_EINPUT, "%s: bs_mesh_write_msh writes .msh files (the name must end in .msh)", path);
  if (!x) x = m->x;
  FILE *f = fopen(path, "wb");
  if (!f) return bs_error_set(err, BS_EIO, "%s: cannot write: %s", path, strerror(errno));
  fclose(f);

  tet_classes c;
  int rc = build_classes(m, &c, err);
  if (rc) {
    free_classes(&c);
    bs_error_prefix(err, "%s", path);
    return rc;
  }
  if ((rc = gmsh_begin(path, err))) {
    free_classes(&c);
    return rc;
  }
  rc = build_model(m, x, &c, path, err);
  if (!rc) {
    int ierr = 0;
    gmshOptionSetNumber("Mesh.MshFileVersion", 4.1, &ierr);
    if (!ierr) gmshOptionSetNumber("Mesh.Binary", 0, &ierr);
    if (!ierr) gmshOptionSetNumber("Mesh.SaveAll", 1, &ierr); /* tets outside any 3-D group too */
    if (!ierr) gmshWrite(path, &ierr);
    if (ierr) rc = gmsh_fail(err, BS_EIO, path, "write the file");
  }
  gmsh_end();
  free_classes(&c);
  return rc;
}
