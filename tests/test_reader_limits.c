/* Every reader against hostile input (issue 20): for .msh, .bsls, .off,
 * .stl, .ply, .vtu, .pvd and scene JSON, a corrupted header count, a huge
 * count, a short file, a non-finite number and an out-of-range index each
 * give a clear error that names the file and what is wrong (never a crash or
 * an allocation sized by the bad count); .msh coincident nodes are counted
 * and merged on request; a duplicate node tag is refused with the tag. */
#define _POSIX_C_SOURCE 200809L

#include <criterion/criterion.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_levelset.h"
#include "bs_limits.h"
#include "bs_mesh.h"
#include "bs_scene.h"
#include "bs_shim.h"
#include "bs_vtu_read.h"

static char dir[64];

static void make_dir(void) {
  snprintf(dir, sizeof dir, "/tmp/bs_reader_limits_XXXXXX");
  cr_assert_not_null(mkdtemp(dir));
}

static void remove_dir(void) {
  DIR *d = opendir(dir);
  struct dirent *e;
  char p[512];
  while (d && (e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
      snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
      remove(p);
    }
  if (d) closedir(d);
  rmdir(dir);
}

TestSuite(reader_limits, .init = make_dir, .fini = remove_dir);

/* name in the test folder, with the bytes written to it */
static const char *put(const char *name, const void *bytes, size_t n) {
  static char path[4][256];
  static int k;
  k = (k + 1) % 4;
  snprintf(path[k], sizeof path[k], "%s/%s", dir, name);
  FILE *f = fopen(path[k], "wb");
  cr_assert_not_null(f);
  cr_assert_eq(fwrite(bytes, 1, n, f), n);
  fclose(f);
  return path[k];
}

static const char *put_text(const char *name, const char *text) { return put(name, text, strlen(text)); }

/* rc is the expected error; the message names path and holds both phrases. */
static void expect(int rc, int code, const bs_error *err, const char *path, const char *p1, const char *p2) {
  cr_assert_eq(rc, code, "status %d, expected %d: %s", rc, code, err->msg);
  if (path) cr_assert_not_null(strstr(err->msg, path), "'%s' not in: %s", path, err->msg);
  cr_assert_not_null(strstr(err->msg, p1), "'%s' not in: %s", p1, err->msg);
  if (p2) cr_assert_not_null(strstr(err->msg, p2), "'%s' not in: %s", p2, err->msg);
}

/* ---- .msh ------------------------------------------------------------------ */

static const char msh2_head[] = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

static int msh_code = BS_EINPUT; /* the status msh_fails expects */

static void msh_fails(const char *name, const char *text, const char *p1, const char *p2) {
  const char *path = put_text(name, text);
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, NULL, &m, &err);
  expect(rc, msh_code, &err, path, p1, p2);
  cr_assert_null(m);
}

static void msh2_fails(const char *name, const char *body, const char *p1, const char *p2) {
  char text[4096];
  snprintf(text, sizeof text, "%s%s", msh2_head, body);
  msh_fails(name, text, p1, p2);
}

#define TET_NODES "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"

Test(reader_limits, msh_v2_counts_values_and_indices) {
  msh2_fails("huge.msh", "$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n", "number of nodes = 1000000000000",
             "exceeds bigstep's limit of 100000000");
  msh2_fails("corrupt.msh", "$Nodes\n90000\n1 0 0 0\n$EndNodes\n", "number of nodes = 90000", "cannot fit");
  msh2_fails("short.msh", "$Nodes\n2\n1 0.5 0.5 0.5\n2 1.5 0", "node coordinate", "the file ends");
  msh_code = BS_ENUMERIC;
  msh2_fails("nan.msh", "$Nodes\n4\n1 0 0 0\n2 1 nan 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n", "line 7",
             "node 2 has a non-finite coordinate (1, nan, 0)");
  msh2_fails("inf.msh", "$Nodes\n4\n1 0 0 0\n2 1 1e999 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n", "(1, inf, 0)", NULL);
  msh_code = BS_EINPUT;
  msh2_fails("index.msh", TET_NODES "$Elements\n1\n1 4 2 1 1 1 2 3 99\n$EndElements\n",
             "element 1 refers to node 99, which is not defined", NULL);
  msh2_fails("type.msh", TET_NODES "$Elements\n1\n1 99 2 1 1 1 2 3 4\n$EndElements\n", "element type", "= 99");
  msh2_fails("partitions.msh", TET_NODES "$Elements\n1\n1 4 3 1 1 7 1 2 3 4\n$EndElements\n",
             "element 1 lists 7 partitions: partitioned meshes are not read", NULL);
  msh2_fails("partition.msh", TET_NODES "$Elements\n1\n1 4 4 1 1 1 2 1 2 3 4\n$EndElements\n",
             "element 1 lists 1 partitions", NULL);
  msh2_fails("dup.msh", "$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n2 5 5 5\n$EndNodes\n",
             "node tag 2 is defined twice", NULL);
  msh2_fails("section.msh", TET_NODES "$NodeData\n1\n$EndNodeData\n", "section $NodeData is not read by bigstep",
             NULL);
  msh_fails("version.msh", "$MeshFormat\n4.0 0 8\n$EndMeshFormat\n", "format version 4.0", "4.1 or 2.2");
  msh_fails("empty.msh", "", "the file is empty", NULL);
}

