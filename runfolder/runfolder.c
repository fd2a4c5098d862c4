/* runfolder.c — writing a run folder: frames.csv, stats.csv, state.bin,
 * the VTU frames and their PVD collection (formats: bs_runfolder.h). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_fields.h"
#include "bs_obstacle_output.h"
#include "bs_qoi.h"
#include "outfile.h"
#include "runfolder_internal.h"

/* state.bin's header (bs_runfolder.h). */
static int write_state_header(bs_outfile *f, int32_t n, bs_error *err) {
  uint32_t version = BS_STATE_VERSION;
  int32_t hdr[2] = {n, 0};
  bs_outfile_write(f, "BSST", 1, 4);
  bs_outfile_write(f, &version, 4, 1);
  bs_outfile_write(f, hdr, 4, 2);
  return bs_outfile_flush(f, err);
}

int bs_runfolder_create(const char *dir, const bs_sim *s, bs_runfolder **out, bs_error *err) {
  return bs_runfolder_open(dir, s, NULL, out, err);
}

/* frames.csv and stats.csv (output.stats), new with their headers or, append,
 * opened at their end. */
int bs__runfolder_rows_open(bs_runfolder *rf, int append, bs_error *err) {
  const bs_scene *sc = rf->run.scene;
  int st = 0;
  if (append) {
    if (sc->stats_csv) st = bs_outfile_open(&rf->stats, rf->dir, "stats.csv", "ab", err);
    return st ? st : bs_outfile_open(&rf->frames, rf->dir, "frames.csv", "ab", err);
  }
  if (sc->stats_csv && !(st = bs_outfile_open(&rf->stats, rf->dir, "stats.csv", "w", err))) {
    bs_outfile_printf(&rf->stats, "%s\n", BS_STATS_CSV_HEADER);
    st = bs_outfile_flush(&rf->stats, err);
  }
  if (!st && !(st = bs_outfile_open(&rf->frames, rf->dir, "frames.csv", "w", err))) {
    bs_outfile_printf(&rf->frames, "%s\n", BS_FRAMES_CSV_HEADER);
    st = bs_outfile_flush(&rf->frames, err);
  }
  return st;
}

/* state.bin (output.states), new with its header or, append, at its end. */
static int open_state(bs_runfolder *rf, const bs_sim *s, int append, bs_error *err) {
  if (!s->scene->states) return 0;
  rf->n_state = s->mesh->n_vertices;
  if (append) return bs_outfile_open(&rf->state, rf->dir, "state.bin", "ab", err);
  return bs_runfolder_state_open(rf, s->mesh->n_vertices, err);
}

int bs_runfolder_state_open(bs_runfolder *rf, int32_t n_vertices, bs_error *err) {
  rf->n_state = n_vertices;
  int st = bs_outfile_open(&rf->state, rf->dir, "state.bin", "wb", err);
  return st ? st : write_state_header(&rf->state, n_vertices, err);
}

/* qoi.csv (new with its header, or append) and the quantities resolved on s (bs_qoi.h). */
static int open_qoi(bs_runfolder *rf, const bs_sim *s, int append, bs_error *err) {
  int st = bs_qoi_create(s, &rf->qoi, err);
  if (!st && !(rf->qoi_values = calloc((size_t)s->scene->n_qoi, sizeof(double))))
    st = bs_error_set(err, BS_ENOMEM, "out of memory");
  if (!st) st = bs_outfile_open(&rf->qoi_csv, rf->dir, "qoi.csv", append ? "ab" : "w", err);
  if (st || append) return st;
  bs_outfile_printf(&rf->qoi_csv, "frame,time");
  for (int i = 0; i < s->scene->n_qoi; i++) bs_outfile_printf(&rf->qoi_csv, ",%s", s->scene->qoi[i].name);
  bs_outfile_printf(&rf->qoi_csv, "\n");
  return bs_outfile_flush(&rf->qoi_csv, err);
}

/* The frame's row of qoi.csv (format: bs_runfolder.h). */
static int write_qoi_row(bs_runfolder *rf, const bs_sim *s, int frame, bs_error *err) {
  int st = bs_qoi_eval(rf->qoi, s, rf->qoi_values, err);
  if (st) return st;
  bs_outfile_printf(&rf->qoi_csv, "%d,%.17g", frame, s->time);
  for (int i = 0; i < s->scene->n_qoi; i++) bs_outfile_printf(&rf->qoi_csv, ",%.17g", rf->qoi_values[i]);
  bs_outfile_printf(&rf->qoi_csv, "\n");
  return bs_outfile_flush(&rf->qoi_csv, err);
}

