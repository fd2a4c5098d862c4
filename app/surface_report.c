/* surface_report.c — what bs_surface_prepare did to a surface, printed. */
#include <stdio.h>

#include "app.h"
#include "bs_shim.h"

static const char *fix_name(int fix) {
  switch (fix) {
  case 1: return "removed by autorefinement";
  case 2: return "removed locally (smoothing and re-filling)";
  case 3: return "removed locally, then by autorefinement";
  default: return "none";
  }
}

void bs_app_print_surface_report(const char *spec, const bs_surface_report *r) {
  if (!r || r->tris_in == 0) return;
  printf("surface repair of %s: %lld -> %lld triangles, %lld -> %lld points\n", spec, (long long)r->tris_in,
         (long long)r->tris_out, (long long)r->points_in, (long long)r->points_out);
  printf("  duplicates: %lld points merged, %lld triangles dropped; degenerate triangles removed %lld; points split "
         "where not manifold %lld\n",
         (long long)r->duplicate_points, (long long)r->duplicate_tris, (long long)r->degenerate_tris,
         (long long)r->split_points);
  printf("  holes: %d found, %d closed", r->holes, r->holes_closed);
  if (r->holes_closed) {
    printf(" with %lld triangles (largest: diameter %.4g m = %.3g of the bounding-box diagonal, perimeter %.4g m)",
           (long long)r->hole_tris, r->hole_max_diameter,
           r->bbox_diagonal > 0 ? r->hole_max_diameter / r->bbox_diagonal : 0.0, r->hole_max_perimeter);
    printf("\n  the fills: area %.4g m^2 (%.3g%% of the surface), %.4g m^3 beyond flat caps over the holes; faired "
           "(%d of %d), they would enclose %.4g m^3 more (%.3g%% of the enclosed volume): what closing may have left "
           "out",
           r->hole_area, r->area > 0 ? 100 * r->hole_area / r->area : 0.0, r->hole_cap_volume, r->holes_fair_estimated,
           r->holes_closed, r->hole_fair_volume, r->volume > 0 ? 100 * r->hole_fair_volume / r->volume : 0.0);
  }
  printf("\n  self-intersections: %lld pairs of triangles, %s", (long long)r->self_intersections,
         fix_name(r->self_intersection_fix));
  if (r->fold_tris) printf("; %lld triangles around folds re-filled", (long long)r->fold_tris);
  printf("\n");
  printf("  enclosed volume %.9g m^3 (before the self-intersection repair: %.9g)\n", r->volume, r->volume_before);
}
