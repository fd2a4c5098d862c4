#define _POSIX_C_SOURCE 200809L
/* The VTU reader (round trip bit for bit, malformed files named) and
 * `bigstep check` (clean states, inverted and self-intersecting states,
 * folders and PVD lists, unreadable files, usage errors). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bs_mesh.h"
#include "bs_vtu_read.h"
#include "cli_util.h"
#include "sim_util.h"

static char dir[64];

static void make_dir(void) {
  strcpy(dir, "/tmp/bs_test_check_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
}

static void remove_dir(void) {
  if (dir[0]) {
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    (void)!system(cmd);
  }
}

TestSuite(check, .init = make_dir, .fini = remove_dir);

static bs_mesh *box(int n) {
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  bs_mesh *m = NULL;
  bs_error err;
  cr_assert_eq(bs_mesh_create_box(lo, hi, n, n, n, &m, &err), 0, "%s", err.msg);
  return m;
}

static void write_vtu(const bs_mesh *m, const double *x, const double *v, const char *path) {
  bs_error err;
  bs_vtu_fields f = {.x = x, .velocity = v, .cell_detF = NULL};
  cr_assert_eq(bs_mesh_write_vtu(m, &f, path, &err), 0, "%s", err.msg);
}

/* Positions of a box with its vertex at the origin corner pushed through the
 * opposite face (x = 1) to (1.4, 0.45, 0.35); returns it (malloc'ed) and the
 * number of tets of negative volume there, counted independently. */
static double *pushed_through(const bs_mesh *m, int32_t *n_inv) {
  double *x = malloc(3 * (size_t)m->n_vertices * sizeof(double));
  memcpy(x, m->x, 3 * (size_t)m->n_vertices * sizeof(double));
  int32_t corner = -1;
  for (int32_t v = 0; v < m->n_vertices; v++)
    if (x[3 * v] == 0 && x[3 * v + 1] == 0 && x[3 * v + 2] == 0) corner = v;
  cr_assert_geq(corner, 0);
  x[3 * corner] = 1.4;
  x[3 * corner + 1] = 0.45;
  x[3 * corner + 2] = 0.35;
  *n_inv = 0;
  for (int32_t t = 0; t < m->n_tets; t++) *n_inv += bs_mesh_tet_volume(m, x, t) <= 0;
  return x;
}

static int run(const char *args, char **out) {
  char cmd[2048];
  snprintf(cmd, sizeof cmd, "%s check %s", BS_BIGSTEP_EXE, args);
  return bs_test_run(cmd, out);
}

/* Parses the per-frame line of file `name`: frame, tets, inverted, pairs. */
static int frame_line(const char *out, const char *name, int *frame, int *tets, int *inv, long long *pairs) {
  const char *p = out;
  while ((p = strstr(p, name))) {
    const char *ls = p;
    while (ls > out && ls[-1] != '\n') ls--;
    char time[32], pen[32], depth[32];
    if (sscanf(ls, "%d %31s %d %d %lld %31s %31s", frame, time, tets, inv, pairs, pen, depth) == 7) return 0;
    p += strlen(name);
  }
  return -1;
}

static int count_lines_with(const char *out, const char *s) {
  int n = 0;
  for (const char *p = out; (p = strstr(p, s)); p += strlen(s)) n++;
  return n;
}

/* ---- reader ---------------------------------------------------------- */

