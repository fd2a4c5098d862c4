/* bs_study.h — the study engine: speed against accuracy, measured.
 *
 * A study runs the cross product of varied settings ("knobs") of one scene,
 * each run in its own folder, compares every run with a reference run at
 * common frame times and reports study.csv, gnuplot data and a summary.
 * This library plans, measures and reports; running the runs (as processes,
 * threads or in-process) and running gnuplot is the caller's (`bigstep
 * study` forks `bigstep run` children).
 *
 *   plan      bs_study_knob_parse   "KEY=v1,v2,..." into a knob (kind, scene
 *                                   key path, values, the finest value);
 *             bs_study_create       the scene, the user's settings, the knobs;
 *             bs_study_plan         the runs: cross product (last knob fastest),
 *                                   names, folders, --set lists, each validated
 *                                   through bs_scene_load, the reference;
 *             bs_study_measure_bodies  body size L and per-body mesh counts.
 *   results   bs_study_evaluate     after the runs: costs (frames.csv,
 *                                   summary.txt), errors against the
 *                                   reference (state.bin), the quantities
 *                                   of interest (qoi.csv), the Pareto front.
 *   verdict   bs_study_verdict      the one ranking: the cheapest run within
 *                                   1%, 0.1%, 0.01% of the judged quantity
 *                                   (below); printing it is the caller's.
 *   report    bs_study_csv_write, bs_study_plots_write (data files and
 *             plots.gp), bs_study_summary_write (into the caller's FILE *:
 *             the runs not ok, the quantities and their GCI, the orders).
 *   metrics   pure functions on arrays (no files): the order fits, the
 *             Pareto front, the cheapest run within a threshold, energy drift.
 *
 * Errors against the reference (x_ref, v_ref), over the compared vertices C
 * (refinement appends edge midpoints, so the first vertices of each body are
 * the vertices of its coarsest mesh in the study; those are compared):
 *   position e_x(t) = sqrt(sum_{i in C} |x_i - x_ref,i|^2 / |C|) / D,
 *            D = what the reference moved: the max over its frames t of
 *            sqrt(sum_{i in C} |x_ref,i(t) - x_ref,i(t0)|^2 / |C|), t0 its
 *            first frame (the initial state); when D <= 1e-12 L (nothing
 *            moved), L = the diagonal of the bounding box of all bodies at
 *            rest. A run that moved 1.5 cm on a 1 m body is judged against
 *            1.5 cm, never against 1 m;
 *   velocity e_v(t) = sqrt(sum_{i in C} |v_i - v_ref,i|^2 / |C|) / V,
 *            V = the reference's largest vertex speed over all frames, or 1 m/s;
 * each the max over common frames and at the last common frame.
 * Quantities of interest (qoi.csv columns; by default the scene's own):
 *   error = |q - q_ref| / Q at common frames, Q = max over the reference's
 *   frames of |q_ref(t) - o|, o = q_ref(t0) for a position quantity (what it
 *   moved), else 0 (its magnitude); 1 when Q is 0.
 * Energy drift = max_t |total(t) - total(0)| / max(|total(0)|, max_t kinetic(t))
 * (1 J if both are 0). Orders: least-squares slope of log(error) against
 * log(h), h = 2^-refine (space) or dt (time), over the runs whose other knobs
 * are at the reference; and from successive levels (bs_study_successive_fit).
 *
 * Units: SI; errors are relative (dimensionless); costs in seconds per frame.
 * Ownership: a study owns its knobs (copied), runs, --set strings and
 * counts; free it with bs_study_destroy. A knob from bs_study_knob_parse is
 * the caller's, freed with bs_study_knob_free. The run fields exit_code,
 * maxrss_kib and wall are the caller's to fill once it has run a run.
 * Status: 0, or BS_EINPUT (a bad knob spec or a run's settings: the message
 * names the spec, key or run), BS_EIO (a file that cannot be written),
 * BS_ENOMEM, or the scene loader's and mesh reader's codes.
 * Nothing prints (the summary goes to the FILE * the caller passes).
 *
 * Example:
 *     bs_study_knob k; bs_study *S; bs_error err;
 *     bs_study_knob_parse("steps_per_frame=1,2,4", &k, &err);
 *     bs_study_opts o = {.scene = "beam.json", .n_knobs = 1, .knobs = &k};
 *     if (bs_study_create(&o, &S, &err) || bs_study_plan(S, &err) || bs_study_measure_bodies(S, &err)) ...
 *     bs_study_knob_free(&k);
 *     for (int i = 0; i < S->n_runs; i++) ... run `bigstep run scene --set S->runs[i].sets[...]`,
 *                                             set S->runs[i].exit_code
 *     int n_bad = bs_study_evaluate(S);
 *     bs_study_csv_write(S, &err); bs_study_summary_write(S, stdout);
 *     bs_study_destroy(&S);
 */
