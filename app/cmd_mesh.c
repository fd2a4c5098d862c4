/* bigstep mesh info|refine|reorder|convert */
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>
#include <strings.h>

#include "app.h"
#include "bs_shim.h"
#include "bs_tet10.h"

static const char *mesh_help =
    "usage: bigstep mesh info FILE [--size H] [--min-dihedral DEG] [--refine N] [--reorder metis|rcm]\n"
    "                         [--merge-coincident] [--close-holes] [--max-hole F]\n"
    "                         [--mesher auto|cgal|remesh] [--time-budget S] [--json]\n"
    "       bigstep mesh refine IN OUT [--size H] [--levels N] [--order 1|2]\n"
    "       bigstep mesh reorder IN OUT [--size H] [--method metis|rcm] [--order 1|2]\n"
    "       bigstep mesh convert IN OUT [--size H] [--refine N] [--order 1|2]\n"
    "\n"
    "FILE/IN: a mesh (.msh v2/v4), a geometry Gmsh meshes (.geo, .step/.stp, .brep),\n"
    "         a closed surface (.stl, .off, .obj, .ply: meshed by CGAL at --size H,\n"
    "         at a size chosen from its bounding box without; with neither size\n"
    "         nor gate, by Gmsh on its own triangles), or a structured box\n"
    "         'box:NX[xNYxNZ][:LX[xLYxLZ]]'.\n"
    "OUT:     .msh (Gmsh 4.1, with groups) or .vtu (ParaView).\n"
    "  --size H       target mesh size in metres for geometry inputs (a closed\n"
    "                 surface given none gets one chosen from its bounding box,\n"
    "                 printed as 'size chosen')\n"
    "  --time-budget S  stop meshing after S seconds with an error naming the\n"
    "                 budget (default 600; 0: none)\n"
    "  --json         info: print the report as one JSON object (quality, gate,\n"
    "                 and for a surface its volume change and Hausdorff distance)\n"
    "  --min-dihedral DEG  quality gate for the meshes bigstep makes (not .msh):\n"
    "                 optimise until every tet's smallest dihedral angle is at\n"
    "                 least DEG degrees, else fail naming the worst region\n"
    "                 (default 10; 0: no gate)\n"
    "  --mesher M     closed surfaces at --size: cgal (CGAL Mesh_3), remesh (CGAL\n"
    "                 remeshes the surface at H, Gmsh HXT meshes the volume)\n"
    "                 or auto (default: remesh when H asks for more\n"
    "                 than about 2e5 tets, else or if it is refused cgal)\n"
    "  --refine N     uniform 1->8 refinements after reading (info, convert)\n"
    "  --levels N     refinements to apply (refine; default 1)\n"
    "  --reorder M    renumber vertices (info): metis or rcm\n"
    "  --method M     reordering method (reorder; default metis)\n"
    "  --order 2      write quadratic tets (refine, reorder, convert): each edge\n"
    "                 gains its midpoint node; .msh: Gmsh's 10-node tets (type 11)\n"
    "                 and 6-node triangles, .vtu: VTK_QUADRATIC_TETRA (default 1)\n"
    "  --merge-coincident  merge nodes of a .msh that share a position under\n"
    "                 distinct tags (reported as a warning otherwise)\n"
    "  --close-holes  close the holes of a surface (.off, .obj, .ply) up to the\n"
    "                 --max-hole size (an open surface is refused otherwise)\n"
    "  --max-hole F   largest hole closed: diameter <= F x the bounding-box\n"
    "                 diagonal (default 0.2)\n"
    "A surface is repaired before it is meshed (duplicates, zero-area triangles,\n"
    "self-intersections); one the repair cannot make clean (non-manifold parts,\n"
    "overlapping facets, a polygon soup) is replaced by its alpha wrap at H; a mesh\n"
    "under the gate is remeshed by CGAL's tetrahedral remeshing, its boundary kept.\n"
    "What was done is printed.\n";

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

typedef struct mesh_args {
  const char *sub;    /* info, refine, reorder or convert */
  int need_out;       /* the subcommand writes OUT */
  const char *pos[2]; /* FILE, or IN and OUT */
  int npos;
  double size, min_dihedral; /* min_dihedral: < 0 none, 0 default */
  double time_budget;        /* seconds; 0: BS_MESH_TIME_BUDGET, < 0: none */
  int refine, levels, have_order, merge, close_holes, mesher, json; /* mesher: BS_SURFACE_* */
  int element_order; /* --order: 1 (linear) or 2 (quadratic tets) */
  double max_hole;
  bs_order order;
} mesh_args;