/* A valid 4.1 file whose node header is then corrupted. */
static const char msh4[] = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
                           "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n"
                           "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"
                           "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";

static void msh4_fails(const char *name, const char *from, const char *to, const char *p1, const char *p2) {
  char text[2048];
  const char *at = strstr(msh4, from);
  cr_assert_not_null(at, "%s", from);
  snprintf(text, sizeof text, "%.*s%s%s", (int)(at - msh4), msh4, to, at + strlen(from));
  msh_fails(name, text, p1, p2);
}

Test(reader_limits, msh_v4_counts_tags_and_ranges) {
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_read(put_text("ok4.msh", msh4), NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_tets, 1);
  bs_mesh_destroy(&m);
  msh4_fails("huge4.msh", "$Nodes\n1 4 1 4", "$Nodes\n1 4611686018427387904 1 4", "number of nodes", "exceeds");
  msh4_fails("count4.msh", "$Nodes\n1 4 1 4", "$Nodes\n1 5 1 5", "the blocks hold 4 nodes, the header says 5", NULL);
  msh4_fails("range4.msh", "$Nodes\n1 4 1 4", "$Nodes\n1 4 1 3", "tag range [1, 3] cannot hold 4 nodes", NULL);
  msh4_fails("tag4.msh", "1\n2\n3\n4\n", "1\n2\n3\n40\n", "node tag (in the header's range) = 40", "[1, 4]");
  msh4_fails("block4.msh", "3 1 0 4\n", "3 1 0 400000000\n", "number of nodes in the block = 400000000",
             "exceeds bigstep's limit");
  msh4_fails("entity4.msh", "3 1 0 4\n", "3 7 0 4\n", "block of entity 7 of dimension 3", "does not define");
  msh4_fails("elem4.msh", "1 1 2 3 4\n", "1 1 2 3 5\n", "element 1 refers to node 5", NULL);
  msh4_fails("dim4.msh", "3 1 4 1\n", "3 1 2 1\n", "element type 2 is 2-D, in a block of dimension 3", NULL);
  msh_code = BS_ENUMERIC;
  msh4_fails("nan4.msh", "0 1 0\n0 0 1\n", "0 1 0\n0 0 -inf\n", "node 4 has a non-finite coordinate (0, 0, -inf)", NULL);
  msh_code = BS_EINPUT;
  char cut[2048];
  snprintf(cut, sizeof cut, "%.*s", (int)(strstr(msh4, " 4\n$EndElements") - msh4), msh4);
  msh_fails("short4.msh", cut, "element node tag", "the file ends");
}

Test(reader_limits, msh_coincident_nodes_are_counted_and_merged) {
  char text[1024];
  snprintf(text, sizeof text,
           "%s$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 0 0\n6 0 1 0\n7 0 0 1\n8 1 1 1\n$EndNodes\n"
           "$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 5 6 7 8\n$EndElements\n",
           msh2_head);
  const char *path = put_text("coincident.msh", text);
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_read(path, NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_coincident, 3);
  cr_assert_eq(m->coincident_merged, 0);
  cr_assert_eq(m->n_vertices, 8, "kept: two pieces");
  bs_mesh_destroy(&m);
  bs_mesh_read_opts o = {.merge_coincident = 1, .refine = 1};
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_coincident, 3, "carried through the refinement");
  cr_assert_eq(m->coincident_merged, 1);
  cr_assert_eq(m->n_dropped, 0);
  cr_assert_eq(m->n_tets, 16);
  bs_mesh_destroy(&m);
  o.refine = 0;
  cr_assert_eq(bs_mesh_read(path, &o, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_vertices, 5, "merged: one body of two tets sharing a face");
  cr_assert_eq(m->n_faces, 6);
  bs_mesh_destroy(&m);
  cr_assert_eq(bs_mesh_read("data/geo/cube.geo", NULL, &m, &err), 0, "%s", err.msg);
  cr_assert_eq(m->n_coincident, 0);
  bs_mesh_destroy(&m);
}