#ifndef BS_STUDY_H
#define BS_STUDY_H

#include <stdint.h>
#include <stdio.h>

#include "bs_base.h"
#include "bs_runfolder.h"
#include "bs_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BS_STUDY_MAX_KNOBS 16
#define BS_STUDY_MAX_BODIES 64
#define BS_STUDY_MAX_RUNS 100000
#define BS_STUDY_MAX_QOI 16

/* Sizes (bytes, with the terminating NUL). Folders (the study's, the
 * reference's, each run's OUT/NAME) are at most BS_MAX_PATH: a longer one is
 * refused (BS_EINPUT naming it). A run's name "key=value,..." is at most
 * BS_STUDY_NAME_LEN (a longer one is refused). A file in such a folder
 * (bs_study_file_path) is the folder, '/' and a name of at most
 * BS_STUDY_FILE_NAME_MAX - 1 bytes (every file a study and its caller write
 * there: study.csv, plot_*.dat, plots.gp, done, run.log, ...). */
#define BS_STUDY_NAME_LEN 512
#define BS_STUDY_FILE_NAME_MAX 64
#define BS_STUDY_FILE_PATH (BS_MAX_PATH + BS_STUDY_FILE_NAME_MAX)

/* "DIR/NAME" into p: 0, or BS_EINPUT naming the path when it does not fit
 * (DIR longer than BS_MAX_PATH - 1 or NAME than BS_STUDY_FILE_NAME_MAX - 1). */
int bs_study_file_path(const char *dir, const char *name, char p[BS_STUDY_FILE_PATH], bs_error *err);

/* ---- convergence of a quantity (pure; study_gci.c) --------------------- */

/* Richardson extrapolation and the grid convergence index (GCI) of a
 * quantity f at three levels h[0] < h[1] < h[2] (fine to coarse: cell size
 * 2^-refine, or dt), after Roache and Celik et al. 2008 (J. Fluids Eng. 130,
 * 078001), safety factor 1.25 as ASME V&V 20 uses for three levels:
 *   e21 = f1 - f0, e32 = f2 - f1, r21 = h1/h0, r32 = h2/h1, s = sign(e32/e21);
 *   p   the root of e32/e21 = r21^p (r32^p - 1) / (r21^p - 1) (Celik's eq. (4)
 *       for monotone convergence, s = 1), by bisection on (0, 64];
 *   extrapolated = (r21^p f0 - f1) / (r21^p - 1);
 *   e_a = |(f0 - f1)/f0|, GCI_fine = 1.25 e_a / (r21^p - 1), GCI_coarse the
 *   same of levels 1, 2 with r32; asymptotic = GCI_coarse / (r21^p GCI_fine),
 *   near 1 in the asymptotic range; e_ext = |(extrapolated - f0)/extrapolated|.
 * Fields are NAN where not defined; relative figures are fractions (not %). */
