/* bigstep mesh info|refine|reorder|convert */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"

static const char *mesh_help =
    "usage: bigstep mesh info FILE [--size H] [--refine N] [--reorder metis|rcm]\n"
    "       bigstep mesh refine IN OUT [--size H] [--levels N]\n"
    "       bigstep mesh reorder IN OUT [--size H] [--method metis|rcm]\n"
    "       bigstep mesh convert IN OUT [--size H] [--refine N]\n"
    "\n"
    "FILE/IN: a mesh or geometry Gmsh reads (.msh v2/v4, .geo, .step/.stp, .brep,\n"
    "         .stl, .off), or a structured box 'box:NX[xNYxNZ][:LX[xLYxLZ]]'.\n"
    "OUT:     .msh (Gmsh 4.1, with groups) or .vtu (ParaView).\n"
    "  --size H       target mesh size in metres for geometry inputs\n"
    "  --refine N     uniform 1->8 refinements after reading (info, convert)\n"
    "  --levels N     refinements to apply (refine; default 1)\n"
    "  --reorder M    renumber vertices (info): metis or rcm\n"
    "  --method M     reordering method (reorder; default metis)\n";

static int parse_order(const char *s, bs_order *o) {
  if (strcmp(s, "metis") == 0) *o = BS_ORDER_METIS;
  else if (strcmp(s, "rcm") == 0) *o = BS_ORDER_RCM;
  else return -1;
  return 0;
}

