/* bs_doutput.h — the output folder of a run on the petsc backend: the run
 * folder of bs_runfolder.h, whose files every backend writes alike written
 * once, by runfolder/ on rank 0 (bs_runfolder_open_run: the lock, the check
 * of the folder, run.txt, scene.json, frames.csv with the measures over the
 * ranks, stats.csv, frames.pvd, summary.txt; bs_runfolder_state: state.bin,
 * the state gathered to rank 0 in the serial vertex order), and the
 * backend's own: the
 * frames for ParaView as one PVTU per written frame (frame_NNNNN.pvtu, rank
 * 0) over one VTU piece per rank (frame_NNNNN_pRRRR.vtu: the rank's owned
 * cells, with displacement, velocity, material, detF and inverted
 * (BS_DSIM_FIELDS) and a cell array "rank"), each written to NAME.tmp and
 * renamed, collected in frames.pvd; beside each, the obstacles' files
 * (bs_obstacle_output.h, rank 0, as a serial run's). ParaView opens
 * frames.pvd as one data set (the vertices shared by two ranks appear in
 * both pieces).
 *
 * Frames written: every frame's rows; a PVTU at frame 0 and every
 * output.vtu_every frames (every frame of a static run), as bs_runfolder.
 * What the backend does not write (checkpoints, qoi.csv, state.bin but of a
 * box mesh, fields outside BS_DSIM_FIELDS) is refused by
 * bs_dsim_check_output (bs_dout_open calls it), never skipped.
 *
 * Collective. Status: BS_EIO naming the file, BS_EINPUT (a folder in use or
 * with an earlier run, or what bs_dsim_check_output refuses), BS_ENOMEM; the
 * same status on every rank.
 */
#ifndef BS_DOUTPUT_H
#define BS_DOUTPUT_H

#include "bs_dsim.h"
#include "bs_runfolder.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_dout bs_dout;

/* opts: as bs_runfolder_open's (replace, the command line for run.txt); NULL:
 * all zero. */
int bs_dout_open(const bs_dsim *d, const char *dir, const bs_runfolder_opts *opts, bs_dout **out,
                 bs_error *err);
/* After frame fs (frame 0: the initial state) of d. */
int bs_dout_frame(bs_dout *o, bs_dsim *d, const bs_frame_stats *fs, bs_error *err);
/* summary.txt with this text and the appended files closed
 * (bs_runfolder_finish). */
int bs_dout_finish(bs_dout *o, const char *summary, bs_error *err);
void bs_dout_destroy(bs_dout **o);

/* The state's measures over the ranks (bs_measure_state on each rank's
 * owned cells, summed; min det F the minimum; penetration from
 * bs_dsim_penetration). */
int bs_dsim_measure(bs_dsim *d, bs_sim_measures *m, bs_error *err);

#ifdef __cplusplus
}
#endif
#endif