bs_runfolder_run bs__runfolder_run_of(const bs_sim *s) {
  const bs_runfolder_run run = {.scene = s->scene, .dofs = bs_sim_dofs(s), .obstacles = s->obstacles != NULL};
  return run;
}

int bs__runfolder_begin(const char *dir, const bs_runfolder_run *run, bs_runfolder **out, bs_error *err) {
  *out = NULL;
  if (strlen(dir) >= BS_MAX_PATH) return bs_error_set(err, BS_EINPUT, "output folder name too long: '%s'", dir);
  bs_runfolder *rf = calloc(1, sizeof *rf);
  if (!rf) return bs_error_set(err, BS_ENOMEM, "out of memory");
  rf->lock_fd = -1;
  rf->run = *run;
  snprintf(rf->dir, sizeof rf->dir, "%s", dir);
  rf->t_open = bs_seconds();
  char *id = NULL;
  int st = bs__scene_identity(run->scene, &id, err);
  if (!st) rf->scene_hash = bs_fnv1a(BS_FNV_SEED, id, strlen(id));
  free(id);
  if (!st && run->scene->checkpoint_every < 0)
    st = bs_error_set(err, BS_EINPUT, "output.checkpoint_every: must be an integer in [0, 1000000], got %d",
                      run->scene->checkpoint_every);
  if (!st) st = bs_mkdir_p(dir, err);
  if (!st) st = bs_runfolder_lock(dir, &rf->lock_fd, err);
  if (st) bs_runfolder_destroy(&rf);
  *out = rf;
  return st;
}

int bs__runfolder_outputs(bs_runfolder *rf, const bs_sim *s, int append, bs_error *err) {
  int st = open_state(rf, s, append, err);
  if (!st && s->scene->vtu_every > 0) st = bs_fields_create(s, s->scene->out_fields, &rf->fields, err);
  if (!st && s->scene->vtu_every > 0) st = bs_obstacle_output_create(rf->dir, s, &rf->obstacles, err);
  if (!st && s->scene->n_qoi > 0) st = open_qoi(rf, s, append, err);
  return st;
}

int bs_runfolder_open_run(const char *dir, const bs_runfolder_run *run, const bs_runfolder_opts *o,
                          bs_runfolder **out, bs_error *err) {
  const bs_runfolder_opts none = {0};
  if (!o) o = &none;
  bs_runfolder *rf = NULL;
  int st = bs__runfolder_begin(dir, run, &rf, err);
  if (!st) st = bs_runfolder_prepare(dir, o->replace, NULL, err);
  if (!st) st = bs_runfolder_write_record(dir, o->command_line, err);
  char p[BS_MAX_PATH + 16];
  snprintf(p, sizeof p, "%s/scene.json", dir);
  if (!st) st = bs_scene_write_json_file(run->scene, p, err);
  if (!st) st = bs__runfolder_rows_open(rf, 0, err);
  if (st) bs_runfolder_destroy(&rf);
  *out = rf;
  return st;
}

int bs_runfolder_open(const char *dir, const bs_sim *s, const bs_runfolder_opts *o, bs_runfolder **out,
                      bs_error *err) {
  const bs_runfolder_run run = bs__runfolder_run_of(s);
  int st = bs_runfolder_open_run(dir, &run, o, out, err);
  if (!st && (st = bs__runfolder_outputs(*out, s, 0, err))) bs_runfolder_destroy(out);
  return st;
}

static int write_stats_rows(bs_outfile *f, const bs_frame_stats *fs, bs_error *err) {
  for (int k = 0; k < fs->n_steps; k++) {
    const bs_step_stats *st = &fs->steps[k].st;
    bs_outfile_printf(f, "%d,%d,%.9g,%d,%d,%d,%d,%d,%d,%d,%d,%d,%.6g,%.6g,%.6e,%.9e,%s,%d,%.6f,%.6f,%.6f,%.6f,%.6f\n",
                      fs->frame, k, fs->steps[k].time, st->guess, st->min.iterations, st->min.cg_iterations,
                      st->min.ls_evaluations, st->min.indefinite_exits, st->min.fallback_neg_dx,
                      st->min.fallback_neg_grad, st->min.clamps, st->min.cholmod_fallbacks, st->min.alpha_min,
                      st->min.alpha_max, st->min.grad_norm, st->min.E, st->min.reason_text ? st->min.reason_text : "",
                      fs->steps[k].inverted, st->min.t_eval, st->min.t_assembly, st->min.t_linear,
                      st->min.t_line_search, st->seconds);
  }
  return bs_outfile_flush(f, err);
}