/* One "--flag value" of the subcommand. 0, or the usage status. */
static int parse_flag(mesh_args *a, const char *flag, const char *val) {
  const char *sub = a->sub;
  if (!strcmp(flag, "--size")) {
    if (bs_parse_double(val, &a->size) || a->size <= 0)
      return bs_app_usage_error("mesh", "--size must be a positive number, got '%s'", val);
  } else if (!strcmp(flag, "--min-dihedral")) {
    if (bs_parse_double(val, &a->min_dihedral) || !(a->min_dihedral >= 0 && a->min_dihedral < 70.5))
      return bs_app_usage_error("mesh", "--min-dihedral must be a number of degrees in [0, 70.5), got '%s'", val);
    if (a->min_dihedral == 0) a->min_dihedral = -1; /* no gate */
  } else if (!strcmp(flag, "--time-budget")) {
    if (bs_parse_double(val, &a->time_budget) || !(a->time_budget >= 0))
      return bs_app_usage_error("mesh", "--time-budget must be a number of seconds >= 0 (0: none), got '%s'", val);
    if (a->time_budget == 0) a->time_budget = -1; /* no budget */
  } else if (!strcmp(flag, "--mesher")) {
    if (bs_mesh_parse_mesher(val, &a->mesher))
      return bs_app_usage_error("mesh", "--mesher must be auto, cgal or remesh, got '%s'", val);
  } else if (!strcmp(flag, "--refine") && strcmp(sub, "refine") && strcmp(sub, "reorder")) {
    if (bs_parse_int(val, 0, 6, &a->refine))
      return bs_app_usage_error("mesh", "--refine must be an integer 0..6, got '%s'", val);
  } else if (!strcmp(flag, "--max-hole")) {
    if (bs_parse_double(val, &a->max_hole) || !(a->max_hole > 0 && a->max_hole <= 1))
      return bs_app_usage_error("mesh", "--max-hole must be a number in (0, 1], got '%s'", val);
  } else if (!strcmp(flag, "--order") && strcmp(sub, "info")) {
    if (bs_parse_int(val, 1, 2, &a->element_order))
      return bs_app_usage_error("mesh", "--order must be 1 or 2, got '%s'", val);
  } else if (!strcmp(flag, "--levels") && !strcmp(sub, "refine")) {
    if (bs_parse_int(val, 1, 6, &a->levels))
      return bs_app_usage_error("mesh", "--levels must be an integer 1..6, got '%s'", val);
  } else if ((!strcmp(flag, "--reorder") && !strcmp(sub, "info")) ||
             (!strcmp(flag, "--method") && !strcmp(sub, "reorder"))) {
    if (parse_order(val, &a->order)) return bs_app_usage_error("mesh", "%s must be metis or rcm, got '%s'", flag, val);
    a->have_order = 1;
  } else {
    return bs_app_usage_error("mesh", "unknown flag '%s' for 'mesh %s'", flag, sub);
  }
  return 0;
}

/* 0, the usage status, or -1 when --help was printed. */
static int parse_args(int argc, char **argv, mesh_args *a) {
  if (argc < 2) return bs_app_usage_error("mesh", "missing subcommand (info, refine, reorder, convert)");
  *a = (mesh_args){.sub = argv[1], .levels = 1, .order = BS_ORDER_METIS, .element_order = 1};
  for (int i = 1; i < argc; i++)
    if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
      fputs(mesh_help, stdout);
      return -1;
    }
  const char *sub = a->sub;
  if (strcmp(sub, "info") == 0) a->need_out = 0;
  else if (!strcmp(sub, "refine") || !strcmp(sub, "reorder") || !strcmp(sub, "convert")) a->need_out = 1;
  else return bs_app_usage_error("mesh", "unknown subcommand '%s' (info, refine, reorder, convert)", sub);
  for (int i = 2; i < argc; i++) {
    const char *arg = argv[i];
    if (strcmp(arg, "--merge-coincident") == 0) {
      a->merge = 1;
    } else if (strcmp(arg, "--close-holes") == 0) {
      a->close_holes = 1;
    } else if (strcmp(arg, "--json") == 0 && !strcmp(sub, "info")) {
      a->json = 1;
    } else if (strncmp(arg, "--", 2) == 0) {
      char fbuf[64];
      const char *flag, *val;
      if (bs_app_flag_value(argc, argv, &i, fbuf, sizeof fbuf, &flag, &val))
        return bs_app_usage_error("mesh", "flag %s needs a value", fbuf);
      int rc = parse_flag(a, flag, val);
      if (rc) return rc;
    } else {
      if (a->npos >= 1 + a->need_out) return bs_app_usage_error("mesh", "unexpected argument '%s'", arg);
      a->pos[a->npos++] = arg;
    }
  }
  if (a->npos < 1 + a->need_out)
    return bs_app_usage_error("mesh", a->need_out ? "'mesh %s' needs IN and OUT" : "'mesh %s' needs FILE", sub);
  return 0;
}

