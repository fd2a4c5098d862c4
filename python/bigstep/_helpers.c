/* _helpers.c — the C side of the Python binding, compiled into the cffi
 * extension bigstep._bigstep (not into the library). Only the installed API
 * (bigstep/bigstep.h) is used.
 *
 *   bspy_run_sim   bs_sim_run_with with a stop flag that a SIGINT handler of
 *                  ours sets (installed for the call only, the previous handler
 *                  put back after), an on_frame that writes the run folder
 *                  like `bigstep run` and calls back into Python, and a frame
 *                  limit (the flag is also set after the last wanted frame);
 *   bspy_step_sig  bs_sim_take_step with SIGINT caught for its duration;
 *   bspy_add_term  a term whose value, gradient and Hessian are Python's.
 * The Python callbacks are cffi extern "Python" functions: cffi takes the GIL
 * around them; every other call runs with the GIL released. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Defined by cffi below (extern "Python"). */
static int bspy_py_frame(const bs_sim *s, const bs_frame_stats *fs, void *py);
static int bspy_py_value(void *py, const bs_term *t, const double *x, double *E);
static int bspy_py_gradient(void *py, const bs_term *t, const double *x, double *E, double *g);
static int bspy_py_hessian(void *py, const bs_term *t, const double *x, bs_bsr *H);

typedef struct bspy_run {
  bs_runfolder *folder;        /* NULL: no output folder                          */
  void *py;                    /* the Python callback's handle; NULL: none        */
  int last_frame;              /* stop after this frame; -1: the scene's last     */
  int stop_reason;             /* after a stop: the signal (> 0), or -1 the limit */
  int measured_frame;          /* the frame last_m measured; -1 none              */
  bs_sim_measures last_m;
  volatile sig_atomic_t stop;  /* the flag bs_sim_run_with reads                  */
  int py_failed;               /* the Python callback raised                      */
} bspy_run;

static volatile sig_atomic_t *volatile bspy_flag = NULL;

static void bspy_on_sigint(int sig) {
  volatile sig_atomic_t *f = bspy_flag;
  if (f) *f = sig;
}

static int bspy_on_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  bspy_run *r = ctx;
  if (r->folder) { /* as `bigstep run`: measured once with intersections, then the folder's files */
    bs_sim_measure(s, 1, &r->last_m);
    r->measured_frame = fs->frame;
    if (bs_runfolder_write(r->folder, s, fs, &r->last_m, err)) return BS_EIO;
  }
  if (r->py && bspy_py_frame(s, fs, r->py)) {
    r->py_failed = 1;
    return bs_error_set(err, BS_EINPUT, "the Python frame callback raised an exception");
  }
  if (r->last_frame >= 0 && fs->frame >= r->last_frame && !r->stop) r->stop = -1;
  return 0;
}

int bspy_run_sim(bs_sim *s, bspy_run *r, int resume, bs_run_totals *T, int catch_sigint, bs_error *err) {
  struct sigaction sa, old;
  int installed = 0;
  r->stop = 0;
  r->stop_reason = 0;
  r->py_failed = 0;
  if (catch_sigint) {
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = bspy_on_sigint;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    bspy_flag = &r->stop;
    if (sigaction(SIGINT, &sa, &old) == 0) installed = 1;
    else bspy_flag = NULL;
  }
  const bs_sim_run_opts o = {.on_frame = bspy_on_frame, .ctx = r, .stop = &r->stop, .resume = resume};
  int st = bs_sim_run_with(s, &o, T, err);
  if (installed) {
    sigaction(SIGINT, &old, NULL);
    bspy_flag = NULL;
  }
  if (st == BS_SIM_STOPPED) r->stop_reason = r->stop;
  return st;
}

