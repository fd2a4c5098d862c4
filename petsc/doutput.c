/* doutput.c — a petsc-backend run's output folder: rank 0 writes the files
 * every backend writes through runfolder/ (bs_runfolder_open_run: the lock,
 * run.txt, scene.json, frames.csv, stats.csv, frames.pvd, summary.txt;
 * state.bin of the gathered state; the obstacles' files) and the PVTU files;
 * every rank writes its VTU piece (bs_doutput.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bs_dist.h"
#include "bs_doutput.h"
#include "bs_obstacle_output.h"
#include "bs_runfolder.h"
#include "outfile.h"

struct bs_dout {
  char dir[BS_MAX_PATH];
  bs_runfolder *rf;      /* rank 0: the run folder's shared files */
  bs_obstacle_output *obstacles; /* rank 0, with VTU frames: the obstacles' files */
  double *xg, *vg;       /* rank 0, with output.states: the state in the source mesh's order */
  double *vm;            /* work: 3 per local-mesh vertex */
  int32_t *rank_cells;   /* per owned cell: this rank */
};

/* rc on every rank: the worst (most negative) status, with rank 0's
 * message when rank 0 failed (it writes most files), else a message naming
 * the failure on another rank. */
static int agree(int rc, bs_error *err) {
  int worst = rc, root = rc;
  MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Bcast(&root, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!worst) return BS_OK;
  char msg[BS_ERROR_MSG] = "";
  if (bs_dist_rank() == 0 && err) snprintf(msg, sizeof msg, "%s", err->msg);
  MPI_Bcast(msg, (int)sizeof msg, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (root && bs_dist_rank() != 0) bs_error_set(err, root, "%s", msg);
  else if (!rc) bs_error_set(err, worst, "another rank could not write its output");
  return root ? root : worst;
}

/* Rank 0's writer of the obstacles' files beside the VTU frames, over the
 * rest box of every rank's vertices (collective). */
static int open_obstacles(bs_dout *o, const bs_dsim *d, bs_error *err) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t v = 0; v < d->mesh->n_vertices; v++)
    for (int k = 0; k < 3; k++)
      lo[k] = fmin(lo[k], d->mesh->x[3 * v + k]), hi[k] = fmax(hi[k], d->mesh->x[3 * v + k]);
  MPI_Allreduce(MPI_IN_PLACE, lo, 3, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, hi, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (bs_dist_rank() != 0 || d->scene->vtu_every <= 0) return BS_OK;
  return bs_obstacle_output_create_for(o->dir, d->obstacles, lo, hi, d->scene->out_compress, &o->obstacles, err);
}

/* Rank 0: state.bin and the arrays its records are gathered into. */
static int open_state(bs_dout *o, const bs_dsim *d, bs_error *err) {
  const int64_t n = d->mesh->n_global_vertices;
  if (n > INT32_MAX / 7) return bs_error_set(err, BS_EINPUT, "state.bin: %lld vertices are too many", (long long)n);
  if (bs_dist_rank() != 0) return BS_OK;
  o->xg = bs_calloc(3 * (size_t)n + 3, sizeof *o->xg, "the gathered positions", err);
  o->vg = bs_calloc(3 * (size_t)n + 3, sizeof *o->vg, "the gathered velocities", err);
  if (!o->xg || !o->vg) return BS_ENOMEM;
  return bs_runfolder_state_open(o->rf, (int32_t)n, err);
}

/* Rank 0: the records of every rank's owned vertices (7 doubles each: the
 * source mesh's index, x, v) into xg, vg; every vertex exactly once. */
static int unpack_state(bs_dout *o, const bs_dsim *d, const double *rec, int n, bs_error *err) {
  const int64_t N = d->mesh->n_global_vertices;
  int64_t got = 0;
  for (int i = 0; i < n; i++, rec += 7) {
    int64_t id = (int64_t)rec[0];
    if (id < 0 || id >= N)
      return bs_error_set(err, BS_EINTERNAL, "state.bin: a vertex without its source index (%lld)", (long long)id);
    memcpy(o->xg + 3 * id, rec + 1, 3 * sizeof(double));
    memcpy(o->vg + 3 * id, rec + 4, 3 * sizeof(double));
    got++;
  }
  if (got != N)
    return bs_error_set(err, BS_EINTERNAL, "state.bin: %lld owned vertices of %lld", (long long)got, (long long)N);
  return BS_OK;
}

/* The frame's state.bin record: the owned vertices gathered to rank 0 in
 * the source mesh's order (the serial run's: bs_dsim_check_output). */
