#define _POSIX_C_SOURCE 200809L
/* The audit of saved states through the library (runfolder/bs_audit.h):
 * listing a folder's frames or a PVD's files; a clean folder audits to zero;
 * a vertex pushed through a face gives its inverted tets (counted
 * independently) and intersecting pairs; two bodies moved into each other
 * intersect without an inverted tet; a vertex below a scene's plane is
 * counted with its depth; missing, garbled and truncated files give named
 * errors (and count as unreadable in a list). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bs_audit.h"
#include "bs_mesh.h"
#include "bs_scene.h"
#include "bs_sim.h"
#include "bs_vtu_read.h"

static char dir[64];

static void make_dir(void) {
  strcpy(dir, "/tmp/bs_test_audit_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
}

static void remove_dir(void) {
  if (dir[0]) {
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    (void)!system(cmd);
  }
}

TestSuite(audit, .init = make_dir, .fini = remove_dir);

static bs_mesh *box(int n) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  bs_mesh *m = NULL;
  bs_error err;
  cr_assert_eq(bs_mesh_create_box(lo, hi, n, n, n, &m, &err), 0, "%s", err.msg);
  return m;
}

static void write_vtu(const bs_mesh *m, const double *x, const char *path) {
  bs_error err;
  bs_vtu_fields f = {.x = x};
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), 0, "%s", err.msg);
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  cr_assert_not_null(f, "%s", path);
  fputs(text, f);
  fclose(f);
}

static void path_in(char *buf, size_t n, const char *name) { snprintf(buf, n, "%s/%s", dir, name); }

/* The counts of one file, without a scene; the status. */
static int audit_file(const char *path, bs_audit_counts *c, bs_error *err) {
  bs_auditor *a = NULL;
  cr_assert_eq(bs_auditor_create(NULL, &a, err), 0);
  int rc = bs_auditor_frame(a, path, 0.0, c, err);
  bs_auditor_destroy(&a);
  cr_assert_null(a);
  return rc;
}

/* What the callback saw, frame by frame. */
typedef struct seen {
  int n;
  int number[8], status[8];
  bs_audit_counts c[8];
  char msg[8][sizeof ((bs_error *)0)->msg];
} seen;

static void on_frame(void *ctx, const bs_audit_entry *e, int status, const bs_audit_counts *c, const bs_error *err) {
  seen *s = ctx;
  cr_assert_lt(s->n, 8);
  s->number[s->n] = e->number;
  s->status[s->n] = status;
  s->c[s->n] = *c;
  snprintf(s->msg[s->n], sizeof s->msg[0], "%s", status ? err->msg : "");
  s->n++;
}

Test(audit, clean_folder_gives_zero) {
  bs_mesh *m = box(2);
  char sub[128], path[192];
  path_in(sub, sizeof sub, "run");
  cr_assert_eq(mkdir(sub, 0755), 0);
  double *x = malloc(3 * (size_t)m->n_vertices * sizeof(double));
  const int order[3] = {10, 2, 0}; /* written out of order; listed by N */
  for (int k = 0; k < 3; k++) {
    for (int32_t i = 0; i < 3 * m->n_vertices; i++) /* a translation and a small shear */
      x[i] = m->x[i] + 0.1 * order[k] + (i % 3 == 0 ? 0.2 * m->x[i + 1] : 0);
    snprintf(path, sizeof path, "%s/frame_%05d.vtu", sub, order[k]);
    write_vtu(m, x, path);
  }
  snprintf(path, sizeof path, "%s/frame_x.vtu", sub); /* not a frame name */
  write_text(path, "not a frame\n");
  bs_audit_list L;
  bs_error err;
  cr_assert_eq(bs_audit_list_frames(sub, &L, &err), 0, "%s", err.msg);
  cr_assert_eq(L.n, 3);
  cr_assert_eq(L.origin, BS_AUDIT_FRAME_FILES);
  cr_assert_eq(L.entries[0].number, 0);
  cr_assert_eq(L.entries[1].number, 2);
  cr_assert_eq(L.entries[2].number, 10);
  cr_assert_not_null(strstr(L.entries[2].path, "frame_00010.vtu"));
  cr_assert_eq(L.entries[1].has_time, 0);
  seen s = {0};
  bs_audit_totals T;
  cr_assert_eq(bs_audit_run(&L, NULL, on_frame, &s, &T, &err), 0, "%s", err.msg);
  cr_assert_eq(s.n, 3);
  for (int k = 0; k < 3; k++) {
    cr_assert_eq(s.status[k], 0, "%s", s.msg[k]);
    cr_assert_eq(s.c[k].n_tets, m->n_tets);
    cr_assert_eq(s.c[k].inverted, 0);
    cr_assert_eq(s.c[k].self_pairs, 0);
  }
  cr_assert_eq(T.n_frames, 3);
  cr_assert_eq(T.inverted + T.self_pairs + T.penetrating + T.bad_frames + T.unreadable, 0);
  cr_assert_eq(T.max_depth, 0);
  bs_audit_list_free(&L);
  cr_assert_eq(L.n, 0);
  cr_assert_null(L.entries);
  free(x);
  bs_mesh_destroy(&m);
}