/* ---- .bsls ------------------------------------------------------------------ */

static size_t bsls_header(unsigned char *b, int32_t nx, int32_t ny, int32_t nz, double h) {
  memcpy(b, "BSLS1\0\0\0", 8);
  int32_t n[4] = {nx, ny, nz, 0};
  double g[4] = {0, 0, 0, h};
  memcpy(b + 8, n, 16); /* the test machine is little-endian, as the format */
  memcpy(b + 24, g, 32);
  return 56;
}

static void bsls_fails(const char *name, const void *b, size_t n, int code, const char *p1, const char *p2) {
  const char *path = put(name, b, n);
  bs_levelset *ls = NULL;
  bs_error err = {0};
  expect(bs_levelset_grid_load(path, &ls, &err), code, &err, path, p1, p2);
  cr_assert_null(ls);
}

Test(reader_limits, bsls_header_against_the_file) {
  unsigned char b[56 + 8 * 27];
  bsls_header(b, 1290, 1290, 1290, 0.1); /* the 56-byte file */
  bsls_fails("huge.bsls", b, 56, BS_EINPUT, "grid 1290 x 1290 x 1290", "exceeds bigstep's limit of 268435456 nodes");
  bsls_header(b, 100, 100, 100, 0.1); /* under the limit, but the file is short */
  bsls_fails("short.bsls", b, 56 + 8 * 27, BS_EIO, "truncated: 272 bytes", "needs 8000056");
  bsls_header(b, 3, 3, 3, 0.1);
  for (int i = 0; i < 27; i++) memcpy(b + 56 + 8 * i, &(double){1.0}, 8);
  bsls_fails("trailing.bsls", b, 56 + 8 * 27 - 8, BS_EIO, "truncated", NULL);
  bsls_header(b, 3, -5, 3, 0.1);
  bsls_fails("negative.bsls", b, sizeof b, BS_EINPUT, "n[1] = -1", "at least 2 nodes"); /* > INT32_MAX as uint32 */
  bsls_header(b, 3, 3, 3, 0.0 / 0.0);
  bsls_fails("nan_h.bsls", b, sizeof b, BS_EINPUT, "grid spacing h = ", "must be finite");
  bsls_header(b, 3, 3, 3, 0.1);
  memcpy(b + 56 + 8 * 13, &(double){1.0 / 0.0}, 8);
  bsls_fails("inf_value.bsls", b, sizeof b, BS_EINPUT, "node (1, 1, 1) = inf", NULL);
}

/* ---- surfaces: .off, .stl, .ply ---------------------------------------------- */

static void surface_fails(const char *name, const void *b, size_t n, const char *p1, const char *p2) {
  const char *path = put(name, b, n);
  double *pts = NULL;
  int32_t *tris = NULL;
  int64_t np = 0, nt = 0;
  bs_error err = {0};
  expect(bs_shim_read_surface(path, &pts, &np, &tris, &nt, &err), BS_EINPUT, &err, path, p1, p2);
  cr_assert_null(pts);
  cr_assert_null(tris);
}

static void off_fails(const char *name, const char *text, const char *p1, const char *p2) {
  surface_fails(name, text, strlen(text), p1, p2);
}

#define TET_OFF_VERTS "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
#define TET_OFF_FACES "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"