int bs_frames_csv_row(char *buf, size_t n, double time, const bs_frame_stats *fs, const bs_sim_measures *m) {
  long ccd = 0; /* line searches of the frame bounded by the CCD (barrier contact) */
  for (int k = 0; k < fs->n_steps && fs->steps; k++) ccd += fs->steps[k].st.min.ccd_limited;
  return snprintf(buf, n, "%d,%.9g,%.12e,%.12e,%.12e,%.12e,%d,%.6e,%ld,%ld,%ld,%.6f,%d,%.6e,%lld,%.6e,%lld,%ld,%.6e,%.6e\n",
                  fs->frame, time, m->kinetic, m->elastic, m->gravity, m->total, m->inverted, m->min_detF,
                  fs->iterations, fs->cg_iterations, fs->failed, fs->seconds, m->penetrating, m->max_depth,
                  (long long)m->self_intersections, m->contact_min_distance, (long long)m->contact_pairs, ccd,
                  m->kappa, m->obstacle_min_distance);
}

int bs_runfolder_rows(bs_runfolder *rf, double time, const bs_frame_stats *fs, const bs_sim_measures *m,
                      bs_error *err) {
  int st = rf->stats.f ? write_stats_rows(&rf->stats, fs, err) : 0;
  if (st) return st;
  char row[512];
  bs_frames_csv_row(row, sizeof row, time, fs, m);
  bs_outfile_printf(&rf->frames, "%s", row);
  return bs_outfile_flush(&rf->frames, err);
}

int bs_runfolder_state(bs_runfolder *rf, double time, const double *x, const double *v, bs_error *err) {
  if (!rf->state.f) return 0;
  size_t n3 = 3 * (size_t)rf->n_state;
  bs_outfile_write(&rf->state, &time, sizeof(double), 1);
  bs_outfile_write(&rf->state, x, sizeof(double), n3);
  bs_outfile_write(&rf->state, v, sizeof(double), n3);
  return bs_outfile_flush(&rf->state, err);
}

/* frames.pvd of the frames written so far, through a temporary file renamed
 * over the old one: the collection is valid after every frame. */
int bs__runfolder_write_pvd(const bs_runfolder *rf, bs_error *err) {
  char p[BS_MAX_PATH + 64], tmp[BS_MAX_PATH + 72];
  snprintf(p, sizeof p, "%s/frames.pvd", rf->dir);
  bs_tmp_path(tmp, sizeof tmp, p);
  int st = bs_pvd_write(tmp, rf->n_vtu, rf->vtu_times, (const char *const *)rf->vtu_names, err);
  return st ? st : bs_tmp_commit(tmp, p, err);
}

int bs__runfolder_add_vtu(bs_runfolder *rf, const char *name, double t, bs_error *err) {
  if (rf->n_vtu == rf->cap_vtu) {
    int cap = rf->cap_vtu ? 2 * rf->cap_vtu : 64;
    char **nn = realloc(rf->vtu_names, sizeof(char *) * (size_t)cap);
    if (nn) rf->vtu_names = nn;
    double *tt = nn ? realloc(rf->vtu_times, sizeof(double) * (size_t)cap) : NULL;
    if (!nn || !tt) return bs_error_set(err, BS_ENOMEM, "out of memory");
    rf->vtu_times = tt;
    rf->cap_vtu = cap;
  }
  if (!(rf->vtu_names[rf->n_vtu] = strdup(name))) return bs_error_set(err, BS_ENOMEM, "out of memory");
  rf->vtu_times[rf->n_vtu++] = t;
  return 0;
}

static int write_vtu(bs_runfolder *rf, const bs_sim *s, int frame, bs_error *err) {
  char path[BS_MAX_PATH + 64], tmp[BS_MAX_PATH + 72], name[64];
  snprintf(name, sizeof name, "frame_%05d.vtu", frame);
  snprintf(path, sizeof path, "%s/%s", rf->dir, name);
  bs_tmp_path(tmp, sizeof tmp, path);
  int st = bs_fields_write_vtu(rf->fields, s, tmp, err);
  if (!st) st = bs_tmp_commit(tmp, path, err);
  if (!st) st = bs_obstacle_output_frame(rf->obstacles, s, frame, err);
  return st ? st : bs_runfolder_add_frame_file(rf, name, s->time, err);
}