typedef enum {
  BS_GCI_OK = 0,        /* monotone convergence: every field set                    */
  BS_GCI_OSCILLATORY,   /* e32 / e21 < 0: no order or extrapolation is fitted        */
  BS_GCI_DIVERGENT,     /* |e21| >= |e32|: the differences do not shrink            */
  BS_GCI_CONVERGED,     /* e21, e32 within 1e-12 of the values: extrapolated f0, GCI 0 */
  BS_GCI_NO_ORDER,      /* one difference 0, or the fixed point failed               */
  BS_GCI_BAD_INPUT      /* a non-finite value, h not positive and increasing         */
} bs_gci_status;

typedef struct bs_gci {
  bs_gci_status status;
  double p, extrapolated, e_a, e_ext, gci_fine, gci_coarse, asymptotic;
} bs_gci;

/* "monotone", "oscillatory", "divergent", "converged", "no_order", "bad_input". */
const char *bs_gci_status_name(bs_gci_status s);
bs_gci_status bs_study_gci(const double h[3], const double f[3], bs_gci *g);

/* ---- knobs ----------------------------------------------------------------- */

typedef enum {
  BS_KNOB_STEPS_PER_FRAME = 0, /* time.steps_per_frame: finest the largest     */
  BS_KNOB_TOLERANCE,           /* solver.tolerance: finest the smallest         */
  BS_KNOB_REFINE,              /* bodies.*.refine or bodies.N.refine: largest   */
  BS_KNOB_METHOD,              /* solver.method: "optimization", else the first */
  BS_KNOB_DT,                  /* time.dt: smallest                              */
  BS_KNOB_FPS,                 /* time.fps: largest                              */
  BS_KNOB_OTHER                /* any other key path: the last listed value      */
} bs_knob_kind;

typedef struct bs_study_knob {
  char key[256];   /* as given (the study.csv column)                          */
  char path[256];  /* scene key path; "" for refine over every body, and       */
                   /* "bodies.*.KEY" for a shorthand of every body (element)   */
  bs_knob_kind kind;
  int body;        /* BS_KNOB_REFINE through bodies.N.refine: N; -1 every body */
  int n;           /* values                                                   */
  char **vals;     /* owned                                                    */
  double *num;     /* the values as numbers (NAN for method and other knobs)   */
  int finest;      /* index of the finest value                                */
} bs_study_knob;

/* Parses "KEY=v1,v2,..." (KEY a key path or a shorthand: steps_per_frame,
 * tolerance, method, refine). BS_EINPUT with a message "'SPEC': problem"
 * (no key, not a key path, an empty or repeated value, a non-number for a
 * numeric knob). */
int bs_study_knob_parse(const char *spec, bs_study_knob *k, bs_error *err);
void bs_study_knob_free(bs_study_knob *k);
/* 1 when b varies the same scene key as a (the same path; refine of the
 * same body or of every body). */
int bs_study_knob_same(const bs_study_knob *a, const bs_study_knob *b);
/* 1 for the knobs that set dt (steps_per_frame, dt, fps). */
int bs_study_knob_is_time(const bs_study_knob *k);

/* ---- the study -------------------------------------------------------------- */

typedef struct bs_study_run {
  int idx[BS_STUDY_MAX_KNOBS]; /* value index of each knob                  */
  char name[BS_STUDY_NAME_LEN]; /* "key=value,key=value"                   */
  char dir[BS_MAX_PATH];       /* OUT/name                                  */
  int n_sets;
  char **sets;                 /* owned "key=value": defaults, the user's, the knobs', output.* */
  /* from the run's scene */
  int frames, spf, is_static;
  double fps;
  char method[32];
  int *body_refine;            /* n_bodies                                  */
  /* the process: the caller's to fill */
  int exit_code;               /* 0 ok; anything else: failed               */
  int timed_out;               /* 1: stopped after the run budget           */
  long maxrss_kib;             /* peak memory of the process (0: unknown)    */
  double wall;                 /* s                                          */
  /* results (bs_study_evaluate) */
  int complete, is_ref, pareto, n_rows, inv_max;
  long newton, cg, failed_steps;
  double s_per_frame, newton_per_step, cg_per_step, peak_mib;
  double pos_max, pos_last, vel_max, vel_last, drift, pen_max;
  /* quantities of interest (bs__study_read_qoi; NAN where not measured) */
  double q_last[BS_STUDY_MAX_QOI];     /* the value at the last frame       */
  double q_err_last[BS_STUDY_MAX_QOI]; /* |q - q_ref| / Q at the last common frame */
  double q_err_max[BS_STUDY_MAX_QOI];  /* the max over common frames        */
  /* the verdict (bs_study_evaluate, bs_study_verdict) */
  double verdict_err;          /* the error of the judged quantity; NAN: not measured */
  int verdict_by;              /* what set it: an index into S->qoi, -1 the position error */
} bs_study_run;