/* The summary into the folder (as `bigstep run` writes it): 0 or BS_EIO. */
int bspy_finish(bspy_run *r, const bs_sim *s, const bs_run_totals *T, int stopped, double wall, bs_error *err) {
  if (!r->folder) return 0;
  bs_summary u;
  char summary[2048];
  if (!stopped && r->measured_frame == s->frame) bs_summary_make_measured(s, T, wall, &r->last_m, &u);
  else bs_summary_make(s, T, wall, &u);
  if (stopped) u.partial = BS_SUMMARY_INTERRUPTED;
  bs_summary_format(&u, summary, sizeof summary);
  int st = bs_runfolder_finish(r->folder, summary, err);
  bs_runfolder_destroy(&r->folder);
  return st;
}

double bspy_folder_wall(bspy_run *r) { return r->folder ? bs_runfolder_wall(r->folder) : 0.0; }

/* bs_sim_take_step with SIGINT caught for its duration (catch_sigint):
 * *got_sigint says whether one came, for the caller to raise
 * KeyboardInterrupt once its bookkeeping is done (the step itself is
 * completed, not undone). */
int bspy_step_sig(bs_sim *s, int catch_sigint, int *got_sigint, int *frame_done, bs_frame_stats *fs, bs_error *err) {
  struct sigaction sa, old;
  int installed = 0;
  volatile sig_atomic_t flag = 0;
  if (catch_sigint) {
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = bspy_on_sigint;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    bspy_flag = &flag;
    if (sigaction(SIGINT, &sa, &old) == 0) installed = 1;
    else bspy_flag = NULL;
  }
  int st = bs_sim_take_step(s, frame_done, fs, err);
  if (installed) {
    sigaction(SIGINT, &old, NULL);
    bspy_flag = NULL;
  }
  *got_sigint = flag != 0;
  return st;
}

int bspy_scene_mode(const bs_scene *s) { return (int)s->mode; }

/* ---- terms of Python's ------------------------------------------------------ */

typedef struct bspy_term {
  void *py;
  char name[128];
} bspy_term;

static int bspy_t_value(const bs_term *t, const double *x, double *E) {
  return bspy_py_value(((const bspy_term *)t->data)->py, t, x, E);
}
static int bspy_t_gradient(const bs_term *t, const double *x, double *E, double *g) {
  return bspy_py_gradient(((const bspy_term *)t->data)->py, t, x, E, g);
}
static int bspy_t_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  return bspy_py_hessian(((const bspy_term *)t->data)->py, t, x, H);
}

static const bs_term_ops bspy_term_ops = {bspy_t_value, bspy_t_gradient, bspy_t_hessian, NULL, free, NULL, NULL, NULL,
                                          NULL, NULL};

int bspy_add_term(bs_sim *s, const char *name, void *py, int dynamic_only, int quadratic, int external,
                  bs_error *err) {
  bspy_term *d = calloc(1, sizeof *d);
  if (!d) return bs_error_set(err, BS_ENOMEM, "out of memory for the term '%s'", name);
  d->py = py;
  snprintf(d->name, sizeof d->name, "%s", name);
  bs_term *t = NULL;
  int st = bs_term_create(d->name, &bspy_term_ops, s->fem, &s->step, d, &t, err); /* frees d on failure */
  if (st) return st;
  t->dynamic_only = dynamic_only;
  t->quadratic = quadratic;
  t->external = external;
  return bs_sim_add_term(s, t, err); /* owns t from here, also on error */
}

/* H_ij += B_k for k < m (blocks row-major); -1 - k for the first block that
 * has no slot in the pattern (nothing after it added), else 0. */
int64_t bspy_bsr_add(bs_bsr *H, int64_t m, const int32_t *i, const int32_t *j, const double *B) {
  for (int64_t k = 0; k < m; k++) {
    if (i[k] < 0 || j[k] < 0 || i[k] >= H->n || j[k] >= H->n) return -1 - k;
    const int32_t slot = i[k] == j[k] ? H->diag[i[k]] : bs_bsr_slot(H, i[k], j[k]);
    if (slot < 0) return -1 - k;
    double *dst = H->val + 9 * (size_t)slot;
    for (int c = 0; c < 9; c++) dst[c] += B[9 * k + c];
  }
  return 0;
}
