"""cffi builder of bigstep._bigstep (API mode, out of line).

The extension is compiled against the installed public headers
(PREFIX/include/bigstep/bigstep.h) and linked to PREFIX/lib/libbigstep.so
with an rpath to PREFIX/lib. Only the installed API is declared below; the
structs are declared partially (``...;``) so that cffi takes their layout
from the real headers at compile time. _helpers.c (beside this file) is
compiled into the extension: the run loop with its SIGINT flag, the single
step, and the user-term trampolines.

Used by python/build.py; not imported at run time.
"""
import os

import cffi

CDEF = r"""
/* ---- base ---------------------------------------------------------------- */
#define BS_OK ...
#define BS_EIO ...
#define BS_EINPUT ...
#define BS_ENOMEM ...
#define BS_ENUMERIC ...
#define BS_EGMSH ...
#define BS_EINTERNAL ...
#define BS_MAX_PATH ...
#define BS_MAX_NAME ...
#define BS_SIM_STOPPED ...
#define BS_TERM_OK ...
#define BS_TERM_NOT_EVALUABLE ...
#define BS_FIELD_COUNT ...
#define BS_STUDY_MAX_KNOBS ...
#define BS_STUDY_MAX_QOI ...
#define BS_STUDY_KEY_LEN ...

typedef struct bs_error { int code; char msg[...]; } bs_error;
void bs_error_clear(bs_error *err);
const char *bs_status_name(int code);
const char *bs_version(void);
double bs_seconds(void);
void free(void *p);

/* ---- mesh ---------------------------------------------------------------- */
typedef struct bs_group {
  int dim; int tag; char *name;
  int32_t n_elems; int32_t *elems;
  int32_t n_vertices; int32_t *vertices;
  ...;
} bs_group;
typedef struct bs_mesh {
  int32_t n_vertices; double *x;
  int32_t n_tets; int32_t *tets; int32_t *material;
  int32_t n_faces; int32_t *faces; int32_t *face_tet; int32_t *boundary;
  int n_groups; bs_group *groups;
  int32_t n_dropped; int32_t n_coincident;
  ...;
} bs_mesh;
typedef struct bs_mesh_read_opts {
  double size; int refine; int64_t max_tets; int merge_coincident; int close_holes;
  double max_hole; double min_dihedral; double feature_angle; int surface_mesher;
  ...;
} bs_mesh_read_opts;
typedef struct bs_mesh_quality {
  double vol_min, vol_max, dihedral_min, dihedral_max, radius_ratio_min, radius_ratio_mean;
  int32_t n_inverted, n_degenerate, n_sliver;
  ...;
} bs_mesh_quality;
int bs_mesh_load(const char *spec, const bs_mesh_read_opts *opts, bs_mesh **out, bs_error *err);
int bs_mesh_create(int32_t n_vertices, const double *x, int32_t n_tets, const int32_t *tets,
                   int n_groups, const bs_group *groups, bs_mesh **out, bs_error *err);
void bs_mesh_destroy(bs_mesh **m);
void bs_mesh_quality_compute(const bs_mesh *m, const double *x, bs_mesh_quality *q);
int bs_mesh_dihedral_gate(const bs_mesh *m, double gate, const char *what, bs_error *err);
int bs_mesh_parse_mesher(const char *s, int *mesher);
int bs_mesh_check(const bs_mesh *m, bs_error *err);
double bs_mesh_volume(const bs_mesh *m);
int bs_mesh_write_msh(const bs_mesh *m, const double *x, const char *path, bs_error *err);
int bs_mesh_write_vtu(const bs_mesh *m, const void *f, const char *path, bs_error *err);

/* ---- scene --------------------------------------------------------------- */
typedef enum { BS_MODE_DYNAMIC, BS_MODE_STATIC } bs_scene_mode;
typedef struct bs_scene_qoi { char name[...]; ...; } bs_scene_qoi;
typedef struct bs_scene {
  char path[...]; char *description;
  double fps; int frames, steps_per_frame; double dt;
  bs_scene_mode mode;
  int n_bodies; int n_obstacles; int n_qoi; bs_scene_qoi *qoi;
  char out_dir[...]; int checkpoint_every;
  ...;
} bs_scene;
int bs_scene_load(const char *path, int n_sets, const char *const *sets, bs_scene **out, bs_error *err);
int bs_scene_parse(const char *json, const char *name, int n_sets, const char *const *sets, bs_scene **out,
                   bs_error *err);
void bs_scene_destroy(bs_scene **s);
int bs_scene_write_json(const bs_scene *s, char **out, bs_error *err);
int bs_scene_schema_json(char **out, bs_error *err);

/* ---- fem, matrices, terms ------------------------------------------------- */
typedef struct bs_fem { int32_t n_vertices, n_tets; ...; } bs_fem;
typedef struct bs_bsr {
  int32_t n; int64_t nnzb; int32_t *row_ptr; int32_t *col; int32_t *diag; double *val;
  ...;
} bs_bsr;
int32_t bs_bsr_slot(const bs_bsr *A, int32_t i, int32_t j);
int bs_fem_matrix(const bs_fem *fem, bs_bsr **out, bs_error *err);
void bs_bsr_destroy(bs_bsr **A);
void bs_bsr_mul(const bs_bsr *A, const uint8_t *mask, const double *x, double *y);
typedef struct bs_step_data { double dt; double time; double load; ...; } bs_step_data;
typedef struct bs_term { const char *name; int dynamic_only, expensive, quadratic, external; ...; } bs_term;

/* ---- the simulation -------------------------------------------------------- */
typedef enum { BS_MIN_CONVERGED, BS_MIN_MAX_ITER, BS_MIN_STALLED, BS_MIN_LINE_SEARCH, BS_MIN_NONFINITE,
               BS_MIN_STEPS_DONE, BS_MIN_DIVERGED, BS_MIN_FLOOR, BS_MIN_STOPPED, ... } bs_min_reason;
typedef struct bs_minimize_stats {
  int iterations, cg_iterations, indefinite_exits, fallback_neg_dx, fallback_neg_grad,
      clamps, ls_evaluations, cholmod_fallbacks;
  double alpha_min, alpha_max, grad_norm, E;
  double t_eval, t_assembly, t_linear, t_line_search, t_total;
  bs_min_reason reason;
  const char *reason_text;
  ...;
} bs_minimize_stats;
typedef struct bs_step_stats { bs_minimize_stats min; int guess; int failed; double seconds; ...; } bs_step_stats;
typedef struct bs_sim_step { bs_step_stats st; double time; int32_t inverted; char reason[...]; } bs_sim_step;
typedef struct bs_frame_stats {
  int frame; double time; int n_steps; const bs_sim_step *steps;
  long iterations, cg_iterations, failed; double seconds; double grad_max;
  ...;
} bs_frame_stats;
typedef struct bs_run_totals {
  long steps, failed, iterations, cg, ls, indefinite, fb_dx, fb_grad, clamps, chol_fb, downhill, floor;
  double seconds, max_grad;
  int first_fail_frame, first_fail_step;
  char first_fail_reason[...];
} bs_run_totals;
typedef struct bs_sim {
  const bs_scene *scene; bs_mesh *mesh; int n_bodies; int32_t *vertex_offset;
  double *x0; double size; double memory_bytes; double *x, *v; uint8_t *mask; int32_t n_free;
  bs_fem *fem; int n_terms; bs_step_data step; int frame; int substep; double time; bs_sim_step *steps;
  ...;
} bs_sim;
typedef struct bs_sim_measures {
  double kinetic, elastic, gravity, total; int32_t inverted; double min_detF;
  int32_t penetrating; double max_depth; int64_t self_intersections;
  ...;
} bs_sim_measures;
int bs_sim_create(const bs_scene *scene, bs_sim **out, bs_error *err);
void bs_sim_destroy(bs_sim **s);
int bs_sim_restore(bs_sim *s, int frame, const double *x, const double *v, bs_error *err);
void bs_sim_measure(const bs_sim *s, int intersections, bs_sim_measures *m);
long bs_sim_dofs(const bs_sim *s);
void bs_run_totals_add(bs_run_totals *T, const bs_frame_stats *fs);
void bs_frame_sums(int frame, double time, int n, const bs_sim_step *steps, bs_frame_stats *fs);
const char *bs_min_reason_name(bs_min_reason r);
const char *bs_guess_name(int g);

/* fields, QoIs */
typedef struct bs_fields {
  uint32_t set; int32_t n_vertices, n_tets;
  uint8_t *scripted; int32_t *point_body; int32_t *cell_body, *material;
  double *J; uint8_t *inverted; double *P, *cauchy, *green; double *von_mises, *psi; double *stretch;
  double *f_elastic, *f_contact; double *friction;
  ...;
} bs_fields;
int bs_fields_create(const bs_sim *s, uint32_t set, bs_fields **out, bs_error *err);
void bs_fields_destroy(bs_fields **f);
void bs_fields_compute(bs_fields *f, const bs_sim *s);
const char *bs_field_name(int f);
int bs_fields_parse_names(int n, const char *const *names, uint32_t *set, bs_error *err);
typedef struct bs_qoi bs_qoi;
int bs_qoi_create(const bs_sim *s, bs_qoi **out, bs_error *err);
int bs_qoi_eval(bs_qoi *q, const bs_sim *s, double *values, bs_error *err);
void bs_qoi_destroy(bs_qoi **q);

/* ---- run folders ----------------------------------------------------------- */
typedef struct bs_runfolder bs_runfolder;
typedef struct bs_runfolder_opts { int replace; const char *command_line; 
  ...;
} bs_runfolder_opts;
int bs_runfolder_open(const char *dir, const bs_sim *s, const bs_runfolder_opts *opts, bs_runfolder **out,
                      bs_error *err);
void bs_runfolder_destroy(bs_runfolder **rf);
int bs_runfolder_write(bs_runfolder *rf, const bs_sim *s, const bs_frame_stats *fs, const bs_sim_measures *m,
                       bs_error *err);
int bs_runfolder_checkpoint(bs_runfolder *rf, const bs_sim *s, bs_error *err);

/* ---- studies ----------------------------------------------------------------- */
typedef enum { BS_GCI_OK, BS_GCI_OSCILLATORY, BS_GCI_DIVERGENT, BS_GCI_CONVERGED, BS_GCI_NO_ORDER,
               BS_GCI_BAD_INPUT } bs_gci_status;
typedef struct bs_gci { bs_gci_status status; double p, extrapolated, e_a, e_ext, gci_fine, gci_coarse, asymptotic; 
  ...;
} bs_gci;
const char *bs_gci_status_name(bs_gci_status s);
bs_gci_status bs_study_gci(const double h[3], const double f[3], bs_gci *g);
typedef enum { BS_KNOB_STEPS_PER_FRAME, BS_KNOB_TOLERANCE, BS_KNOB_REFINE, BS_KNOB_METHOD, BS_KNOB_DT,
               BS_KNOB_FPS, BS_KNOB_OTHER } bs_knob_kind;
typedef struct bs_study_knob {
  char key[...]; char path[...]; bs_knob_kind kind; int body; int n; char **vals; double *num; int finest;
} bs_study_knob;
int bs_study_knob_parse(const char *spec, bs_study_knob *k, bs_error *err);
void bs_study_knob_free(bs_study_knob *k);
int bs_study_knob_same(const bs_study_knob *a, const bs_study_knob *b);
int bs_study_knob_is_time(const bs_study_knob *k);
typedef struct bs_study_run {
  int idx[...]; char name[...], dir[...]; int n_sets; char **sets;
  int frames, spf, is_static; double fps; char method[...];
  int exit_code; int timed_out; long maxrss_kib; double wall;
  int complete, is_ref, pareto, n_rows, inv_max;
  long newton, cg, failed_steps;
  double s_per_frame, newton_per_step, cg_per_step, peak_mib;
  double pos_max, pos_last, vel_max, vel_last, drift, pen_max;
  double q_last[...]; double q_err_last[...]; double q_err_max[...];
  ...;
} bs_study_run;
const char *bs_study_run_status(const bs_study_run *r);
typedef struct bs_study_opts {
  const char *scene; int n_sets; const char *const *sets; int n_knobs; const bs_study_knob *knobs;
  const char *reference; const char *out; int n_qoi; const char *const *qoi;
  ...;
} bs_study_opts;
typedef struct bs_study {
  char scene_path[...], name[...], out[...]; char ref_dir[...];
  int n_knobs; bs_study_knob knobs[...]; int n_bodies; int n_runs; bs_study_run *runs; int ref;
  double size; int n_qoi; char qoi[16][256];
  ...;
} bs_study;
int bs_study_create(const bs_study_opts *o, bs_study **out, bs_error *err);
void bs_study_destroy(bs_study **S);
int bs_study_check_bodies(const bs_study *S, bs_error *err);
int bs_study_plan(bs_study *S, bs_error *err);
int bs_study_measure_bodies(bs_study *S, bs_error *err);
int bs_study_run_key(const bs_study *S, const bs_study_run *r, char key[], bs_error *err);
int bs_study_run_complete(const bs_study_run *r);
int bs_study_evaluate(bs_study *S);
int bs_study_csv_write(const bs_study *S, bs_error *err);
int bs_study_plots_write(const bs_study *S, bs_error *err);
bs_gci_status bs_study_qoi_gci(const bs_study *S, int k, const char *method, int q, bs_gci *g, int used[3],
                               int *n_skipped);
double bs_study_knob_h(const bs_study *S, const bs_study_run *r, int k);
int bs_study_methods(const bs_study *S, const char **names, int max);
int bs_mkdir_p(const char *dir, bs_error *err);

/* ---- _helpers.c ---------------------------------------------------------------- */
typedef struct bspy_run {
  bs_runfolder *folder; void *py; int last_frame; int stop_reason; int measured_frame;
  bs_sim_measures last_m;
  ...;
} bspy_run;
int bspy_run_sim(bs_sim *s, bspy_run *r, int resume, bs_run_totals *T, int catch_sigint, bs_error *err);
int bspy_finish(bspy_run *r, const bs_sim *s, const bs_run_totals *T, int stopped, double wall, bs_error *err);
double bspy_folder_wall(bspy_run *r);
int bspy_step_sig(bs_sim *s, int catch_sigint, int *got_sigint, int *frame_done, bs_frame_stats *fs, bs_error *err);
int bspy_add_term(bs_sim *s, const char *name, void *py, int dynamic_only, int quadratic, int external,
                  bs_error *err);
int64_t bspy_bsr_add(bs_bsr *H, int64_t m, const int32_t *i, const int32_t *j, const double *B);
int bspy_scene_mode(const bs_scene *s);

extern "Python" int bspy_py_frame(const bs_sim *, const bs_frame_stats *, void *);
extern "Python" int bspy_py_value(void *, const bs_term *, const double *, double *);
extern "Python" int bspy_py_gradient(void *, const bs_term *, const double *, double *, double *);
extern "Python" int bspy_py_hessian(void *, const bs_term *, const double *, bs_bsr *);
"""

HERE = os.path.dirname(os.path.abspath(__file__))


def make_ffi(prefix):
    """The FFI builder for the library installed under `prefix`."""
    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    with open(os.path.join(HERE, "_helpers.c")) as f:
        helpers = f.read()
    inc = os.path.join(prefix, "include")
    lib = os.path.join(prefix, "lib")
    ffi.set_source(
        "bigstep._bigstep",
        '#include <bigstep/bigstep.h>\n' + helpers,
        include_dirs=[inc],
        library_dirs=[lib],
        runtime_library_dirs=[lib],
        libraries=["bigstep"],
        extra_compile_args=["-std=gnu11", "-O2", "-Wno-unused-parameter"],
    )
    return ffi