/* A box with its vertex at the origin corner pushed through the opposite
 * face: the tets of negative volume (counted here by bs_mesh_tet_volume) are
 * the inverted ones, and the surface now intersects itself. */
Test(audit, inverted_tets_and_pairs) {
  bs_mesh *m = box(2);
  double *x = malloc(3 * (size_t)m->n_vertices * sizeof(double));
  memcpy(x, m->x, 3 * (size_t)m->n_vertices * sizeof(double));
  int32_t corner = -1;
  for (int32_t v = 0; v < m->n_vertices; v++)
    if (x[3 * v] == 0 && x[3 * v + 1] == 0 && x[3 * v + 2] == 0) corner = v;
  cr_assert_geq(corner, 0);
  x[3 * corner] = 1.4;
  x[3 * corner + 1] = 0.45;
  x[3 * corner + 2] = 0.35;
  int32_t want = 0;
  for (int32_t t = 0; t < m->n_tets; t++) want += bs_mesh_tet_volume(m, x, t) <= 0;
  cr_assert_gt(want, 0);
  char path[128];
  path_in(path, sizeof path, "pushed.vtu");
  write_vtu(m, x, path);
  bs_audit_counts c;
  bs_error err;
  cr_assert_eq(audit_file(path, &c, &err), 0, "%s", err.msg);
  cr_assert_eq(c.n_tets, m->n_tets);
  cr_assert_eq(c.inverted, want);
  cr_assert_gt(c.self_pairs, 0);
  cr_assert_eq(c.penetrating, 0);
  free(x);
  bs_mesh_destroy(&m);
}

/* Two unit boxes 2 m apart at rest, moved rigidly into each other (half
 * overlapping): intersecting pairs, no inverted tet. */