static void print_info(const bs_mesh *m, const char *name) {
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  int64_t bw, prof;
  bs_mesh_bandwidth(m, &bw, &prof);
  printf("mesh %s\n", name);
  printf("  vertices %d (dofs %lld), tets %d, boundary faces %d, boundary edges %d\n", m->n_vertices,
         3LL * m->n_vertices, m->n_tets, m->n_faces, m->n_edges);
  if (m->n_dropped) printf("  dropped %d vertices that no tet uses\n", m->n_dropped);
  printf("  volume %.9g m^3 (from the boundary: %.9g)\n", bs_mesh_volume(m), bs_mesh_boundary_volume(m));
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (int32_t v = 0; v < m->n_vertices; v++)
    for (int k = 0; k < 3; k++) {
      double c = m->x[3 * v + k];
      if (c < lo[k]) lo[k] = c;
      if (c > hi[k]) hi[k] = c;
    }
  printf("  bounding box [%g, %g] x [%g, %g] x [%g, %g]\n", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
  printf("  groups %d\n", m->n_groups);
  for (int g = 0; g < m->n_groups; g++) {
    const bs_group *gr = &m->groups[g];
    static const char *what[4] = {"points", "lines", "triangles", "tets"};
    printf("    (%d, %d) %-16s %9d %-9s %9d vertices\n", gr->dim, gr->tag, gr->name[0] ? gr->name : "(unnamed)",
           gr->n_elems, what[gr->dim], gr->n_vertices);
  }
  printf("  quality\n");
  printf("    volume range        [%.4g, %.4g] m^3\n", q.vol_min, q.vol_max);
  printf("    dihedral angles     [%.3f, %.3f] degrees\n", q.dihedral_min, q.dihedral_max);
  printf("    radius ratio        min %.4f, mean %.4f (1 = regular)\n", q.radius_ratio_min, q.radius_ratio_mean);
  printf("    inverted %d, near-degenerate %d, slivers (dihedral < 1 deg) %d\n", q.n_inverted, q.n_degenerate,
         q.n_sliver);
  printf("  vertex graph bandwidth %lld, profile %lld\n", (long long)bw, (long long)prof);
  if (q.n_sliver || q.n_degenerate || q.n_inverted)
    fprintf(stderr, "bigstep mesh: warning: %s has %d sliver, %d near-degenerate and %d inverted tets\n", name,
            q.n_sliver, q.n_degenerate, q.n_inverted);
}

int bs_cmd_mesh(int argc, char **argv) {
  /* argv[0] = "mesh" */
  if (argc < 2) return bs_app_usage_error("mesh", "missing subcommand (info, refine, reorder, convert)");
  const char *sub = argv[1];
  for (int i = 1; i < argc; i++)
    if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
      fputs(mesh_help, stdout);
      return 0;
    }
  int need_out;
  if (strcmp(sub, "info") == 0) need_out = 0;
  else if (!strcmp(sub, "refine") || !strcmp(sub, "reorder") || !strcmp(sub, "convert")) need_out = 1;
  else return bs_app_usage_error("mesh", "unknown subcommand '%s' (info, refine, reorder, convert)", sub);

  const char *pos[2] = {NULL, NULL};
  int npos = 0;
  double size = 0;
  int refine = 0, levels = 1, have_order = 0;
  bs_order order = BS_ORDER_METIS;
  for (int i = 2; i < argc; i++) {
    const char *a = argv[i];
    if (strncmp(a, "--", 2) == 0) {
      const char *val = NULL;
      char flag[64];
      const char *eq = strchr(a, '=');
      if (eq) {
        snprintf(flag, sizeof flag, "%.*s", (int)(eq - a), a);
        val = eq + 1;
      } else {
        snprintf(flag, sizeof flag, "%s", a);
        if (i + 1 < argc) val = argv[++i];
      }
      if (!val) return bs_app_usage_error("mesh", "flag %s needs a value", flag);
      if (!strcmp(flag, "--size")) {
        if (bs_app_parse_double(val, &size) || size <= 0)
          return bs_app_usage_error("mesh", "--size must be a positive number, got '%s'", val);
      } else if (!strcmp(flag, "--refine") && strcmp(sub, "refine") && strcmp(sub, "reorder")) {
        if (bs_app_parse_int(val, 0, 6, &refine))
          return bs_app_usage_error("mesh", "--refine must be an integer 0..6, got '%s'", val);
      } else if (!strcmp(flag, "--levels") && !strcmp(sub, "refine")) {
        if (bs_app_parse_int(val, 1, 6, &levels))
          return bs_app_usage_error("mesh", "--levels must be an integer 1..6, got '%s'", val);
      } else if ((!strcmp(flag, "--reorder") && !strcmp(sub, "info")) ||
                 (!strcmp(flag, "--method") && !strcmp(sub, "reorder"))) {
        if (parse_order(val, &order)) return bs_app_usage_error("mesh", "%s must be metis or rcm, got '%s'", flag, val);
        have_order = 1;
      } else {
        return bs_app_usage_error("mesh", "unknown flag '%s' for 'mesh %s'", flag, sub);
      }
    } else {
      if (npos >= 1 + need_out) return bs_app_usage_error("mesh", "unexpected argument '%s'", a);
      pos[npos++] = a;
    }
  }
  if (npos < 1 + need_out)
    return bs_app_usage_error("mesh", need_out ? "'mesh %s' needs IN and OUT" : "'mesh %s' needs FILE", sub);

  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  if (!strcmp(sub, "refine")) refine = levels;
  if (bs_app_load_mesh(pos[0], size, refine, &m, &err)) {
    fprintf(stderr, "bigstep mesh: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  double t_load = bs_seconds() - t0;
  int rc = 0;
  if (!strcmp(sub, "info")) {
    if (have_order) {
      int64_t bw0, p0, bw1, p1;
      bs_mesh_bandwidth(m, &bw0, &p0);
      t0 = bs_seconds();
      if (bs_mesh_reorder(m, order, NULL, &err)) {
        fprintf(stderr, "bigstep mesh: %s\n", err.msg);
        rc = BS_EXIT_FAIL;
      } else {
        bs_mesh_bandwidth(m, &bw1, &p1);
        printf("reordered (%s) in %.3f s: bandwidth %lld -> %lld, profile %lld -> %lld\n",
               order == BS_ORDER_METIS ? "metis" : "rcm", bs_seconds() - t0, (long long)bw0, (long long)bw1,
               (long long)p0, (long long)p1);
      }
    }
    if (!rc) {
      print_info(m, pos[0]);
      printf("  loaded in %.3f s\n", t_load);
      if (bs_mesh_check(m, &err)) {
        fprintf(stderr, "bigstep mesh: check failed: %s\n", err.msg);
        rc = BS_EXIT_FAIL;
      } else {
        printf("  check: ok\n");
      }
    }
  } else {
    if (!strcmp(sub, "reorder")) {
      int64_t bw0, p0, bw1, p1;
      bs_mesh_bandwidth(m, &bw0, &p0);
      if (bs_mesh_reorder(m, order, NULL, &err)) {
        fprintf(stderr, "bigstep mesh: %s\n", err.msg);
        bs_mesh_destroy(&m);
        return BS_EXIT_FAIL;
      }
      bs_mesh_bandwidth(m, &bw1, &p1);
      printf("bandwidth %lld -> %lld, profile %lld -> %lld\n", (long long)bw0, (long long)bw1, (long long)p0,
             (long long)p1);
    }
    if (bs_app_write_mesh(m, pos[1], &err)) {
      fprintf(stderr, "bigstep mesh: %s\n", err.msg);
      rc = BS_EXIT_FAIL;
    } else {
      printf("wrote %s: %d vertices, %d tets\n", pos[1], m->n_vertices, m->n_tets);
    }
  }
  bs_mesh_destroy(&m);
  return rc;
}