Test(reader_limits, off_read_by_bigstep) {
  const char *path = put_text("ok.off", "OFF\n# comment\n4 4 6\n" TET_OFF_VERTS TET_OFF_FACES);
  double *pts = NULL;
  int32_t *tris = NULL;
  int64_t np = 0, nt = 0;
  bs_error err = {0};
  cr_assert_eq(bs_shim_read_surface(path, &pts, &np, &tris, &nt, &err), 0, "%s", err.msg);
  cr_assert_eq(np, 4);
  cr_assert_eq(nt, 4);
  cr_assert_eq(tris[3 * 3 + 2], 3);
  bs_shim_free(pts);
  bs_shim_free(tris);
  off_fails("huge.off", "OFF\n4 1e30 0\n" TET_OFF_VERTS, "line 2: the face count", "'1e30'");
  off_fails("big.off", "OFF\n4 190000000 0\n" TET_OFF_VERTS TET_OFF_FACES, "190000000 faces cannot fit", NULL);
  off_fails("few.off", "OFF\n4 2 0\n" TET_OFF_VERTS "3 0 1 2\n2 0 1\n", "line 8: polygon 1: its vertex count", "not '2'");
  off_fails("over.off", "OFF 300000000 4 0\n", "the vertex count must be an integer in [0, 1e8]", "'300000000'");
  off_fails("short.off", "OFF\n4 2 6\n0.25 0.25 0.25\n1.25 0.25 0.25\n0.25 1.25 0.25\n0.25 0.25 1.25\n3 0 2 1\n",
            "the file ends before all the faces", NULL);
  off_fails("nan.off", "OFF\n4 4 6\n0 0 0\n1 nan 0\n0 1 0\n0 0 1\n" TET_OFF_FACES, "line 4",
            "a vertex coordinate must be a finite number, not 'nan'");
  off_fails("overflow.off", "OFF\n4 4 6\n0 0 0\n1 1e999 0\n0 1 0\n0 0 1\n" TET_OFF_FACES, "line 4", "'1e999'");
  off_fails("index.off", "OFF\n4 4 6\n" TET_OFF_VERTS "3 0 2 1\n3 0 1 3\n3 0 3 4\n3 1 2 3\n", "line 9",
            "polygon 2: a vertex index must be an integer in [0, vertices - 1], not '4'");
  off_fails("negative.off", "OFF\n4 1 6\n" TET_OFF_VERTS "3 0 2 -1\n", "not '-1'", NULL);
  off_fails("ngon.off", "OFF\n4 1 6\n" TET_OFF_VERTS "9999999999 0 1 2\n", "polygon 0: its vertex count must be an integer in [3, 65536]",
            NULL);
  off_fails("binary.off", "OFF BINARY\n4 4 6\n", "binary OFF is not read", NULL);
  off_fails("dim4.off", "4OFF\n4 4 6\n", "only 3-D OFF files", NULL);
}