Test(check, reader_round_trip_bit_exact) {
  bs_mesh *m = box(3);
  const size_t n3 = 3 * (size_t)m->n_vertices;
  double *x = malloc(n3 * sizeof(double)), *vel = malloc(n3 * sizeof(double));
  for (size_t i = 0; i < n3; i++) {
    x[i] = m->x[i] + 1e-3 * sin(1.7 * (double)i) + 1e-17 * (double)(i % 7); /* awkward bits */
    vel[i] = cos(0.3 * (double)i);
  }
  char path[128];
  snprintf(path, sizeof path, "%s/rt.vtu", dir);
  write_vtu(m, x, vel, path);

  bs_vtu *v = NULL;
  bs_error err;
  cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
  cr_assert_eq(v->n_points, m->n_vertices);
  cr_assert_eq(v->n_cells, m->n_tets);
  cr_assert_eq(memcmp(v->x, x, n3 * sizeof(double)), 0, "points differ");
  cr_assert_eq(memcmp(v->tets, m->tets, 4 * (size_t)m->n_tets * sizeof(int32_t)), 0, "connectivity differs");
  cr_assert_not_null(v->displacement);
  for (size_t i = 0; i < n3; i++) {
    double d = x[i] - m->x[i];
    cr_assert_eq(memcmp(&v->displacement[i], &d, sizeof d), 0, "displacement %zu differs", i);
  }
  const bs_vtu_array *va = bs_vtu_point_array(v, "velocity");
  cr_assert_not_null(va);
  cr_assert_eq(va->ncomp, 3);
  cr_assert_eq(memcmp(va->data, vel, n3 * sizeof(double)), 0, "velocity differs");
  const bs_vtu_array *mat = bs_vtu_cell_array(v, "material"), *inv = bs_vtu_cell_array(v, "inverted");
  cr_assert_not_null(mat);
  cr_assert_str_eq(mat->type, "Int32");
  cr_assert_not_null(inv);
  cr_assert_str_eq(inv->type, "UInt8");
  cr_assert_not_null(bs_vtu_cell_array(v, "detF"));
  cr_assert_null(bs_vtu_cell_array(v, "nope"));
  for (int32_t t = 0; t < m->n_tets; t++) {
    cr_assert_eq(mat->data[t], (double)m->material[t]);
    cr_assert_eq(inv->data[t], 0.0);
  }
  /* rest = x - displacement: within one rounding of the mesh's rest positions */
  double *rest = malloc(n3 * sizeof(double));
  cr_assert_eq(bs_vtu_rest(v, path, rest, &err), 0, "%s", err.msg);
  for (size_t i = 0; i < n3; i++) cr_assert_leq(fabs(rest[i] - m->x[i]), 1e-15, "rest %zu", i);
  free(rest);
  bs_vtu_destroy(&v);
  cr_assert_null(v);
  bs_vtu_destroy(&v); /* NULL is fine */
  free(x);
  free(vel);
  bs_mesh_destroy(&m);
}

Test(check, pvd_round_trip) {
  char path[128];
  snprintf(path, sizeof path, "%s/c.pvd", dir);
  const double times[3] = {0, 1.0 / 24, 0.1};
  const char *files[3] = {"frame_00000.vtu", "sub/a&b.vtu", "/abs/x.vtu"};
  bs_error err;
  cr_assert_eq(bs_pvd_write(path, 3, times, files, &err), 0, "%s", err.msg);
  bs_pvd *p = NULL;
  cr_assert_eq(bs_pvd_read(path, &p, &err), 0, "%s", err.msg);
  cr_assert_eq(p->n, 3);
  char want[256];
  snprintf(want, sizeof want, "%s/frame_00000.vtu", dir);
  cr_assert_str_eq(p->files[0], want);
  snprintf(want, sizeof want, "%s/sub/a&b.vtu", dir);
  cr_assert_str_eq(p->files[1], want);
  cr_assert_str_eq(p->files[2], "/abs/x.vtu");
  for (int i = 0; i < 3; i++) cr_assert_eq(p->times[i], times[i]);
  bs_pvd_destroy(&p);
  cr_assert_null(p);
}

static void write_text(const char *path, const char *s) {
  FILE *fp = fopen(path, "w");
  cr_assert_not_null(fp);
  fputs(s, fp);
  fclose(fp);
}

static long file_size(const char *path) {
  struct stat sb;
  cr_assert_eq(stat(path, &sb), 0);
  return (long)sb.st_size;
}

