/* CAD assemblies (bs_mesh_read on STEP files of several solids; mesh/
 * cad_assembly.c): two touching boxes written by Gmsh, and Gmsh's demo
 * assembly as1-tu-203.stp (data/corpus/gmsh, extracted from Debian's gmsh-doc
 * by setup.sh: a plate, two L-brackets with three nut-bolt pairs each and a
 * rod with two nuts, 18 solids that touch). The mesh must be conformal (no
 * coincident nodes; the parts' tets one connected mesh), carry one named 3-D
 * group per part, hold the parts' OpenCASCADE volume within 1%, and pass
 * the default quality gate (every tet's smallest dihedral angle at least
 * 10 degrees, none inverted). */
#define _GNU_SOURCE

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <gmshc.h>

#include "bs_mesh.h"

#define ASSEMBLY BS_SOURCE_DIR "/data/corpus/gmsh/as1-tu-203.stp"

/* Connected components of the tets (two tets are joined by a shared vertex). */
static int tet_components(const bs_mesh *m) {
  int32_t *parent = malloc((size_t)m->n_vertices * sizeof *parent);
  cr_assert_not_null(parent);
  for (int32_t v = 0; v < m->n_vertices; v++) parent[v] = v;
  for (int32_t t = 0; t < m->n_tets; t++)
    for (int k = 1; k < 4; k++) {
      int32_t a = m->tets[4 * t], b = m->tets[4 * t + k];
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      while (parent[b] != b) b = parent[b] = parent[parent[b]];
      if (a != b) parent[a] = b;
    }
  int n = 0;
  for (int32_t v = 0; v < m->n_vertices; v++) n += parent[v] == v;
  free(parent);
  return n;
}

/* The 3-D groups: distinct names, every tet in exactly one. Returns their count. */
static int check_part_groups(const bs_mesh *m) {
  int n3 = 0;
  int64_t in_groups = 0;
  for (int g = 0; g < m->n_groups; g++) {
    const bs_group *a = &m->groups[g];
    if (a->dim != 3) continue;
    n3++;
    in_groups += a->n_elems;
    cr_expect(a->n_elems > 0, "part \"%s\" has no tets", a->name);
    for (int h = g + 1; h < m->n_groups; h++)
      if (m->groups[h].dim == 3) cr_expect(strcmp(a->name, m->groups[h].name), "two parts named \"%s\"", a->name);
  }
  cr_expect_eq(in_groups, m->n_tets, "%lld tets in groups, %d tets", (long long)in_groups, m->n_tets);
  for (int32_t t = 0; t < m->n_tets; t++) cr_assert(m->material[t] > 0, "tet %d is in no part", t);
  return n3;
}

/* The sum of OpenCASCADE's volumes of the solids of a CAD file, in m^3. */
static double occ_volume(const char *path) {
  int ierr = 0, *dt = NULL;
  size_t n = 0;
  double total = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshOptionSetString("Geometry.OCCTargetUnit", "M", &ierr);
  gmshOpen(path, &ierr);
  cr_assert_eq(ierr, 0, "Gmsh could not open %s", path);
  gmshModelGetEntities(&dt, &n, 3, &ierr);
  for (size_t i = 0; i + 1 < n; i += 2) {
    double v = 0;
    gmshModelOccGetMass(3, dt[i + 1], &v, &ierr);
    total += v;
  }
  gmshFree(dt);
  gmshFinalize(&ierr);
  return total;
}

/* Two unit boxes that share the face x = 1, written by Gmsh as BREP (which
 * names no solid; OpenCASCADE's STEP writer would name them after itself). */
static void write_two_boxes(const char *path) {
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshModelAdd("boxes", &ierr);
  gmshModelOccAddBox(0, 0, 0, 1, 1, 1, 1, &ierr);
  gmshModelOccAddBox(1, 0, 0, 1, 1, 1, 2, &ierr);
  gmshModelOccSynchronize(&ierr);
  gmshWrite(path, &ierr);
  cr_assert_eq(ierr, 0, "Gmsh could not write %s", path);
  gmshFinalize(&ierr);
}

/* path (a mkstemps template ending in ".brep") becomes a new file holding
 * the two boxes of write_two_boxes. */
static void two_boxes_file(char *path) {
  int fd = mkstemps(path, 5);
  cr_assert(fd >= 0);
  close(fd);
  write_two_boxes(path);
}

