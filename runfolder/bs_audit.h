/* bs_audit.h — auditing saved states: the VTU frames of a run folder (or any
 * VTU files of tet meshes) checked for inverted tets, surface
 * self-intersections and, given the scene, vertices inside its obstacles.
 * What `bigstep check` reports.
 *
 * What is audited, per VTU file (bs_vtu_read: points, tets, and the point
 * array "displacement"):
 *  - inverted tets: the rest shape is recovered as rest = x - displacement
 *    (bs_vtu_rest) and the mesh rebuilt from it (bs_mesh_create orients every
 *    tet positively at rest and refuses a tet of zero rest volume); a tet is
 *    inverted when the exact orientation of its four current positions is not
 *    positive, i.e. det F <= 0 decided without round-off. A quadratic tet
 *    (VTK type 24) is inverted when its corners are, or when its curved map
 *    folds: det J <= 0 at one of its 10 nodes or 14 quadrature points of the
 *    current positions (bs_tet10_rest_init; floating point, not exact);
 *  - surface self-intersections: the boundary triangles of that rest mesh
 *    (of a quadratic mesh: the flat triangles of its corners, which do not
 *    follow the curved faces),
 *    placed at the current positions, tested pairwise with exact predicates
 *    (degenerate triangles count as a pair);
 *  - vertices inside obstacles (with a simulation of the scene that produced
 *    the states, bs_sim_create): the file's points must be the simulation's
 *    vertices (same count, and the rest shape equal to the simulation's up to
 *    1e-9 of its largest box edge), then bs_sim_penetration counts the
 *    vertices inside some obstacle at the frame's time and the largest depth.
 * Points that no tet uses are ignored by the first two checks.
 *
 * Which files: bs_audit_list_frames lists, for a folder, its frame_N.vtu
 * files (N all digits, at most 9) in the order of N, or, when it holds none,
 * the files its frames.pvd lists; for a .pvd file, the files it lists; for
 * any other file, that file. A frame's time is the PVD's timestep when it
 * has one, else N / fps for frame N of a dynamic scene (the frames `bigstep
 * run` writes), else 0 (bs_audit_entry_time).
 *
 * Units: SI (m, s); depths in metres. Counts of one frame in
 * bs_audit_counts; sums over frames in bs_audit_totals.
 *
 * Ownership: a list is the caller's, freed with bs_audit_list_free. An
 * auditor (bs_auditor_create) borrows the simulation it is given (which
 * must outlive it) and overwrites that simulation's positions x and time at
 * every frame; it keeps the rest mesh of the last frame, reused while the
 * next frame has the same tets and rest shape. Free it with
 * bs_auditor_destroy. Nothing here prints: bs_audit_run hands each frame's
 * counts or error to the caller's callback.
 *
 * Status: 0; BS_EIO (a file or folder that cannot be read: the message
 * names it and the OS reason); BS_EINPUT (a file that is not a VTU or PVD
 * file, a VTU without cells or without a usable displacement, a rest tet of
 * zero volume, a state that is not one of the simulation's scene, a folder
 * with no frames, a PVD listing none; the message names the file);
 * BS_ENUMERIC (a rest coordinate that is not finite); BS_ENOMEM;
 * BS_EINTERNAL (an exact test that failed).
 *
 * Example:
 *   bs_audit_list L; bs_audit_totals T; bs_error err;
 *   if (bs_audit_list_frames("out/run", &L, &err)) { report(err.msg); return; }
 *   if (bs_audit_run(&L, NULL, on_frame, ctx, &T, &err)) report(err.msg);
 *   else if (T.inverted || T.self_pairs || T.unreadable) ...;
 *   bs_audit_list_free(&L);
 * with on_frame(ctx, e, status, c, err) called once per entry, in order:
 * status 0 with the frame's counts, else the frame's error.
 */
#ifndef BS_AUDIT_H
#define BS_AUDIT_H

#include <stdint.h>