static int write_state(bs_dout *o, const bs_dsim *d, bs_error *err) {
  const bs_dmesh *m = d->mesh;
  const int root = bs_dist_rank() == 0, size = bs_dist_size();
  int n = 0, rc = BS_OK;
  double *mine = bs_calloc(7 * (size_t)m->n_owned + 1, sizeof *mine, "state records", err);
  int *counts = root ? bs_calloc((size_t)size, 2 * sizeof *counts, "state counts", err) : NULL;
  double *all = root ? bs_calloc(7 * (size_t)m->n_global_vertices + 1, sizeof *all, "state records", err) : NULL;
  if (!mine || (root && (!counts || !all))) rc = BS_ENOMEM;
  for (int32_t v = 0; !rc && v < m->n_vertices; v++) {
    if (!m->owned[v]) continue;
    mine[7 * n] = (double)m->orig_id[v];
    memcpy(mine + 7 * n + 1, d->x + 3 * (size_t)v, 3 * sizeof(double));
    memcpy(mine + 7 * n + 4, d->v + 3 * (size_t)v, 3 * sizeof(double));
    n++;
  }
  int len = 7 * n;
  if (!(rc = agree(rc, err))) MPI_Gather(&len, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
  for (int r = 1; !rc && root && r < size; r++) counts[size + r] = counts[size + r - 1] + counts[r - 1];
  if (!rc)
    MPI_Gatherv(mine, len, MPI_DOUBLE, all, counts, counts ? counts + size : NULL, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (!rc && root) rc = unpack_state(o, d, all, (counts[2 * size - 1] + counts[size - 1]) / 7, err);
  if (!rc && root) rc = bs_runfolder_state(o->rf, d->time, o->xg, o->vg, err);
  free(mine), free(counts), free(all);
  return agree(rc, err); /* every rank gets here */
}

int bs_dout_open(const bs_dsim *d, const char *dir, const bs_runfolder_opts *opts, bs_dout **out,
                 bs_error *err) {
  *out = NULL;
  int rc = bs_dsim_check_output(d->scene, 0, err); /* the same on every rank */
  if (rc) return rc;
  bs_dout *o = bs_calloc(1, sizeof *o, "output", err);
  rc = o ? BS_OK : BS_ENOMEM;
  if (o) {
    snprintf(o->dir, sizeof o->dir, "%s", dir);
    o->vm = bs_calloc(3 * (size_t)d->mesh->local->n_vertices + 3, sizeof *o->vm, "output vectors", err);
    o->rank_cells = bs_calloc((size_t)d->mesh->local->n_tets + 1, sizeof *o->rank_cells, "output cells", err);
    if (!o->vm || !o->rank_cells) rc = BS_ENOMEM;
    for (int32_t t = 0; !rc && t < d->mesh->local->n_tets; t++) o->rank_cells[t] = bs_dist_rank();
  }
  const bs_runfolder_run run = {.scene = d->scene, .dofs = bs_dsim_dofs(d), .obstacles = d->obstacles != NULL};
  if (!rc && bs_dist_rank() == 0) rc = bs_runfolder_open_run(dir, &run, opts, &o->rf, err);
  if ((rc = agree(rc, err)) == BS_OK) rc = agree(open_obstacles(o, d, err), err);
  if (!rc && d->scene->states) rc = agree(open_state(o, d, err), err);
  if (rc) bs_dout_destroy(&o);
  *out = o;
  return rc;
}

void bs_dout_destroy(bs_dout **op) {
  if (!op || !*op) return;
  bs_dout *o = *op;
  bs_obstacle_output_destroy(&o->obstacles);
  bs_runfolder_destroy(&o->rf);
  free(o->vm), free(o->rank_cells), free(o->xg), free(o->vg);
  free(o);
  *op = NULL;
}

int bs_dsim_measure(bs_dsim *d, bs_sim_measures *m, bs_error *err) {
  double *vm = bs_calloc(3 * (size_t)d->mesh->local->n_vertices + 3, sizeof *vm, "velocities", err);
  if (!vm) return BS_ENOMEM;
  bs_dfem_mesh_vector(d->df, d->x, d->xm);
  bs_dfem_mesh_vector(d->df, d->v, vm);
  bs_measure_state(d->df->fem, d->xm, vm, d->scene->gravity, m);
  free(vm);
  double s[5] = {m->kinetic, m->elastic, m->gravity, m->total, m->inverted};
  int rc = bs_dist_sum(s, 5, err);
  double mn = -m->min_detF;
  if (!rc) rc = bs_dist_max(&mn, 1, err);
  m->kinetic = s[0], m->elastic = s[1], m->gravity = s[2], m->total = s[3], m->inverted = (int32_t)s[4];
  m->min_detF = -mn;
  int64_t pen = 0;
  if (!rc) rc = bs_dsim_penetration(d, &pen, &m->max_depth, err);
  m->penetrating = (int32_t)pen;
  return rc;
}

/* This rank's piece of frame f, through NAME.tmp renamed over it. */
static int write_piece(bs_dout *o, bs_dsim *d, int f, bs_error *err) {
  char p[BS_MAX_PATH + 64], tmp[BS_MAX_PATH + 72];
  snprintf(p, sizeof p, "%s/frame_%05d_p%04d.vtu", o->dir, f, bs_dist_rank());
  bs_tmp_path(tmp, sizeof tmp, p);
  bs_dfem_mesh_vector(d->df, d->x, d->xm);
  bs_dfem_mesh_vector(d->df, d->v, o->vm);
  bs_vtu_data rank = {"rank", BS_VTU_INT32, 1, o->rank_cells};
  bs_vtu_fields fl = {.x = d->xm, .velocity = o->vm, .n_cell_data = 1, .cell_data = &rank,
                      .compress = d->scene->out_compress};
  int rc = bs_mesh_write_vtu(d->mesh->local, &fl, tmp, err);
  return rc ? rc : bs_tmp_commit(tmp, p, err);
}

/* Rank 0: frame f's PVTU over every rank's piece (through NAME.tmp), listed
 * in frames.pvd (bs_runfolder_add_frame_file). */
static int write_pvtu(bs_dout *o, int f, double time, bs_error *err) {
  static const bs_pvtu_array pa[] = {{"displacement", BS_VTU_FLOAT64, 3}, {"velocity", BS_VTU_FLOAT64, 3}};
  static const bs_pvtu_array ca[] = {{"material", BS_VTU_INT32, 1}, {"detF", BS_VTU_FLOAT64, 1},
                                     {"inverted", BS_VTU_UINT8, 1}, {"rank", BS_VTU_INT32, 1}};
  int n = bs_dist_size(), rc = BS_OK;
  char **pieces = calloc((size_t)n, sizeof *pieces), name[64], p[BS_MAX_PATH + 64], tmp[BS_MAX_PATH + 72];
  for (int r = 0; pieces && r < n && !rc; r++)
    if (!(pieces[r] = malloc(64))) rc = BS_ENOMEM;
    else snprintf(pieces[r], 64, "frame_%05d_p%04d.vtu", f, r);
  if (!pieces || rc) rc = bs_error_set(err, BS_ENOMEM, "out of memory writing frame %d", f);
  snprintf(name, sizeof name, "frame_%05d.pvtu", f);
  snprintf(p, sizeof p, "%s/%s", o->dir, name);
  bs_tmp_path(tmp, sizeof tmp, p);
  if (!rc) rc = bs_pvtu_write(tmp, 2, pa, 4, ca, n, (const char *const *)pieces, err);
  for (int r = 0; pieces && r < n; r++) free(pieces[r]);
  free(pieces);
  if (!rc) rc = bs_tmp_commit(tmp, p, err);
  if (!rc) rc = bs_obstacle_output_frame_at(o->obstacles, time, f, err);
  return rc ? rc : bs_runfolder_add_frame_file(o->rf, name, time, err);
}

int bs_dout_frame(bs_dout *o, bs_dsim *d, const bs_frame_stats *fs, bs_error *err) {
  bs_sim_measures m;
  int rc = bs_dsim_measure(d, &m, err);
  if (rc) return rc;
  const int root = bs_dist_rank() == 0, every = d->scene->vtu_every;
  const int vtu = every > 0 && (fs->frame % every == 0 || d->scene->mode == BS_MODE_STATIC);
  if (root) rc = bs_runfolder_rows(o->rf, d->time, fs, &m, err);
  if (!(rc = agree(rc, err)) && d->scene->states) rc = write_state(o, d, err);
  if (!rc && vtu) rc = write_piece(o, d, fs->frame, err);
  if ((rc = agree(rc, err))) return rc;
  if (root && vtu) rc = write_pvtu(o, fs->frame, d->time, err);
  if (root && !rc) rc = bs_runfolder_frame_done(o->rf, fs, d->frame, &m, err);
  return agree(rc, err);
}

int bs_dout_finish(bs_dout *o, const char *summary, bs_error *err) {
  int rc = BS_OK;
  if (bs_dist_rank() == 0) rc = bs_runfolder_finish(o->rf, summary, err);
  return agree(rc, err);
}