/* "ok", "failed" (nonzero exit), "timeout" (timed_out). */
const char *bs_study_run_status(const bs_study_run *r);

typedef struct bs_study_opts {
  const char *scene;            /* the scene file                              */
  int n_sets;                   /* the user's "key.path=value" settings        */
  const char *const *sets;
  int n_knobs;
  const bs_study_knob *knobs;   /* copied                                      */
  const char *reference;        /* a run folder; NULL: the finest run (auto)   */
  const char *out;              /* the study folder; NULL: out/study/<scene name> */
  int n_qoi;                    /* quantities of interest measured (qoi.csv names); */
  const char *const *qoi;       /* 0: the scene's own (bs_scene.qoi), if any      */
  int no_scene_qoi;             /* 1: with n_qoi 0, none (judge the position error) */
} bs_study_opts;

/* ---- the verdict -------------------------------------------------------------- */

#define BS_STUDY_N_THRESHOLDS 3 /* 1%, 0.1%, 0.01% */
/* The smallest observed order an extrapolation is trusted with: below it
 * the extrapolated value is the last difference times 1 / (2^p - 1) > 2.4
 * beyond the finest level (a sequence far from its asymptotic range). */
#define BS_STUDY_MIN_ORDER 0.5

/* A quantity the verdict judges: error = |q_last - target| / scale. */
typedef struct bs_study_judged {
  int qoi;             /* index into S->qoi                                        */
  int extrapolated;    /* 1: target = the Richardson extrapolation of q_last along  */
                       /* knobs[knob] (GCI converged, or monotone with an observed   */
                       /* order p >= BS_STUDY_MIN_ORDER); 0: the reference's value   */
                       /* (error = the run's q_err_last)                            */
  int knob;            /* the knob of gci: the first refine (then time) knob whose */
                       /* three finest levels converge (monotone or converged), else */
                       /* the first with three levels; -1 when there is none        */
  bs_gci gci;          /* along knob, for the verdict's method (its status says why  */
                       /* a quantity is not extrapolated: p too low, or divergent...) */
  double target;       /* the extrapolated value, or the reference's last value (NAN: */
                       /* a given reference folder)                                  */
  double scale;        /* extrapolated: |target - o| (o as for Q, bs_study.h top),   */
                       /* Q when that is 0; else Q                                   */
} bs_study_judged;

/* The study's one verdict. The judged quantity: the quantities of interest
 * that can be judged (extrapolated, or present in the reference's qoi.csv),
 * a run's error being the largest of theirs (verdict_by names which); when
 * there are none, the position error pos_max (the max over frames, against
 * the reference). Candidates: every run that finished (exit 0, not timed
 * out) with a finite error and cost, across every knob (method, strings,
 * refinement alike); the reference too when a judged quantity is
 * extrapolated (else its error is 0 by construction and it is left out; in
 * a quantity judged against the reference its error is 0). */