/* The gate in degrees for --min-dihedral's value (< 0 none, 0 default). */
static double bs__gate_degrees(double min_dihedral) {
  return min_dihedral < 0 ? 0.0 : (min_dihedral > 0 ? min_dihedral : BS_MESH_MIN_DIHEDRAL);
}

/* What the surface path chose or replaced: the size, the alpha wrap. */
static void print_wrap_and_size(const bs_mesh *m, const bs_surface_report *r) {
  if (m->auto_size > 0) printf("size chosen %.6g m (no --size given)\n", m->auto_size);
  if (r->lifted)
    printf("tetrahedral remeshing (%d run%s, %.2f s): smallest dihedral angle %.2f -> %.2f degrees\n", r->lifted,
           r->lifted == 1 ? "" : "s", r->lift_seconds, r->lift_dihedral_in, r->lift_dihedral);
  if (r->from_boundary)
    printf("meshed again from its boundary by CGAL (Gmsh's mesh: smallest dihedral angle %.2f degrees): volume change "
           "%+.3f%%\n",
           r->from_boundary_dihedral_in, 100 * r->from_boundary_volume_change);
  if (r->wrapped)
    printf("alpha wrap (%s): alpha %.4g m, offset %.4g m, volume change %+.3f%%, %.2f s\n",
           r->wrapped == 1 ? "the repair could not make the surface clean" : "the meshes of the surface were refused",
           r->wrap_alpha, r->wrap_offset, 100 * r->wrap_volume_change, r->wrap_seconds);
}

/* mesh info: optional reordering, the report and bs_mesh_check. */
static int mesh_info(bs_mesh *m, const mesh_args *a, double t_load, bs_error *err) {
  if (a->have_order) {
    int64_t bw0, p0, bw1, p1;
    bs_mesh_bandwidth(m, &bw0, &p0);
    double t0 = bs_seconds();
    if (bs_mesh_reorder(m, a->order, NULL, err)) {
      fprintf(stderr, "bigstep mesh: %s\n", err->msg);
      return BS_EXIT_FAIL;
    }
    bs_mesh_bandwidth(m, &bw1, &p1);
    printf("reordered (%s) in %.3f s: bandwidth %lld -> %lld, profile %lld -> %lld\n",
           a->order == BS_ORDER_METIS ? "metis" : "rcm", bs_seconds() - t0, (long long)bw0, (long long)bw1,
           (long long)p0, (long long)p1);
  }
  print_info(m, a->pos[0]);
  printf("  loaded in %.3f s\n", t_load);
  if (bs_mesh_check(m, err)) {
    fprintf(stderr, "bigstep mesh: check failed: %s\n", err->msg);
    return BS_EXIT_FAIL;
  }
  printf("  check: ok\n");
  return 0;
}

/* mesh refine|reorder|convert: reorders (reorder), then writes OUT. */
static int mesh_write(bs_mesh *m, const mesh_args *a, bs_error *err) {
  if (!strcmp(a->sub, "reorder")) {
    int64_t bw0, p0, bw1, p1;
    bs_mesh_bandwidth(m, &bw0, &p0);
    if (bs_mesh_reorder(m, a->order, NULL, err)) {
      fprintf(stderr, "bigstep mesh: %s\n", err->msg);
      return BS_EXIT_FAIL;
    }
    bs_mesh_bandwidth(m, &bw1, &p1);
    printf("bandwidth %lld -> %lld, profile %lld -> %lld\n", (long long)bw0, (long long)bw1, (long long)p0,
           (long long)p1);
  }
  if ((a->element_order == 2 && bs_tet10_mesh(m, err)) || bs_app_write_mesh(m, a->pos[1], err)) {
    fprintf(stderr, "bigstep mesh: %s\n", err->msg);
    return BS_EXIT_FAIL;
  }
  if (m->tets10) printf("wrote %s: %d nodes (%d vertices), %d quadratic tets\n", a->pos[1], m->n_vertices, m->n_corners, m->n_tets);
  else printf("wrote %s: %d vertices, %d tets\n", a->pos[1], m->n_vertices, m->n_tets);
  return 0;
}

