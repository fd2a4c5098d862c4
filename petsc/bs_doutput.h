/* bs_doutput.h — the output folder of a run on the petsc backend: the same
 * frames.csv (bs_frames_csv_row) and summary.txt (bs_summary_format) as a
 * serial run, written by rank 0, plus scene.json; the frames for ParaView as
 * one PVTU per written frame (frame_NNNNN.pvtu) over one VTU piece per rank
 * (frame_NNNNN_pRRRR.vtu: the rank's owned cells, with the serial VTU's
 * arrays and a cell array "rank"), collected in frames.pvd. ParaView opens
 * frames.pvd as one data set (the vertices shared by two ranks appear in
 * both pieces).
 *
 * Frames written: every frame's row; a PVTU at frame 0 and every
 * output.vtu_every frames (every frame of a static run), as bs_runfolder.
 * Not written (yet): stats.csv, state.bin, qoi.csv, checkpoints, run.txt, and
 * no lock is taken. A folder that holds a frames.csv is refused unless
 * `replace`.
 *
 * Collective. Status: BS_EIO naming the file, BS_EINPUT (a folder with an
 * earlier run), BS_ENOMEM; the same status on every rank.
 */
#ifndef BS_DOUTPUT_H
#define BS_DOUTPUT_H

#include "bs_dsim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bs_dout bs_dout;

int bs_dout_open(const bs_dsim *d, const char *dir, int replace, bs_dout **out, bs_error *err);
/* After frame fs (frame 0: the initial state) of d. */
int bs_dout_frame(bs_dout *o, bs_dsim *d, const bs_frame_stats *fs, bs_error *err);
/* summary.txt with this text, written through summary.txt.tmp renamed over
 * it (bs_outfile_replace_text, base/outfile.h): a reader or a kill finds the
 * old summary or the new one. */
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