typedef struct bs_study_verdict {
  int on_qoi;          /* 1: judged on quantities of interest; 0: on the position error */
  int n_judged;
  bs_study_judged judged[BS_STUDY_MAX_QOI];
  char method[32];     /* the method whose GCI groups gave the extrapolations  */
  int ref_competes;    /* the reference run is a candidate (a quantity is extrapolated) */
  double threshold[BS_STUDY_N_THRESHOLDS]; /* 1e-2, 1e-3, 1e-4                  */
  int cheapest[BS_STUDY_N_THRESHOLDS];     /* the cheapest candidate within each (by */
                                           /* s/frame, the first of equal costs); -1 none */
  int most_accurate;   /* the candidate with the smallest error; -1 none        */
  int n_candidates;
} bs_study_verdict;

typedef struct bs_study {
  char scene_path[BS_MAX_PATH], name[256], out[BS_MAX_PATH];
  char ref_dir[BS_MAX_PATH];    /* "" : the reference is runs[ref]             */
  int n_user;
  char **user_sets;
  int n_knobs;
  bs_study_knob knobs[BS_STUDY_MAX_KNOBS];
  int n_bodies;
  int n_runs;
  bs_study_run *runs;
  int ref;                      /* the reference run, -1 for a given folder    */
  double size;                  /* body size L (m)                             */
  int64_t (*counts)[4];         /* per body V, E, F, T at refine 0             */
  int64_t cmp[BS_STUDY_MAX_BODIES]; /* compared vertices per body              */
  double vscale;                /* velocity scale V (m/s)                      */
  int direct;                   /* whole states compared (no refinement relation) */
  int n_qoi;
  char qoi[BS_STUDY_MAX_QOI][BS_MAX_NAME];
  double q_ref_scale[BS_STUDY_MAX_QOI]; /* Q: the reference's largest |q| over frames (1 if 0) */
  int q_ref_ok[BS_STUDY_MAX_QOI];      /* the reference's qoi.csv had the column */
  double q_origin[BS_STUDY_MAX_QOI];   /* o of Q (top): the reference's first value for a position */
  double q_ref_last[BS_STUDY_MAX_QOI]; /* the reference's last value (NAN: none)  */
  int q_kind[BS_STUDY_MAX_QOI];        /* the scene's bs_qoi_kind of the name; -1 not the scene's */
  double disp;                  /* D: what the reference moved (m; top), 0 if unread */
  double xscale;                /* the position error's scale: D, or L when nothing moved */
  bs_study_verdict verdict;     /* bs_study_evaluate's                          */
} bs_study;

/* Copies the options and loads the scene with the user's settings (its
 * body count; at most BS_STUDY_MAX_BODIES). A scene path, reference or
 * study folder of BS_MAX_PATH bytes or more is BS_EINPUT naming it. */
int bs_study_create(const bs_study_opts *o, bs_study **out, bs_error *err);
void bs_study_destroy(bs_study **S);

/* Every bodies.N.refine knob names a body of the scene: else BS_EINPUT
 * "'KEY': the scene has N bodies". */
int bs_study_check_bodies(const bs_study *S, bs_error *err);

/* The runs (see the top). Each run's settings go through bs_scene_load:
 * "run NAME: message". Refinement knobs need bodies.*.reorder none. A run
 * name or folder longer than its size (see Sizes) is BS_EINPUT naming it. */
int bs_study_plan(bs_study *S, bs_error *err);

/* Body size L and the per-body counts of the unrefined meshes. */
int bs_study_measure_bodies(bs_study *S, bs_error *err);

/* The cache key of run r: a digest (zlib's CRC-32 and Adler-32, and the
 * byte count) of the scene file's bytes, the run's --set list, and the bytes
 * of every mesh and grid level-set file the run's scene names (resolved
 * paths); hex, BS_STUDY_KEY_LEN characters. A run folder is reused only when
 * the key it was made with is this one. BS_EIO for a file that cannot be
 * read, or the scene loader's codes. */
#define BS_STUDY_KEY_LEN 32
int bs_study_run_key(const bs_study *S, const bs_study_run *r, char key[BS_STUDY_KEY_LEN + 1], bs_error *err);