#include "bs_base.h"
#include "bs_sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One file to audit. */
typedef struct bs_audit_entry {
  char *path;     /* as found: FOLDER/frame_N.vtu, the PVD's file attribute
                     (resolved against the PVD's folder), or the file given  */
  int number;     /* N when the file is named frame_N.vtu, else the position
                     in the PVD's list (0 for a single file)                  */
  double time;    /* the PVD's timestep (s), when has_time                    */
  int has_time;
} bs_audit_entry;

/* How a list was made (for a caller's report). */
typedef enum {
  BS_AUDIT_ONE_FILE = 0,  /* the target is a file, not a .pvd                */
  BS_AUDIT_FRAME_FILES,   /* a folder's frame_N.vtu files                    */
  BS_AUDIT_FOLDER_PVD,    /* a folder without them: its frames.pvd's files    */
  BS_AUDIT_PVD_FILE       /* the target is a .pvd file: the files it lists    */
} bs_audit_origin;

typedef struct bs_audit_list {
  int n;
  bs_audit_entry *entries; /* n, in audit order                              */
  bs_audit_origin origin;
} bs_audit_list;

/* The files to audit for target (a folder, a .pvd file or a VTU file; see
 * the top). On error *L is empty. BS_EIO for a target that does not exist or
 * a folder that cannot be listed, BS_EINPUT for a folder with no frames and
 * no frames.pvd or a PVD listing no data sets, the PVD reader's codes. */
int bs_audit_list_frames(const char *target, bs_audit_list *L, bs_error *err);

/* Frees the entries and empties L (NULL accepted). */
void bs_audit_list_free(bs_audit_list *L);

/* The time of entry e: its PVD timestep, else number / fps when sim's scene
 * is dynamic, else 0 (also for sim NULL). */
double bs_audit_entry_time(const bs_audit_entry *e, const bs_sim *sim);

/* What one frame holds. */
typedef struct bs_audit_counts {
  int32_t n_tets;      /* tets of the file                                   */
  int32_t inverted;    /* tets whose current orientation is not positive     */
  int64_t self_pairs;  /* intersecting pairs of boundary triangles           */
  int32_t penetrating; /* vertices inside an obstacle (0 without a sim)      */
  double max_depth;    /* the largest depth inside an obstacle (m; 0 without) */
} bs_audit_counts;

/* The reusable state of an audit (see Ownership). */
typedef struct bs_auditor bs_auditor;

/* sim: the scene's simulation for the obstacle check, or NULL for none. */
int bs_auditor_create(bs_sim *sim, bs_auditor **out, bs_error *err);
void bs_auditor_destroy(bs_auditor **a);

/* Reads and audits the VTU file at path, at time t (s; used only with a
 * sim), into *c (zeroed first). Errors name the file. */
int bs_auditor_frame(bs_auditor *a, const char *path, double t, bs_audit_counts *c, bs_error *err);

/* The sums over the frames of a list. */
typedef struct bs_audit_totals {
  int n_frames;             /* entries audited or tried                      */
  long long inverted, self_pairs, penetrating;
  double max_depth;         /* m, the largest over the frames                */
  int bad_frames;           /* frames with an inverted tet, an intersecting
                               pair or a penetrating vertex                  */
  int unreadable;           /* entries whose audit failed                    */
} bs_audit_totals;

/* Called once per entry in list order: status 0 and the frame's counts c,
 * or the frame's error status and err (c then zero). */
typedef void (*bs_audit_frame_fn)(void *ctx, const bs_audit_entry *e, int status, const bs_audit_counts *c,
                                  const bs_error *err);

/* Audits every entry of L at its time (bs_audit_entry_time) with sim (may be
 * NULL), calling fn (may be NULL) after each, and sums into *T. A frame that
 * cannot be audited is counted as unreadable and the audit goes on: the
 * status is 0 then, and nonzero only when the audit itself cannot start
 * (BS_ENOMEM). */
int bs_audit_run(const bs_audit_list *L, bs_sim *sim, bs_audit_frame_fn fn, void *ctx, bs_audit_totals *T,
                 bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