Test(audit, two_bodies_intersect_without_inversion) {
  bs_mesh *a = box(2);
  const int32_t nv = a->n_vertices, nt = a->n_tets;
  double *rest = malloc(6 * (size_t)nv * sizeof(double)), *x = malloc(6 * (size_t)nv * sizeof(double));
  int32_t *tets = malloc(8 * (size_t)nt * sizeof(int32_t));
  for (int32_t i = 0; i < 3 * nv; i++) {
    rest[i] = x[i] = a->x[i];
    rest[3 * nv + i] = a->x[i] + (i % 3 == 0 ? 2.0 : 0.0);
    x[3 * nv + i] = a->x[i] + (i % 3 == 0 ? 0.5 : 0.0);
  }
  for (int32_t i = 0; i < 4 * nt; i++) {
    tets[i] = a->tets[i];
    tets[4 * nt + i] = a->tets[i] + nv;
  }
  bs_mesh *m = NULL;
  bs_error err;
  cr_assert_eq(bs_mesh_create(2 * nv, rest, 2 * nt, tets, 0, NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_vertices, 2 * nv);
  char path[128];
  path_in(path, sizeof path, "overlap.vtu");
  write_vtu(m, x, path);
  bs_audit_counts c;
  cr_assert_eq(audit_file(path, &c, &err), 0, "%s", err.msg);
  cr_assert_eq(c.n_tets, 2 * nt);
  cr_assert_eq(c.inverted, 0);
  cr_assert_gt(c.self_pairs, 0);
  /* apart again: clean */
  for (int32_t i = 0; i < 3 * nv; i++) x[3 * nv + i] = rest[3 * nv + i];
  write_vtu(m, x, path);
  cr_assert_eq(audit_file(path, &c, &err), 0, "%s", err.msg);
  cr_assert_eq(c.inverted + c.self_pairs, 0);
  free(rest);
  free(x);
  free(tets);
  bs_mesh_destroy(&m);
  bs_mesh_destroy(&a);
}

/* A box resting on the plane y = 0 of its scene: a vertex moved 0.05 m below
 * it is one penetrating vertex of depth 0.05 m; a state of another mesh is
 * refused. */
Test(audit, vertex_inside_obstacle) {
  char scene[128];
  path_in(scene, sizeof scene, "s.json");
  write_text(scene,
             "{\"time\": {\"fps\": 24, \"frames\": 0},\n"
             " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
             "   \"translate\": [0, 0.5, 0], \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"
             " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": 0, \"collision\": \"constraint\"}]}\n");
  bs_scene *sc = NULL;
  bs_sim *sim = NULL;
  bs_error err;
  cr_assert_eq(bs_scene_load(scene, 0, NULL, &sc, &err), 0, "%s", err.msg);
  cr_assert_eq(bs_sim_create(sc, &sim, &err), 0, "%s", err.msg);
  const bs_mesh *m = sim->mesh;
  double *x = malloc(3 * (size_t)m->n_vertices * sizeof(double));
  memcpy(x, m->x, 3 * (size_t)m->n_vertices * sizeof(double));
  int32_t pick = 0;
  for (int32_t i = 0; i < m->n_vertices; i++)
    if (x[3 * i + 1] < x[3 * pick + 1]) pick = i;
  cr_assert_geq(x[3 * pick + 1], 0.0);
  char sub[128], path[192];
  path_in(sub, sizeof sub, "out");
  cr_assert_eq(mkdir(sub, 0755), 0);
  snprintf(path, sizeof path, "%s/frame_00000.vtu", sub);
  write_vtu(m, x, path);
  x[3 * pick + 1] = -0.05;
  snprintf(path, sizeof path, "%s/frame_00003.vtu", sub);
  write_vtu(m, x, path);

  bs_audit_list L;
  cr_assert_eq(bs_audit_list_frames(sub, &L, &err), 0, "%s", err.msg);
  cr_assert_eq(L.n, 2);
  cr_assert_float_eq(bs_audit_entry_time(&L.entries[1], sim), 3.0 / 24, 1e-15);
  cr_assert_eq(bs_audit_entry_time(&L.entries[1], NULL), 0.0);
  seen s = {0};
  bs_audit_totals T;
  cr_assert_eq(bs_audit_run(&L, sim, on_frame, &s, &T, &err), 0, "%s", err.msg);
  cr_assert_eq(s.n, 2);
  cr_assert_eq(s.status[0], 0, "%s", s.msg[0]);
  cr_assert_eq(s.c[0].penetrating, 0);
  cr_assert_eq(s.c[0].max_depth, 0);
  cr_assert_eq(s.status[1], 0, "%s", s.msg[1]);
  cr_assert_eq(s.number[1], 3);
  cr_assert_eq(s.c[1].penetrating, 1);
  cr_assert_float_eq(s.c[1].max_depth, 0.05, 1e-12);
  cr_assert_eq(s.c[1].inverted, 0);
  cr_assert_eq(T.penetrating, 1);
  cr_assert_float_eq(T.max_depth, 0.05, 1e-12);
  cr_assert_eq(T.bad_frames, 1);
  cr_assert_eq(T.unreadable, 0);
  bs_audit_list_free(&L);

  /* a state of another mesh (a box of 3^3 cells): refused, named */
  bs_mesh *other = box(3);
  snprintf(path, sizeof path, "%s/other.vtu", dir);
  write_vtu(other, NULL, path);
  bs_auditor *a = NULL;
  bs_audit_counts c;
  cr_assert_eq(bs_auditor_create(sim, &a, &err), 0);
  cr_assert_eq(bs_auditor_frame(a, path, 0.0, &c, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "other.vtu"), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "not a state of this scene"), "%s", err.msg);
  bs_auditor_destroy(&a);
  bs_mesh_destroy(&other);
  free(x);
  bs_sim_destroy(&sim);
  bs_scene_destroy(&sc);
}

