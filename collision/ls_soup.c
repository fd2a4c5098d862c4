/* ls_soup.c — the triangle surfaces level sets are sampled from
 * (bs_ls_sample.h): read, copied from a mesh, checked closed. */
#include <stdlib.h>
#include <string.h>

#include "bs_ls_sample.h"
#include "bs_shim.h"

int bs_ls_soup_is_file(const char *path) {
  const char *dot = strrchr(path, '.');
  if (!dot || strchr(dot, '/')) return 0;
  static const char *const ext[] = {".off", ".obj", ".ply", ".stl", ".OFF", ".OBJ", ".PLY", ".STL", NULL};
  for (int i = 0; ext[i]; i++)
    if (!strcmp(dot, ext[i])) return 1;
  return 0;
}

void bs_ls_soup_free(bs_ls_soup *s) {
  if (!s) return;
  free(s->x);
  free(s->tris);
  memset(s, 0, sizeof *s);
}

/* A soup of np points and nt triangles, uninitialised. */
static int soup_alloc(int64_t np, int64_t nt, const char *name, bs_ls_soup *s, bs_error *err) {
  s->n_points = np;
  s->n_tris = nt;
  s->x = malloc(sizeof(double) * 3 * (size_t)(np > 0 ? np : 1));
  s->tris = malloc(sizeof(int32_t) * 3 * (size_t)(nt > 0 ? nt : 1));
  if (s->x && s->tris) return BS_OK;
  bs_ls_soup_free(s);
  return bs_error_set(err, BS_ENOMEM, "out of memory reading '%s'", name);
}

int bs_ls_soup_read(const char *path, bs_ls_soup *out, bs_error *err) {
  memset(out, 0, sizeof *out);
  double *pts = NULL;
  int32_t *tris = NULL;
  int64_t np = 0, nt = 0;
  int rc = bs_shim_read_surface(path, &pts, &np, &tris, &nt, err);
  if (!rc && !(rc = soup_alloc(np, nt, path, out, err))) {
    memcpy(out->x, pts, sizeof(double) * 3 * (size_t)np);
    memcpy(out->tris, tris, sizeof(int32_t) * 3 * (size_t)nt);
  }
  bs_shim_free(pts);
  bs_shim_free(tris);
  return rc;
}

int bs_ls_soup_from_mesh(const bs_mesh *m, bs_ls_soup *out, bs_error *err) {
  memset(out, 0, sizeof *out);
  int rc = soup_alloc(m->n_vertices, m->n_faces, "the mesh", out, err);
  if (rc) return rc;
  memcpy(out->x, m->x, sizeof(double) * 3 * (size_t)m->n_vertices);
  memcpy(out->tris, m->faces, sizeof(int32_t) * 3 * (size_t)m->n_faces);
  return BS_OK;
}

/* A point and its index, sorted by coordinates (then index). */
typedef struct keyed_point {
  double p[3];
  int64_t i;
} keyed_point;

static int cmp_keyed(const void *a, const void *b) {
  const keyed_point *u = a, *v = b;
  for (int k = 0; k < 3; k++)
    if (u->p[k] != v->p[k]) return u->p[k] < v->p[k] ? -1 : 1;
  return (u->i > v->i) - (u->i < v->i);
}

static int cmp_edge(const void *a, const void *b) {
  const int64_t *e = a, *f = b;
  if (e[0] != f[0]) return e[0] < f[0] ? -1 : 1;
  return (e[1] > f[1]) - (e[1] < f[1]);
}

/* rep[i]: the first of the points with the coordinates of point i. */
static void merge_points(const double *pts, int64_t np, keyed_point *kp, int64_t *rep) {
  for (int64_t i = 0; i < np; i++) {
    memcpy(kp[i].p, pts + 3 * i, 3 * sizeof(double));
    kp[i].i = i;
  }
  qsort(kp, (size_t)np, sizeof *kp, cmp_keyed);
  for (int64_t i = 0; i < np; i++) {
    int same = i > 0 && !memcmp(kp[i].p, kp[i - 1].p, 3 * sizeof(double));
    rep[kp[i].i] = same ? rep[kp[i - 1].i] : kp[i].i;
  }
}

/* The sorted undirected edges (2 per edge, merged endpoints; collapsed
 * edges left out); returns their count. */
static int64_t sorted_edges(const bs_ls_soup *s, const int64_t *rep, int64_t *edges) {
  int64_t ne = 0;
  for (int64_t t = 0; t < s->n_tris; t++)
    for (int k = 0; k < 3; k++) {
      int64_t a = rep[s->tris[3 * t + k]], b = rep[s->tris[3 * t + (k + 1) % 3]];
      if (a == b) continue; /* a collapsed edge bounds nothing */
      edges[2 * ne] = a < b ? a : b;
      edges[2 * ne + 1] = a < b ? b : a;
      ne++;
    }
  qsort(edges, (size_t)ne, 2 * sizeof(int64_t), cmp_edge);
  return ne;
}

/* The edges used an odd number of times, and the first of them. */
static int64_t odd_edges(const int64_t *edges, int64_t ne, int64_t first[2]) {
  int64_t n_odd = 0;
  for (int64_t i = 0; i < ne;) {
    int64_t j = i;
    while (j < ne && edges[2 * j] == edges[2 * i] && edges[2 * j + 1] == edges[2 * i + 1]) j++;
    if ((j - i) % 2 && !n_odd++) {
      first[0] = edges[2 * i];
      first[1] = edges[2 * i + 1];
    }
    i = j;
  }
  return n_odd;
}

int bs_ls_soup_check_closed(const bs_ls_soup *s, const char *name, bs_error *err) {
  const int64_t np = s->n_points, nt = s->n_tris;
  keyed_point *kp = malloc(sizeof *kp * (size_t)(np > 0 ? np : 1));
  int64_t *rep = malloc(sizeof(int64_t) * (size_t)(np > 0 ? np : 1));
  int64_t *edges = malloc(sizeof(int64_t) * 2 * 3 * (size_t)(nt > 0 ? nt : 1));
  int st = 0;
  if (!kp || !rep || !edges) {
    st = bs_error_set(err, BS_ENOMEM, "out of memory checking the surface of '%s'", name);
  } else {
    merge_points(s->x, np, kp, rep);
    int64_t first[2] = {0, 0};
    int64_t n_odd = odd_edges(edges, sorted_edges(s, rep, edges), first);
    const double *p = s->x + 3 * first[0], *q = s->x + 3 * first[1];
    if (n_odd)
      st = bs_error_set(err, BS_EINPUT,
                        "'%s': the surface is not closed: %lld edges bound an odd number of triangles, e.g. the "
                        "edge (%g, %g, %g)-(%g, %g, %g); a signed distance needs a closed surface",
                        name, (long long)n_odd, p[0], p[1], p[2], q[0], q[1], q[2]);
  }
  free(kp);
  free(rep);
  free(edges);
  return st;
}