Test(check, reader_errors_name_the_file) {
  bs_mesh *m = box(1);
  char good[128], path[160];
  snprintf(good, sizeof good, "%s/good.vtu", dir);
  write_vtu(m, NULL, NULL, good);
  long size = file_size(good);
  bs_vtu *v = NULL;
  bs_error err;

  /* missing */
  snprintf(path, sizeof path, "%s/missing.vtu", dir);
  cr_assert_eq(bs_vtu_read(path, &v, &err), BS_EIO);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);

  /* cut inside the raw data, and cut just before the closing tags */
  const long cuts[4] = {size / 2, size - 20, size - 5, 300};
  for (int i = 0; i < 4; i++) {
    snprintf(path, sizeof path, "%s/cut%d.vtu", dir, i);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, path);
    cr_assert_eq(system(cmd), 0);
    cr_assert_eq(truncate(path, cuts[i]), 0);
    cr_assert_eq(bs_vtu_read(path, &v, &err), BS_EINPUT, "cut at %ld", cuts[i]);
    cr_assert_null(v);
    cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
    cr_assert(strstr(err.msg, "truncated") || strstr(err.msg, "malformed"), "%s", err.msg);
  }

  /* not a VTU: text, a PVD */
  snprintf(path, sizeof path, "%s/notes.vtu", dir);
  write_text(path, "hello, world\n");
  cr_assert_eq(bs_vtu_read(path, &v, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  cr_assert_not_null(strstr(err.msg, "not a VTK XML file"), "%s", err.msg);

  snprintf(path, sizeof path, "%s/c.pvd", dir);
  const double t0 = 0;
  const char *f0 = "good.vtu";
  cr_assert_eq(bs_pvd_write(path, 1, &t0, &f0, &err), 0);
  cr_assert_eq(bs_vtu_read(path, &v, &err), BS_EINPUT);
  cr_assert_not_null(strstr(err.msg, "Collection"), "%s", err.msg);

  snprintf(path, sizeof path, "%s/ascii.vtu", dir);
  write_text(path,
             "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\">\n<UnstructuredGrid>\n"
             "<Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><Points>\n"
             "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0</DataArray>\n"
             "</Points></Piece></UnstructuredGrid></VTKFile>\n");
  /* inline ascii arrays are read (tests/test_vtu_read.c has the formats) */
  cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
  cr_assert_eq(v->n_points, 1);
  cr_assert_eq(v->n_cells, 0);
  bs_vtu_destroy(&v);

  /* a cell that is not a tetrahedron: patch the last byte of 'types' */
  snprintf(path, sizeof path, "%s/wedge.vtu", dir);
  char cmd[512];
  snprintf(cmd, sizeof cmd, "cp '%s' '%s'", good, path);
  cr_assert_eq(system(cmd), 0);
  FILE *fp = fopen(path, "r+b");
  cr_assert_not_null(fp);
  /* the file ends with: types bytes, "\n  </AppendedData>\n</VTKFile>\n" (30 bytes) */
  cr_assert_eq(fseek(fp, size - 30 - 1, SEEK_SET), 0);
  cr_assert_eq(fgetc(fp), 10);
  cr_assert_eq(fseek(fp, size - 30 - 1, SEEK_SET), 0);
  fputc(13, fp);
  fclose(fp);
  cr_assert_eq(bs_vtu_read(path, &v, &err), BS_EINPUT);
  char want[64];
  snprintf(want, sizeof want, "cell %d has VTK type 13", m->n_tets - 1);
  cr_assert_not_null(strstr(err.msg, want), "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* ---- bigstep check ---------------------------------------------------- */

Test(check, clean_box_exit_0) {
  bs_mesh *m = box(2);
  char path[128];
  snprintf(path, sizeof path, "%s/clean.vtu", dir);
  write_vtu(m, NULL, NULL, path);
  char *out;
  int rc = run(path, &out);
  cr_assert_eq(rc, 0, "%s", out);
  int frame, tets, inv;
  long long pairs;
  cr_assert_eq(frame_line(out, "clean.vtu", &frame, &tets, &inv, &pairs), 0, "%s", out);
  cr_assert_eq(tets, m->n_tets);
  cr_assert_eq(inv, 0);
  cr_assert_eq(pairs, 0);
  cr_assert_not_null(strstr(out, "total: 1 frames, inverted 0, self-intersecting pairs 0"), "%s", out);
  cr_assert_not_null(strstr(out, "clean"), "%s", out);
  free(out);

  /* a moved but valid state (a rigid translation plus a small shear) is clean too */
  double *x = malloc(3 * (size_t)m->n_vertices * sizeof(double));
  for (int32_t i = 0; i < m->n_vertices; i++) {
    x[3 * i] = m->x[3 * i] + 0.2 * m->x[3 * i + 1] + 5;
    x[3 * i + 1] = m->x[3 * i + 1] - 2;
    x[3 * i + 2] = m->x[3 * i + 2];
  }
  write_vtu(m, x, NULL, path);
  rc = run(path, &out);
  cr_assert_eq(rc, 0, "%s", out);
  free(out);
  free(x);
  bs_mesh_destroy(&m);
}

Test(check, vertex_through_face_found) {
  bs_mesh *m = box(2);
  int32_t want_inv;
  double *x = pushed_through(m, &want_inv);
  cr_assert_gt(want_inv, 0);
  char path[128];
  snprintf(path, sizeof path, "%s/pushed.vtu", dir);
  write_vtu(m, x, NULL, path);
  char *out;
  int rc = run(path, &out);
  cr_assert_eq(rc, 1, "%s", out);
  int frame, tets, inv;
  long long pairs;
  cr_assert_eq(frame_line(out, "pushed.vtu", &frame, &tets, &inv, &pairs), 0, "%s", out);
  cr_assert_eq(inv, want_inv, "%s", out);
  cr_assert_gt(pairs, 0, "%s", out);
  cr_assert_not_null(strstr(out, "problems in 1 frame"), "%s", out);
  free(out);

  /* --quiet: the total line only, same status */
  char args[256];
  snprintf(args, sizeof args, "'%s' --quiet", path);
  rc = run(args, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_eq(count_lines_with(out, "pushed.vtu"), 0, "%s", out);
  cr_assert_not_null(strstr(out, "total: 1 frames"), "%s", out);
  free(out);
  free(x);
  bs_mesh_destroy(&m);
}

Test(check, folder_three_frames_and_pvd) {
  bs_mesh *m = box(2);
  int32_t want_inv;
  double *bad = pushed_through(m, &want_inv);
  char sub[128], path[192];
  snprintf(sub, sizeof sub, "%s/run", dir);
  cr_assert_eq(mkdir(sub, 0755), 0);
  /* frames 0 and 2 clean, frame 1 bad; written out of order */
  const int order[3] = {2, 0, 1};
  for (int k = 0; k < 3; k++) {
    snprintf(path, sizeof path, "%s/frame_%05d.vtu", sub, order[k]);
    write_vtu(m, order[k] == 1 ? bad : NULL, NULL, path);
  }
  snprintf(path, sizeof path, "%s/notes.txt", sub);
  write_text(path, "not a frame\n");
  char *out;
  int rc = run(sub, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_eq(count_lines_with(out, "frame_0000"), 3, "%s", out);
  const char *p0 = strstr(out, "frame_00000.vtu"), *p1 = strstr(out, "frame_00001.vtu"),
             *p2 = strstr(out, "frame_00002.vtu");
  cr_assert(p0 && p1 && p2 && p0 < p1 && p1 < p2, "frames out of order:\n%s", out);
  int frame, tets, inv;
  long long pairs;
  cr_assert_eq(frame_line(out, "frame_00001.vtu", &frame, &tets, &inv, &pairs), 0);
  cr_assert_eq(frame, 1);
  cr_assert_eq(inv, want_inv);
  cr_assert_gt(pairs, 0);
  cr_assert_eq(frame_line(out, "frame_00002.vtu", &frame, &tets, &inv, &pairs), 0);
  cr_assert_eq(frame, 2);
  cr_assert_eq(inv, 0);
  cr_assert_eq(pairs, 0);
  cr_assert_not_null(strstr(out, "total: 3 frames"), "%s", out);
  cr_assert_not_null(strstr(out, "problems in 1 frame"), "%s", out);
  free(out);

  /* a PVD listing only the clean frames: two lines, with their times, exit 0 */
  snprintf(path, sizeof path, "%s/clean.pvd", sub);
  const double times[2] = {0.0, 0.125};
  const char *files[2] = {"frame_00000.vtu", "frame_00002.vtu"};
  bs_error err;
  cr_assert_eq(bs_pvd_write(path, 2, times, files, &err), 0, "%s", err.msg);
  rc = run(path, &out);
  cr_assert_eq(rc, 0, "%s", out);
  cr_assert_eq(count_lines_with(out, "frame_0000"), 2, "%s", out);
  cr_assert_not_null(strstr(out, "0.125"), "%s", out);
  free(out);

  /* a folder with no frames but a frames.pvd: the files it lists */
  char sub2[128];
  snprintf(sub2, sizeof sub2, "%s/listed", dir);
  cr_assert_eq(mkdir(sub2, 0755), 0);
  snprintf(path, sizeof path, "%s/frames.pvd", sub2);
  const char *files2[2] = {"../run/frame_00000.vtu", "../run/frame_00001.vtu"};
  cr_assert_eq(bs_pvd_write(path, 2, times, files2, &err), 0, "%s", err.msg);
  rc = run(sub2, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_eq(count_lines_with(out, "frame_0000"), 2, "%s", out);
  free(out);
  free(bad);
  bs_mesh_destroy(&m);
}

Test(check, unreadable_inputs_exit_1_naming_the_file) {
  bs_mesh *m = box(2);
  char sub[128], path[192], *out;
  snprintf(sub, sizeof sub, "%s/run", dir);
  cr_assert_eq(mkdir(sub, 0755), 0);
  for (int k = 0; k < 2; k++) {
    snprintf(path, sizeof path, "%s/frame_%05d.vtu", sub, k);
    write_vtu(m, NULL, NULL, path);
  }
  /* frame 1 truncated: named, the other frame still audited */
  cr_assert_eq(truncate(path, file_size(path) / 2), 0);
  int rc = run(sub, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, path), "%s", out);
  cr_assert_not_null(strstr(out, "truncated"), "%s", out);
  cr_assert_eq(count_lines_with(out, "frame_00000.vtu"), 1, "%s", out);
  cr_assert_not_null(strstr(out, "unreadable 1"), "%s", out);
  free(out);
  rc = run(path, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, path), "%s", out);
  free(out);

  /* missing file, missing folder, empty folder, a text file */
  snprintf(path, sizeof path, "%s/nope.vtu", dir);
  rc = run(path, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, path), "%s", out);
  free(out);
  snprintf(path, sizeof path, "%s/nowhere", dir);
  rc = run(path, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, path), "%s", out);
  free(out);
  snprintf(path, sizeof path, "%s/empty", dir);
  cr_assert_eq(mkdir(path, 0755), 0);
  rc = run(path, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, "no frame_*.vtu"), "%s", out);
  free(out);
  snprintf(path, sizeof path, "%s/readme.txt", dir);
  write_text(path, "plain text\n");
  rc = run(path, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, path), "%s", out);
  cr_assert_not_null(strstr(out, "not a VTK XML file"), "%s", out);
  free(out);
  bs_mesh_destroy(&m);
}

