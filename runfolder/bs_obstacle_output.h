/* bs_obstacle_output.h — a run's obstacles written for ParaView beside its
 * frames, at their pose at each frame's time.
 *
 * Files, for obstacle K (its index in the scene's "obstacles") in the run
 * folder:
 *   analytic shapes (plane, sphere, box, cylinder, torus, inside_out ones
 *     too): a triangle surface (.vtu, bs_ls_surface.h; the plane a square
 *     patch sized to the bodies' bounding box at t = 0), oriented out of the
 *     obstacle into free space;
 *   grid level sets (shape "grid", or an analytic shape sampled with grid_h):
 *     VTK ImageData (.vti) with point data "phi" (m, negative inside), placed
 *     by Origin and Direction at the obstacle's pose (ParaView: Contour at 0
 *     shows the surface);
 *   a moving obstacle gets one file per VTU frame, obstacle_K_NNNNN.vtu (or
 *     .vti), NNNNN the frame number of frame_NNNNN.vtu; a static one a single
 *     obstacle_K.vtu (or .vti), written with the first frame;
 *   obstacles_K.pvd, the collection of obstacle K over the frames written
 *     (a static obstacle's file at every frame time), rewritten through a
 *     temporary file and a rename after every frame, so that it is valid
 *     after each one.
 * The surfaces are compressed when the scene's output.compress says so; the
 * image data is raw.
 *
 * Ownership: bs_obstacle_output_create returns a writer (NULL, and 0, when
 * the scene has no obstacle) freed by bs_obstacle_output_destroy (NULL
 * accepted, pointer nulled); it borrows the simulation's obstacles.
 * Status: 0, BS_EIO (a file that cannot be written, named), BS_ENOMEM.
 *
 * Example (what the run folder does):
 *     bs_obstacle_output *ob;
 *     bs_obstacle_output_create("out", sim, &ob, &err);
 *     ... after each VTU frame:  bs_obstacle_output_frame(ob, sim, frame, &err);
 *     bs_obstacle_output_destroy(&ob);
 */
#ifndef BS_OBSTACLE_OUTPUT_H
#define BS_OBSTACLE_OUTPUT_H

#include "bs_base.h"
#include "bs_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_obstacle_output bs_obstacle_output;

int bs_obstacle_output_create(const char *dir, const bs_sim *s, bs_obstacle_output **out, bs_error *err);

/* The same for any backend: the obstacles obs (NULL or none: *out NULL, 0;
 * borrowed), the bodies' rest bounding box lo, hi over every vertex (a
 * plane's patch), output.compress. */
int bs_obstacle_output_create_for(const char *dir, const bs_obstacles *obs, const double lo[3], const double hi[3],
                                  int compress, bs_obstacle_output **out, bs_error *err);

/* Writes every obstacle at s->time (the files of frame `frame`) and the PVDs. */
int bs_obstacle_output_frame(bs_obstacle_output *o, const bs_sim *s, int frame, bs_error *err);
/* The same at time t (s). */
int bs_obstacle_output_frame_at(bs_obstacle_output *o, double t, int frame, bs_error *err);

/* For a run continued after frame `frame` (bigstep run --resume): records
 * frame's files, which the earlier run wrote, at time t without writing them
 * (nor the PVDs); call for every VTU frame up to the checkpoint, then
 * bs_obstacle_output_write_pvds. */
int bs_obstacle_output_skip(bs_obstacle_output *o, int frame, double t, bs_error *err);
int bs_obstacle_output_write_pvds(bs_obstacle_output *o, bs_error *err);

void bs_obstacle_output_destroy(bs_obstacle_output **o);

#ifdef __cplusplus
}
#endif
#endif