/* Whether r->dir holds a complete frames.csv (the rows a run of r's scene
 * writes, header excluded: frames + 1, or 2 for a static scene). */
int bs_study_run_complete(const bs_study_run *r);

/* ---- results ---------------------------------------------------------------- */

/* Reads the costs of every run, compares every run with the reference, reads
 * the quantities of interest, makes the verdict (S->verdict, each run's
 * verdict_err) and marks the Pareto front of cost against verdict_err;
 * returns the number of runs that could not be compared (their errors are
 * NAN, or untouched when a state file is missing). */
int bs_study_evaluate(bs_study *S);

/* The verdict (see bs_study_verdict) of a study whose costs, errors and
 * quantities are read; sets each run's verdict_err and verdict_by. */
void bs_study_verdict_make(bs_study *S, bs_study_verdict *v);

/* ---- metrics: pure functions ------------------------------------------------ */

/* Least-squares slope p of log err against log h over the points with h > 0,
 * err > 0 and err finite (used: how many), and logc (err ~ exp(logc) h^p).
 * NAN (both) when fewer than 2 points or all h equal. */
double bs_study_fit_order(int n, const double *h, const double *err, double *logc, int *used);

/* The order from successive levels: d[j] the error of level j (step h[j])
 * against level j + 1, rho[j] = h[j+1] / h[j] < 1. Then
 * d_j ~ C h_j^p (1 - rho_j^p), fitted in log-log with the bracket solved for
 * by fixed-point iteration (to 1e-10, at most 100 rounds) from the plain fit.
 * Unlike the fit against a reference one level finer (which reports
 * log2(2^p + 1) from two halvings), this is unbiased. */
double bs_study_successive_fit(int n, const double *h, const double *d, const double *rho, int *used);

/* The Pareto front over points (cost, error) that are ok and finite in both:
 * front[i] = 1 when no other such point is no worse in both and better in
 * one; 0 for the others and for the points not ok. */
void bs_study_pareto(int n, const double *cost, const double *error, const int *ok, int *front);

/* The index of the cheapest point (the first of equal costs) among those
 * that are ok, have error <= threshold and a finite cost; -1 if none. */
int bs_study_cheapest_within(int n, const double *cost, const double *error, const int *ok, double threshold);


/* Energy drift of a frames table (formula at the top); NAN for no rows. */
double bs_study_energy_drift(const bs_frames_table *t);

/* ---- report ----------------------------------------------------------------- */

/* OUT/study.csv: one row per run (BS_EIO "cannot write 'OUT/study.csv'"). */
int bs_study_csv_write(const bs_study *S, bs_error *err);
/* OUT/plots.gp and its data files (plot_*.dat); run "gnuplot plots.gp" in OUT. */
int bs_study_plots_write(const bs_study *S, bs_error *err);
/* The summary (no verdict: that is S->verdict, for the caller to print): the
 * runs that failed or timed out, each quantity of interest per run with its
 * GCI along each refinement or time knob, and the observed orders. */
void bs_study_summary_write(const bs_study *S, FILE *f);


/* ---- the study's results, for programs (the Python package) ------------- */

/* GCI of quantity q (an index into S->qoi) along knob k for method: the
 * three finest complete runs of the knob's group (other knobs at the
 * reference, distinct h), their q_last values.
 * used[3] gets their run indices (-1: missing), *n_skipped the runs of the
 * group that failed or timed out. BS_GCI_BAD_INPUT with fewer than three. */
bs_gci_status bs_study_qoi_gci(const bs_study *S, int k, const char *method, int q, bs_gci *g, int used[3],
                              int *n_skipped);
/* h of run r for knob k: 2^-refine (space) or dt (time). */
double bs_study_knob_h(const bs_study *S, const bs_study_run *r, int k);
/* The distinct methods of the runs, in run order (pointers into the runs). */
int bs_study_methods(const bs_study *S, const char **names, int max);

#ifdef __cplusplus
}
#endif
#endif
