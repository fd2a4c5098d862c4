/* mesh_limits.c — how many tets a mesh job may make on this machine, and the
 * checks that refuse a job before it allocates: a structured box or a
 * refinement whose tets would not fit, and a Gmsh mesh size far too small for
 * the geometry (estimated from its volume before Gmsh meshes it). */
#include <math.h>
#include <stdint.h>

#include "mesh_internal.h"

double bs_mesh_max_tets(const bs_mesh_read_opts *opts) {
  if (opts && opts->max_tets > 0) return (double)opts->max_tets;
  const double mem = bs_machine_memory();
  const double by_memory = mem > 0 ? mem / BS_MESH_BYTES_PER_TET : INFINITY;
  return fmin(by_memory, (double)BS_MESH_MAX_TETS);
}

int bs__check_refined_count(double n_tets, int refine, const bs_mesh_read_opts *opts, const char *what,
                            bs_error *err) {
  const double want = n_tets * pow(8.0, refine), cap = bs_mesh_max_tets(opts);
  if (want <= cap) return 0;
  if (refine == 0)
    return bs_error_set(err, BS_EINPUT, "%s: %.3g tets, more than the %.4g this machine can hold (%.1f GiB)", what,
                        want, cap, bs_machine_memory() / 1073741824.0);
  return bs_error_set(err, BS_EINPUT,
                      "%s: %.0f tets refined %d times = %.3g tets, more than the %.4g this machine can hold (%.1f GiB; "
                      "refine less or use a coarser mesh)",
                      what, n_tets, refine, want, cap, bs_machine_memory() / 1073741824.0);
}

int bs__check_mesh_size(double volume, double size, const bs_mesh_read_opts *opts, const char *what, bs_error *err) {
  if (!(size > 0) || !(volume > 0)) return 0;
  /* Gmsh's Delaunay tets at size h fill a volume V with about 4.5 V / h^3
   * (a unit cube and a unit sphere at h = 0.2 .. 0.03); 6 V / h^3 is taken,
   * to refuse only what is surely too fine. */
  const double want = 6.0 * volume / (size * size * size), cap = bs_mesh_max_tets(opts);
  if (want <= cap) return 0;
  return bs_error_set(err, BS_EINPUT,
                      "%s: mesh size %g m in a volume of %g m^3 makes about %.3g tets, more than the %.3g this "
                      "machine can hold (%.1f GiB); the smallest size that fits is about %.3g m",
                      what, size, volume, want, cap, bs_machine_memory() / 1073741824.0, cbrt(6.0 * volume / cap));
}