Test(audit, missing_and_garbled_files_are_named) {
  char path[128];
  bs_audit_counts c;
  bs_error err;
  bs_audit_list L;
  /* missing: as a target and as a frame */
  path_in(path, sizeof path, "nope.vtu");
  cr_assert_eq(bs_audit_list_frames(path, &L, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  cr_assert_eq(L.n, 0);
  cr_assert_eq(audit_file(path, &c, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  /* a text file */
  path_in(path, sizeof path, "readme.vtu");
  write_text(path, "plain text\n");
  cr_assert_eq(audit_file(path, &c, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "not a VTK XML file"), "%s", err.msg);
  /* an empty folder */
  path_in(path, sizeof path, "empty");
  cr_assert_eq(mkdir(path, 0755), 0);
  cr_assert_eq(bs_audit_list_frames(path, &L, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "no frame_*.vtu"), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
}

/* A folder's frames.pvd (no frame files beside it) listing a good and a
 * truncated frame: both listed with their times, the bad one unreadable and
 * named, the good one audited. */
Test(audit, pvd_list_with_a_truncated_frame) {
  bs_mesh *m = box(2);
  char good[128], bad[128], sub[128], pvd[192];
  path_in(good, sizeof good, "frame_00000.vtu");
  path_in(bad, sizeof bad, "frame_00001.vtu");
  write_vtu(m, NULL, good);
  write_vtu(m, NULL, bad);
  struct stat sb;
  cr_assert_eq(stat(bad, &sb), 0);
  cr_assert_eq(truncate(bad, sb.st_size / 2), 0);
  path_in(sub, sizeof sub, "listed");
  cr_assert_eq(mkdir(sub, 0755), 0);
  snprintf(pvd, sizeof pvd, "%s/frames.pvd", sub);
  const double times[2] = {0.0, 0.25};
  const char *files[2] = {"../frame_00000.vtu", "../frame_00001.vtu"};
  bs_error err;
  cr_assert_eq(bs_pvd_write(pvd, 2, times, files, &err), 0, "%s", err.msg);
  bs_audit_list L;
  cr_assert_eq(bs_audit_list_frames(sub, &L, &err), 0, "%s", err.msg);
  cr_assert_eq(L.origin, BS_AUDIT_FOLDER_PVD);
  cr_assert_eq(L.n, 2);
  cr_assert(L.entries[1].has_time);
  cr_assert_eq(L.entries[1].time, 0.25);
  cr_assert_eq(bs_audit_entry_time(&L.entries[1], NULL), 0.25);
  seen s = {0};
  bs_audit_totals T;
  cr_assert_eq(bs_audit_run(&L, NULL, on_frame, &s, &T, &err), 0, "%s", err.msg);
  cr_assert_eq(s.status[0], 0, "%s", s.msg[0]);
  cr_assert_eq(s.c[0].n_tets, m->n_tets);
  cr_assert_neq(s.status[1], 0);
  cr_assert_not_null(strstr(s.msg[1], "frame_00001.vtu"), "%s", s.msg[1]);
  cr_assert_not_null(strstr(s.msg[1], "truncated"), "%s", s.msg[1]);
  cr_assert_eq(s.c[1].n_tets, 0);
  cr_assert_eq(T.n_frames, 2);
  cr_assert_eq(T.unreadable, 1);
  cr_assert_eq(T.bad_frames, 0);
  bs_audit_list_free(&L);
  /* the PVD itself as the target */
  cr_assert_eq(bs_audit_list_frames(pvd, &L, &err), 0, "%s", err.msg);
  cr_assert_eq(L.origin, BS_AUDIT_PVD_FILE);
  cr_assert_eq(L.n, 2);
  bs_audit_list_free(&L);
  /* one file */
  cr_assert_eq(bs_audit_list_frames(bad, &L, &err), 0, "%s", err.msg);
  cr_assert_eq(L.origin, BS_AUDIT_ONE_FILE);
  cr_assert_eq(L.n, 1);
  cr_assert_eq(L.entries[0].number, 1);
  bs_audit_list_free(&L);
  bs_mesh_destroy(&m);
}