/* ---- mesh info --json ----------------------------------------------------- */

/* s as a JSON string (quotes, backslashes and control characters escaped). */
static void json_string(const char *s) {
  putchar('"');
  for (; *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') printf("\\%c", c);
    else if (c < 0x20) printf("\\u%04x", c);
    else putchar(c);
  }
  putchar('"');
}

static double soup_volume(const double *p, const int32_t *t, int64_t nt) {
  double v = 0;
  for (int64_t f = 0; f < nt; f++) {
    const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
    v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return fabs(v) / 6.0;
}

/* "holes": what closing the surface's holes did (bs_surface_report), or null
 * when the surface was not repaired. area_fraction: of the clean surface's
 * area; fair_volume_fraction: of its enclosed volume. */
static void json_holes(const bs_surface_report *r) {
  if (!r || r->tris_in == 0) {
    printf("\"holes\": null");
    return;
  }
  printf("\"holes\": {\"found\": %d, \"closed\": %d, \"triangles\": %lld, \"area\": %.6g, "
         "\"area_fraction\": %.6g, \"cap_volume\": %.6g, \"fair_estimated\": %d, \"fair_volume\": %.6g, "
         "\"fair_volume_fraction\": %.6g, \"largest_diameter\": %.6g}",
         r->holes, r->holes_closed, (long long)r->hole_tris, r->hole_area, r->area > 0 ? r->hole_area / r->area : 0.0,
         r->hole_cap_volume, r->holes_fair_estimated, r->hole_fair_volume,
         r->volume > 0 ? r->hole_fair_volume / r->volume : 0.0, r->hole_max_diameter);
}

/* The input surface of path (when it is one the shim reads) against m's
 * boundary: "surface": {volume_in, volume_change, hausdorff, ...} or null.
 * volume_in: the volume the repaired (oriented, closed) surface encloses, as
 * the mesher's volume check uses it (r->volume), else the input's own. The
 * Hausdorff distance is two-sided and sampled every diagonal / 400 (it
 * underestimates by at most about half of that). */
static int json_surface(const bs_mesh *m, const char *path, const bs_surface_report *r, bs_error *err) {
  const char *dot = strrchr(path, '.');
  static const char *const exts[] = {".off", ".stl", ".obj", ".ply"};
  int surface = 0;
  for (size_t k = 0; dot && k < 4; k++) surface |= !strcasecmp(dot, exts[k]);
  if (!surface) return printf("  \"surface\": null,\n"), 0;
  double *x = NULL, d1 = 0, d2 = 0, lo[3], hi[3];
  int32_t *t = NULL;
  int64_t np = 0, nt = 0;
  int rc = bs_shim_read_surface(path, &x, &np, &t, &nt, err);
  if (!rc) {
    bs_bbox(np, x, lo, hi);
    const double diag = bs_bbox_diagonal(lo, hi), spacing = diag / 400.0,
                 v0 = r && r->volume > 0 ? r->volume : soup_volume(x, t, nt);
    rc = bs_shim_surface_distance(m->x, m->n_vertices, m->faces, m->n_faces, x, np, t, nt, spacing, &d1, NULL, err);
    if (!rc) rc = bs_shim_surface_distance(x, np, t, nt, m->x, m->n_vertices, m->faces, m->n_faces, spacing, &d2, NULL, err);
    const double v = bs_mesh_volume(m), d = d1 > d2 ? d1 : d2;
    if (!rc) {
      printf("  \"surface\": {\"volume_in\": %.10g, \"volume_change\": %.6g, \"hausdorff\": %.6g, "
             "\"hausdorff_over_diagonal\": %.6g, \"diagonal\": %.10g, \"sample_spacing\": %.6g, ",
             v0, v0 > 0 ? (v - v0) / v0 : 0.0, d, diag > 0 ? d / diag : 0.0, diag, spacing);
      json_holes(r);
      printf("},\n");
    }
  }
  bs_shim_free(x);
  bs_shim_free(t);
  return rc;
}

/* mesh info --json: one JSON object on stdout. */
static int mesh_json(const bs_mesh *m, const char *path, const bs_surface_report *r, double gate, double t_load,
                     bs_error *err) {
  bs_mesh_quality q;
  bs_mesh_quality_compute(m, NULL, &q);
  printf("{\n  \"file\": ");
  json_string(path);
  printf(",\n  \"vertices\": %d, \"tets\": %d, \"boundary_faces\": %d,\n", m->n_vertices, m->n_tets, m->n_faces);
  printf("  \"volume\": %.10g, \"boundary_volume\": %.10g,\n", bs_mesh_volume(m), bs_mesh_boundary_volume(m));
  printf("  \"quality\": {\"dihedral_min\": %.6g, \"dihedral_max\": %.6g, \"radius_ratio_min\": %.6g, "
         "\"radius_ratio_mean\": %.6g, \"volume_min\": %.6g, \"volume_max\": %.6g, \"inverted\": %d, "
         "\"degenerate\": %d, \"slivers\": %d},\n",
         q.dihedral_min, q.dihedral_max, q.radius_ratio_min, q.radius_ratio_mean, q.vol_min, q.vol_max,
         q.n_inverted, q.n_degenerate, q.n_sliver);
  printf("  \"gate\": %g, \"gate_passed\": %s,\n", gate, gate <= 0 || q.dihedral_min >= gate ? "true" : "false");
  if (m->auto_size > 0) printf("  \"size_chosen\": %.6g,\n", m->auto_size);
  else printf("  \"size_chosen\": null,\n");
  if (r && r->wrapped)
    printf("  \"wrap\": {\"how\": %d, \"alpha\": %.6g, \"offset\": %.6g, \"volume_change\": %.6g, \"seconds\": %.3f},\n",
           r->wrapped, r->wrap_alpha, r->wrap_offset, r->wrap_volume_change, r->wrap_seconds);
  else printf("  \"wrap\": null,\n");
  if (r && r->lifted)
    printf("  \"tet_remesh\": {\"runs\": %d, \"dihedral_before\": %.6g, \"dihedral_after\": %.6g, \"seconds\": %.3f},\n",
           r->lifted, r->lift_dihedral_in, r->lift_dihedral, r->lift_seconds);
  else printf("  \"tet_remesh\": null,\n");
  if (r && r->from_boundary)
    printf("  \"from_boundary\": {\"dihedral_before\": %.6g, \"volume_change\": %.6g},\n", r->from_boundary_dihedral_in,
           r->from_boundary_volume_change);
  else printf("  \"from_boundary\": null,\n");
  int rc = json_surface(m, path, r, err);
  if (!rc) rc = bs_mesh_check(m, err);
  printf("  \"check\": %s,\n  \"seconds\": %.3f\n}\n", rc ? "false" : "true", t_load);
  return rc;
}

int bs_cmd_mesh(int argc, char **argv) {
  /* argv[0] = "mesh" */
  mesh_args a;
  int rc = parse_args(argc, argv, &a);
  if (rc) return rc < 0 ? 0 : rc;
  bs_error err;
  bs_error_clear(&err);
  bs_mesh *m = NULL;
  double t0 = bs_seconds();
  bs_surface_report rep = {0};
  bs_mesh_read_opts o = {.size = a.size, .refine = !strcmp(a.sub, "refine") ? a.levels : a.refine,
                         .merge_coincident = a.merge, .close_holes = a.close_holes, .max_hole = a.max_hole,
                         .min_dihedral = a.min_dihedral, .report = &rep, .surface_mesher = a.mesher,
                         .time_budget = a.time_budget, .element_order = a.element_order};
  if (bs_app_load_mesh_opts(a.pos[0], &o, &m, &err)) {
    if (rep.tris_out > 0 && !a.json) bs_app_print_surface_report(a.pos[0], &rep); /* repaired, then meshing failed */
    fprintf(stderr, "bigstep mesh: %s\n", err.msg);
    return BS_EXIT_FAIL;
  }
  double t_load = bs_seconds() - t0;
  if (a.json) {
    rc = mesh_json(m, a.pos[0], &rep, bs__gate_degrees(a.min_dihedral), t_load, &err);
    bs_mesh_destroy(&m);
    if (rc) fprintf(stderr, "bigstep mesh: %s\n", err.msg);
    return rc ? BS_EXIT_FAIL : 0;
  }
  bs_app_print_surface_report(a.pos[0], &rep);
  print_wrap_and_size(m, &rep);
  rc = !strcmp(a.sub, "info") ? mesh_info(m, &a, t_load, &err) : mesh_write(m, &a, &err);
  bs_mesh_destroy(&m);
  return rc;
}