Test(cad_assembly, touching_boxes_conformal) {
  char path[] = "/tmp/bs_test_cad_XXXXXX.brep";
  two_boxes_file(path);
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, &(bs_mesh_read_opts){.size = 0.25}, &m, &err);
  double v = occ_volume(path);
  remove(path);
  cr_assert_eq(rc, BS_OK, "%s", err.msg);
  cr_expect_eq(m->n_coincident, 0, "the shared face's nodes are shared");
  cr_expect_eq(tet_components(m), 1, "the two boxes are one mesh");
  cr_expect_eq(check_part_groups(m), 2);
  const bs_group *a = bs_mesh_group_by_tag(m, 3, 1), *b = bs_mesh_group_by_tag(m, 3, 2);
  cr_assert(a && b);
  cr_expect(strcmp(a->name, "part_1") == 0 && strcmp(b->name, "part_2") == 0, "names \"%s\", \"%s\"", a->name,
            b->name);
  cr_expect_float_eq(v, 2.0, 1e-9);
  cr_expect_float_eq(bs_mesh_volume(m), 2.0, 1e-9);
  cr_expect_float_eq(bs_mesh_boundary_volume(m), 2.0, 1e-9, "the shared face is inside the mesh");
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* At their own size the two boxes pass the gate at Gmsh's sizes, so they
 * are not meshed again finer: elements of at most 1/40 of the diagonal
 * (0.061 m) would give some 10^5 tets. */
Test(cad_assembly, touching_boxes_own_size_kept) {
  char path[] = "/tmp/bs_test_cad_XXXXXX.brep";
  two_boxes_file(path);
  bs_mesh *m = NULL;
  bs_error err = {0};
  int rc = bs_mesh_read(path, NULL, &m, &err);
  remove(path);
  cr_assert_eq(rc, BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL, "smallest dihedral angle %.3f degrees", q.dihedral_min);
  cr_expect_lt(m->n_tets, 5000, "%d tets: meshed again finer though Gmsh's own sizes passed", m->n_tets);
  cr_expect_eq(check_part_groups(m), 2);
  cr_expect_float_eq(bs_mesh_volume(m), 2.0, 1e-9);
  bs_mesh_destroy(&m);
}

/* The demo assembly meshed through the default gate (opts NULL: the file's
 * own size; or opts with .size): conformal, the named parts, the CAD volume
 * within 1%, every tet's smallest dihedral angle at least the gate. */
static void check_demo_assembly(const bs_mesh_read_opts *opts) {
  cr_assert_eq(access(ASSEMBLY, R_OK), 0, "%s is missing: run `bash setup.sh build`", ASSEMBLY);
  bs_mesh *m = NULL;
  bs_error err = {0};
  cr_assert_eq(bs_mesh_read(ASSEMBLY, opts, &m, &err), BS_OK, "%s", err.msg);
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  cr_expect_geq(q.dihedral_min, BS_MESH_MIN_DIHEDRAL, "smallest dihedral angle %.3f degrees", q.dihedral_min);
  cr_expect_eq(q.n_inverted, 0, "%d inverted tets", q.n_inverted);
  cr_expect_gt(q.vol_min, 0.0);
  cr_expect_eq(m->n_coincident, 0);
  cr_expect_eq(check_part_groups(m), 18);
  static const char *const names[] = {"NUT::1/nut", "NUT::2/nut", "rod", "plate",
                                      "L-BRACKET-ASSEMBLY::1/l-bracket-assembly/L-BRACKET/l-bracket",
                                      "L-BRACKET-ASSEMBLY::2/l-bracket-assembly/NUT-BOLT-ASSEMBLY::3/nut-bolt-assembly/BOLT/bolt"};
  for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
    const bs_group *g = bs_mesh_group(m, names[i]);
    cr_expect(g && g->dim == 3, "no part \"%s\"", names[i]);
  }
  int n = tet_components(m);
  cr_expect_eq(n, 1, "%d connected pieces: the 18 parts touch and form one mesh", n);
  double v = occ_volume(ASSEMBLY);
  cr_expect(fabs(bs_mesh_volume(m) - v) <= 0.01 * v, "tets %.9g m^3, OpenCASCADE %.9g m^3", bs_mesh_volume(m), v);
  cr_expect_eq(bs_mesh_check(m, &err), BS_OK, "%s", err.msg);
  bs_mesh_destroy(&m);
}

/* At the file's own size (curvature sizing; Gmsh's own sizes leave it at
 * about 6 degrees, so it is meshed again with elements at most 1/40 of the
 * diagonal: mesh/cad_assembly.c), through the default gate of 10 degrees. */
Test(cad_assembly, step_demo_assembly_at_default_size) { check_demo_assembly(NULL); }

/* At the size a user would ask, diagonal / 25 (10.5 mm; the plate is 3 mm
 * thick), uniform: through the default gate too. */
Test(cad_assembly, step_demo_assembly_at_diagonal_over_25) {
  check_demo_assembly(&(bs_mesh_read_opts){.size = 0.2637 / 25});
}
