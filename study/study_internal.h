/* study_internal.h — what the files of study/ share beyond bs_study.h
 * (not installed: the name is not bs_*.h). The tests include it to check
 * these steps one by one. Units, ownership and statuses as in bs_study.h. */
#ifndef BS_STUDY_INTERNAL_H
#define BS_STUDY_INTERNAL_H

#include <stdint.h>
#include <stdio.h>

#include "bs_study.h"

/* Rows of a complete frames.csv of run r (header excluded). */
int bs__study_run_rows(const bs_study_run *r);

/* ---- results ---------------------------------------------------------------- */

/* Steps of bs_study_evaluate: the costs of every run (frames.csv,
 * summary.txt); the errors against the reference (returns the runs not
 * compared); the Pareto front of cost against verdict_err (runs that
 * finished). */
void bs__study_read_costs(bs_study *S);
int bs__study_compare(bs_study *S);
void bs__study_mark_pareto(bs_study *S);

/* Vertex count of a body with counts c (V, E, F, T) after r uniform
 * refinements; the offsets of each body's block in a run with the given
 * refinement per body (returns the total vertex count). */
int64_t bs__study_body_vertices(const int64_t c[4], int r);
int64_t bs__study_offsets(const bs_study *S, const int *refine, int64_t *off);

/* Errors of one state file against another at common frame times (|t_a -
 * t_b| <= 1e-9 (1 + |t_b|)), over n_blocks blocks: count[q] vertices from
 * off_a[q] in a and off_b[q] in b. Reads both readers to their end. The
 * errors (RMS position difference / xscale, RMS velocity difference / vscale)
 * are NAN first; 0 when at least one frame was common, else -1 (also when a
 * block lies outside a reader). */
typedef struct bs_study_errors {
  double pos_max, pos_last, vel_max, vel_last;
  int n_common;
} bs_study_errors;

int bs__study_compare_states(bs_state_reader *a, bs_state_reader *b, int n_blocks, const int64_t *off_a,
                            const int64_t *off_b, const int64_t *count, double xscale, double vscale,
                            bs_study_errors *e);

/* The displacement scale D of a state file (bs_study.h): the largest, over
 * its frames, RMS over the blocks (count[q] vertices from off[q]) of the
 * distance of each vertex from where it was in the first frame. Reads r to
 * its end; 0 when r has no frame or a block lies outside it. */
double bs__study_disp_scale(bs_state_reader *r, int n_blocks, const int64_t *off, const int64_t *count);

/* Errors of run r against the run folder ref_dir whose body blocks start at
 * off_ref, into r's error fields (left as they are when a state file cannot
 * be opened, NAN when the vertices do not match); 0, or -1 when not compared. */
int bs__study_compare_run(const bs_study *S, bs_study_run *r, const char *ref_dir, const int64_t *off_ref);

/* The quantities of interest: each run's qoi.csv column of every S->qoi
 * name, compared with the reference's at common frame times (as the
 * states): error = |q - q_ref| / Q, Q = the reference's largest |q - o| over
 * its frames, o its first value for a position quantity, else 0 (1 when Q is
 * 0, making the error absolute); also S->q_origin, q_ref_last, q_ref_ok.
 * Returns the number of complete runs whose qoi.csv could not be read or
 * lacks a name. */
int bs__study_read_qoi(bs_study *S);


/* Largest vertex speed over all frames of dir/state.bin (m/s); 0 if unreadable. */
double bs__study_max_speed(const char *dir);

/* ---- orders ----------------------------------------------------------------- */

typedef struct bs_study_order {
  double p, logc;
  int used;
} bs_study_order;

/* The runs of method with every knob but k (and the method) at its finest
 * value, into out (n_runs entries); returns how many. */
int bs__study_group(const bs_study *S, int k, const char *method, int *out);
/* Whether run r of a knob-k group enters the fit against the reference. */
int bs__study_fit_point(const bs_study *S, const bs_study_run *r, int k);
/* The order of knob k for method against the reference. */
bs_study_order bs__study_order_fit(const bs_study *S, int k, const char *method);
/* The order of knob k from successive levels (each run of the group against
 * the next finer one; reads their state files). pts (may be NULL) gets a
 * line "LEVEL ERROR" per pair. NAN when fewer than two pairs. */
double bs__study_order_successive(const bs_study *S, int k, const char *method, int *used, FILE *pts);

#endif