int bs_runfolder_add_frame_file(bs_runfolder *rf, const char *name, double t, bs_error *err) {
  int st = bs__runfolder_add_vtu(rf, name, t, err);
  return st ? st : bs__runfolder_write_pvd(rf, err);
}

int bs_runfolder_frame(const bs_sim *s, const bs_frame_stats *fs, void *ctx, bs_error *err) {
  bs_sim_measures m;
  bs_sim_measure(s, 1, &m);
  return bs_runfolder_write(ctx, s, fs, &m, err);
}

void bs_runfolder_summary(const bs_runfolder *rf, int frames, const bs_run_totals *T, const bs_sim_measures *m,
                          bs_summary *out) {
  const bs_runfolder_run *r = &rf->run;
  bs_summary_make_run(r->scene, frames, r->dofs, r->obstacles, T, bs_runfolder_wall(rf), m, out);
}

int bs_runfolder_frame_done(bs_runfolder *rf, const bs_frame_stats *fs, int frames, const bs_sim_measures *m,
                            bs_error *err) {
  bs_run_totals_add(&rf->totals, fs);
  bs_summary u;
  char text[2048];
  bs_runfolder_summary(rf, frames, &rf->totals, m, &u);
  u.partial = BS_SUMMARY_RUNNING;
  bs_summary_format(&u, text, sizeof text);
  return bs_outfile_replace_text(rf->dir, "summary.txt", text, err);
}

int bs_runfolder_write(bs_runfolder *rf, const bs_sim *s, const bs_frame_stats *fs, const bs_sim_measures *m,
                       bs_error *err) {
  int st = bs_runfolder_rows(rf, s->time, fs, m, err);
  if (!st) st = bs_runfolder_state(rf, s->time, s->x, s->v, err);
  if (!st && rf->qoi_csv.f) st = write_qoi_row(rf, s, fs->frame, err);
  const int every = s->scene->vtu_every;
  if (!st && every > 0 && (fs->frame % every == 0 || s->scene->mode == BS_MODE_STATIC))
    st = write_vtu(rf, s, fs->frame, err);
  if (st) bs_run_totals_add(&rf->totals, fs);
  else st = bs_runfolder_frame_done(rf, fs, s->frame, m, err);
  const int ck = s->scene->checkpoint_every;
  if (!st && ck > 0 && s->scene->mode == BS_MODE_DYNAMIC && (fs->frame % ck == 0 || fs->frame == s->scene->frames))
    st = bs_runfolder_checkpoint(rf, s, err);
  return st;
}

int bs_runfolder_checkpoint(bs_runfolder *rf, const bs_sim *s, bs_error *err) {
  if (s->scene->mode != BS_MODE_DYNAMIC) return 0;
  return bs_checkpoint_write(rf->dir, s, &rf->totals, bs_runfolder_wall(rf), rf->scene_hash, err);
}

double bs_runfolder_wall(const bs_runfolder *rf) { return bs_seconds() - rf->t_open; }

int bs_runfolder_finish(bs_runfolder *rf, const char *summary, bs_error *err) {
  int st = summary ? bs_outfile_replace_text(rf->dir, "summary.txt", summary, err) : 0;
  bs_outfile *files[] = {&rf->frames, &rf->stats, &rf->state, &rf->qoi_csv};
  for (int i = 0; i < 4; i++) {
    int c = bs_outfile_close(files[i], st ? NULL : err);
    if (!st) st = c;
  }
  return st;
}

void bs_runfolder_destroy(bs_runfolder **prf) {
  if (!prf || !*prf) return;
  bs_runfolder *rf = *prf;
  bs_outfile_abandon(&rf->frames);
  bs_outfile_abandon(&rf->stats);
  bs_outfile_abandon(&rf->state);
  bs_fields_destroy(&rf->fields);
  bs_obstacle_output_destroy(&rf->obstacles);
  for (int i = 0; i < rf->n_vtu; i++) free(rf->vtu_names[i]);
  free(rf->vtu_names);
  free(rf->vtu_times);
  bs_outfile_abandon(&rf->qoi_csv);
  bs_qoi_destroy(&rf->qoi);
  free(rf->qoi_values);
  bs_runfolder_unlock(&rf->lock_fd);
  free(rf);
  *prf = NULL;
}