Test(reader_limits, stl_and_ply_counts_before_cgal) {
  unsigned char stl[84 + 50] = {0};
  uint32_t n = 1;
  memcpy(stl + 80, &n, 4);
  float v[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  memcpy(stl + 84, v, sizeof v);
  n = 4000000000u; /* corrupted count: neither binary-consistent nor "solid" */
  memcpy(stl + 80, &n, 4);
  surface_fails("count.stl", stl, sizeof stl, "neither an ASCII STL", "134 bytes");
  const char *path = put("gmsh.stl", stl, sizeof stl); /* the same check before Gmsh reads an .stl */
  bs_mesh *m = NULL;
  bs_error err = {0};
  expect(bs_mesh_read(path, NULL, &m, &err), BS_EINPUT, &err, path, "neither an ASCII STL", NULL);
  n = 1;
  memcpy(stl + 80, &n, 4);
  v[7] = 0.0f / 0.0f;
  memcpy(stl + 84, v, sizeof v);
  surface_fails("nan.stl", stl, sizeof stl, "triangle 0 has a non-finite vertex coordinate", NULL);
  static const char ply_head[] = "ply\nformat ascii 1.0\nelement vertex 50000000\nproperty float x\n"
                                 "property float y\nproperty float z\nelement face 1\n"
                                 "property list uchar int vertex_indices\nend_header\n0 0 0\n";
  surface_fails("huge.ply", ply_head, strlen(ply_head), "at least 300000002 bytes", "6 follow it");
  static const char ply_list[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                 "element face 1\nproperty list uint int vertex_indices\nend_header\n";
  surface_fails("list.ply", ply_list, strlen(ply_list), "line 6", "the length type must be an 8- or 16-bit integer");
  static const char ply_int[] = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                "property uint32 z\nend_header\n0 0 0\n";
  surface_fails("int.ply", ply_int, strlen(ply_int), "line 6: vertex coordinate 'z' must be float or double", NULL);
  static const char ply_over[] = "ply\nformat ascii 1.0\nelement face 300000000\nend_header\n";
  surface_fails("over.ply", ply_over, strlen(ply_over), "300000000 face elements exceed bigstep's limit", NULL);
}

/* ---- .vtu, .pvd ---------------------------------------------------------------- */

static const char vtu_fmt[] =
    "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    "<UnstructuredGrid><Piece NumberOfPoints=\"%s\" NumberOfCells=\"1\">\n"
    "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">%s</DataArray></Points>\n"
    "<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">%s</DataArray>\n"
    "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n"
    "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n"
    "</Piece></UnstructuredGrid></VTKFile>\n";

static void vtu_fails(const char *name, const char *np, const char *pts, const char *conn, size_t cut, int code,
                      const char *p1, const char *p2) {
  char text[2048];
  int n = snprintf(text, sizeof text, vtu_fmt, np, pts, conn);
  const char *path = put(name, text, cut ? cut : (size_t)n);
  bs_vtu *v = NULL;
  bs_error err = {0};
  int rc = bs_vtu_read(path, &v, &err);
  if (code == 0) {
    cr_assert_eq(rc, 0, "%s", err.msg);
    cr_assert_eq(v->n_cells, 1);
    bs_vtu_destroy(&v);
    return;
  }
  expect(rc, code, &err, path, p1, p2);
  cr_assert_null(v);
}

Test(reader_limits, vtu_and_pvd) {
  static const char pts[] = "0 0 0 1 0 0 0 1 0 0 0 1";
  vtu_fails("ok.vtu", "4", pts, "0 1 2 3", 0, 0, NULL, NULL);
  vtu_fails("huge.vtu", "99999999", pts, "0 1 2 3", 0, BS_EINPUT, "Points array", "expected 299999997");
  vtu_fails("over.vtu", "4000000000", pts, "0 1 2 3", 0, BS_EINPUT, "NumberOfPoints is '4000000000'",
            "bigstep's limit");
  vtu_fails("count.vtu", "5", pts, "0 1 2 3", 0, BS_EINPUT, "Points array", "expected 15");
  vtu_fails("short.vtu", "4", pts, "0 1 2 3", 200, BS_EINPUT, "XML", NULL);
  vtu_fails("nan.vtu", "4", "0 0 0 1 nan 0 0 1 0 0 0 1", "0 1 2 3", 0, BS_ENUMERIC, "point 1", NULL);
  vtu_fails("index.vtu", "4", pts, "0 1 2 4", 0, BS_EINPUT, "cell 0 vertex 3 is 4, outside [0, 4)", NULL);
  const char *path = put_text("bad.pvd", "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\"><Collection>\n"
                                         "<DataSet timestep=\"nan\" file=\"a.vtu\"/>\n");
  bs_pvd *p = NULL;
  bs_error err = {0};
  int rc = bs_pvd_read(path, &p, &err);
  cr_assert_lt(rc, 0, "a truncated PVD with a NaN time is refused");
  cr_assert_not_null(strstr(err.msg, path), "%s", err.msg);
  cr_assert_null(p);
}

/* ---- scene JSON ------------------------------------------------------------------ */

Test(reader_limits, scene_text) {
  bs_scene *s = NULL;
  bs_error err = {0};
  int rc = bs_scene_parse("{\"time\": {\"fps\": 1e999}}", "inf.json", 0, NULL, &s, &err);
  expect(rc, BS_EINPUT, &err, "inf.json", "fps", NULL);
  rc = bs_scene_parse("{\"time\": {\"frames\": 1e30}}", "huge.json", 0, NULL, &s, &err);
  expect(rc, BS_EINPUT, &err, "huge.json", "frames", NULL);
  rc = bs_scene_parse("{\"time\": {\"fps\": 24", "short.json", 0, NULL, &s, &err);
  expect(rc, BS_EINPUT, &err, "short.json", "malformed JSON", NULL);
  char deep[4100];
  for (int i = 0; i < 2048; i++) deep[i] = '[', deep[4095 - i] = ']';
  deep[4096] = '\0';
  rc = bs_scene_parse(deep, "deep.json", 0, NULL, &s, &err);
  expect(rc, BS_EINPUT, &err, "deep.json", "JSON", NULL);
  cr_assert_null(s);
  char *big = malloc(BS_MAX_SCENE_BYTES + 16);
  cr_assert_not_null(big);
  memset(big, ' ', BS_MAX_SCENE_BYTES + 15);
  big[0] = '{', big[BS_MAX_SCENE_BYTES + 14] = '}';
  const char *path = put("big.json", big, BS_MAX_SCENE_BYTES + 15);
  free(big);
  expect(bs_scene_load(path, 0, NULL, &s, &err), BS_EINPUT, &err, path, "exceed bigstep's limit", NULL);
  expect(bs_scene_load(dir, 0, NULL, &s, &err), BS_EIO, &err, dir, "cannot read scene", NULL);
  static const char nul[] = "{\"time\": {}}\0{\"bodies\": 7}";
  path = put("nul.json", nul, sizeof nul - 1);
  expect(bs_scene_load(path, 0, NULL, &s, &err), BS_EINPUT, &err, path, "a NUL byte at offset 12", NULL);
}