Test(check, usage_errors_exit_2) {
  char *out;
  cr_assert_eq(run("", &out), 2, "%s", out);
  cr_assert_not_null(strstr(out, "missing"), "%s", out);
  free(out);
  cr_assert_eq(run("a b", &out), 2, "%s", out);
  cr_assert_not_null(strstr(out, "'b'"), "%s", out);
  free(out);
  cr_assert_eq(run("a --bogus", &out), 2, "%s", out);
  cr_assert_not_null(strstr(out, "--bogus"), "%s", out);
  free(out);
  cr_assert_eq(run("a --scene", &out), 2, "%s", out);
  cr_assert_not_null(strstr(out, "--scene"), "%s", out);
  free(out);
  cr_assert_eq(run("--help", &out), 0, "%s", out);
  cr_assert_not_null(strstr(out, "usage: bigstep check"), "%s", out);
  free(out);
}

/* --scene: a box resting on a constraint plane y = 0; frame 0 as `bigstep run`
 * writes it, frame 1 the same with one vertex 0.05 m below the plane. */
Test(check, scene_obstacles_penetration) {
  char scene[160], path[256], *out;
  snprintf(scene, sizeof scene, "%s/s.json", dir);
  char text[768];
  snprintf(text, sizeof text,
           "{\"time\": {\"fps\": 24, \"frames\": 0},\n"
           " \"bodies\": [{\"mesh\": \"box\", \"box\": {\"cells\": [2, 2, 2], \"size\": [1, 1, 1]},\n"
           "   \"translate\": [0, 0.5, 0], \"material\": {\"youngs\": 1e5, \"poisson\": 0.3, \"density\": 1000}}],\n"
           " \"obstacles\": [{\"shape\": \"plane\", \"normal\": [0, 1, 0], \"offset\": 0, \"collision\": \"constraint\"}],\n"
           " \"output\": {\"dir\": \"%s/out\", \"vtu_every\": 1}}\n",
           dir);
  write_text(scene, text);
  {
    /* the run folder through the library, as `bigstep run` writes it */
    sim_rec rec;
    bs_run_totals T;
    char outdir0[160];
    snprintf(outdir0, sizeof outdir0, "%s/out", dir);
    sim_run_scene(scene, NULL, outdir0, &rec, &T, 0, NULL);
    cr_assert_eq(T.failed, 0);
  }
  int rc;

  /* frame 0: clean against the scene's obstacle */
  char outdir[160], args[512];
  snprintf(outdir, sizeof outdir, "%s/out", dir);
  snprintf(args, sizeof args, "'%s' --scene '%s'", outdir, scene);
  rc = run(args, &out);
  cr_assert_eq(rc, 0, "%s", out);
  cr_assert_not_null(strstr(out, "1 obstacle of the scene"), "%s", out);
  cr_assert_not_null(strstr(out, "penetrating 0, max depth 0 m"), "%s", out);
  free(out);

  /* frame 1: a lowest vertex (the one of largest x) moved to 0.05 m below y = 0 */
  snprintf(path, sizeof path, "%s/frame_00000.vtu", outdir);
  bs_vtu *v = NULL;
  bs_error err;
  cr_assert_eq(bs_vtu_read(path, &v, &err), 0, "%s", err.msg);
  double *rest = malloc(3 * (size_t)v->n_points * sizeof(double));
  cr_assert_eq(bs_vtu_rest(v, path, rest, &err), 0, "%s", err.msg);
  bs_mesh *m = NULL;
  cr_assert_eq(bs_mesh_create(v->n_points, rest, v->n_cells, v->tets, 0, NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_vertices, v->n_points);
  double *x = malloc(3 * (size_t)m->n_vertices * sizeof(double));
  memcpy(x, v->x, 3 * (size_t)m->n_vertices * sizeof(double));
  int32_t pick = -1;
  for (int32_t i = 0; i < m->n_vertices; i++)
    if (pick < 0 || x[3 * i + 1] < x[3 * pick + 1] || (x[3 * i + 1] == x[3 * pick + 1] && x[3 * i] > x[3 * pick]))
      pick = i;
  cr_assert_geq(x[3 * pick + 1], 0.0, "the box starts below the plane");
  x[3 * pick + 1] = -0.05;
  snprintf(path, sizeof path, "%s/frame_00001.vtu", outdir);
  write_vtu(m, x, NULL, path);
  rc = run(args, &out);
  cr_assert_eq(rc, 1, "%s", out);
  int frame, tets, inv;
  long long pairs;
  cr_assert_eq(frame_line(out, "frame_00001.vtu", &frame, &tets, &inv, &pairs), 0, "%s", out);
  const char *line = strstr(out, "frame_00001.vtu");
  while (line > out && line[-1] != '\n') line--;
  char time[32], pen[32], depth[32];
  cr_assert_eq(sscanf(line, "%d %31s %d %d %lld %31s %31s", &frame, time, &tets, &inv, &pairs, pen, depth), 7);
  cr_assert_str_eq(pen, "1", "%s", out);
  cr_assert_float_eq(strtod(depth, NULL), 0.05, 1e-9, "%s", out);
  cr_assert_not_null(strstr(out, "penetrating 1, max depth 0.05 m"), "%s", out);
  free(out);

  /* a scene whose mesh is not the one of the states */
  snprintf(args, sizeof args, "'%s' --scene data/scenes/cube_pulse.json", outdir);
  rc = run(args, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, "not a state of this scene"), "%s", out);
  cr_assert_not_null(strstr(out, "frame_00000.vtu"), "%s", out);
  free(out);
  /* a scene that does not load: named */
  snprintf(args, sizeof args, "'%s' --scene '%s/none.json'", outdir, dir);
  rc = run(args, &out);
  cr_assert_eq(rc, 1, "%s", out);
  cr_assert_not_null(strstr(out, "none.json"), "%s", out);
  free(out);
  free(x);
  free(rest);
  bs_mesh_destroy(&m);
  bs_vtu_destroy(&v);
}
