/* runfolder_resume.c — continuing a stopped run in its folder from its last
 * checkpoint (bs_runfolder_resume, bs_runfolder.h): the scene compared, the
 * files cut back to the checkpoint's frame, the collections rebuilt. */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "runfolder_internal.h"

/* The first line where texts a and b differ, into buf ("line N: A | B"). */
static void first_difference(const char *a, const char *b, char *buf, size_t n) {
  int line = 1;
  const char *la = a, *lb = b;
  while (*a && *a == *b) {
    if (*a == '\n') line++, la = a + 1, lb = b + 1;
    a++, b++;
  }
  int na = (int)strcspn(la, "\n"), nb = (int)strcspn(lb, "\n");
  snprintf(buf, n, "line %d of the resolved scene: here '%.*s', there '%.*s'", line, na > 120 ? 120 : na, la,
           nb > 120 ? 120 : nb, lb);
}

/* The scene must be the one the folder was run with (its scene.json). */
static int same_scene(const char *dir, const bs_scene *sc, bs_error *err) {
  char p[BS_MAX_PATH + 32], diff[400];
  snprintf(p, sizeof p, "%s/scene.json", dir);
  bs_scene *old = NULL;
  char *a = NULL, *b = NULL;
  int st = bs_scene_load(p, 0, NULL, &old, err);
  if (st) bs_error_prefix(err, "cannot continue the run in '%s'", dir);
  if (!st) st = bs__scene_identity(sc, &a, err);
  if (!st) st = bs__scene_identity(old, &b, err);
  if (!st && strcmp(a, b)) {
    first_difference(a, b, diff, sizeof diff);
    st = bs_error_set(err, BS_EINPUT,
                      "cannot continue the run in '%s': the scene is not the one it was run with ('%s'; %s)", dir, p,
                      diff);
  }
  free(a);
  free(b);
  bs_scene_destroy(&old);
  return st;
}

static int resumable(const char *dir, const bs_scene *sc, bs_error *err) {
  if (sc->mode != BS_MODE_DYNAMIC)
    return bs_error_set(err, BS_EINPUT, "cannot continue the run in '%s': a static scene has no frames to continue",
                        dir);
  if (sc->solver.method == BS_METHOD_OPTIMIZATION && sc->solver.min.linear == BS_LIN_AMG && !sc->solver.amg_at_rest)
    return bs_error_set(err, BS_EINPUT,
                        "cannot continue the run in '%s': with solver.amg_matrix \"current\" the preconditioner is "
                        "built at an earlier iterate that no checkpoint holds, so the frames would not repeat",
                        dir);
  return same_scene(dir, sc, err);
}

/* Keeps the header and the rows of dir/name whose frame (the first field)
 * is <= K, which must be `want` rows; cuts the file after them. */
static int cut_rows(const char *dir, const char *name, int K, long want, bs_error *err) {
  char p[BS_MAX_PATH + 32];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "cannot continue the run: cannot open '%s': %s", p, strerror(errno));
  char *line = NULL;
  size_t cap = 0;
  ssize_t len;
  long rows = 0, lines = 0;
  off_t keep = 0;
  while ((len = getline(&line, &cap, f)) > 0 && line[len - 1] == '\n') { /* a row cut short ends it */
    char *end;
    long fr = lines++ ? strtol(line, &end, 10) : 0;
    if (lines > 1 && (end == line || *end != ',' || fr > K)) break;
    keep += len;
    rows += lines > 1;
  }
  free(line);
  fclose(f);
  if (rows != want)
    return bs_error_set(err, BS_EINPUT,
                        "cannot continue the run: '%s' holds %ld rows up to frame %d where the checkpoint needs %ld",
                        p, rows, K, want);
  if (truncate(p, keep) != 0) return bs_error_set(err, BS_EIO, "cannot cut '%s': %s", p, strerror(errno));
  return 0;
}

/* state.bin: the header and frames 0..K. */
static int cut_state(const char *dir, const bs_sim *s, int K, bs_error *err) {
  bs_state_reader r;
  int st = bs_state_open(dir, &r, err);
  if (st) return st;
  const long frames = r.frames;
  const int32_t n = r.n;
  bs_state_close(&r);
  char p[BS_MAX_PATH + 32];
  snprintf(p, sizeof p, "%s/state.bin", dir);
  if (n != s->mesh->n_vertices || frames < K + 1)
    return bs_error_set(err, BS_EINPUT, "cannot continue the run: '%s' holds %ld frames of %d vertices, the checkpoint "
                        "needs %d of %d", p, frames, n, K + 1, s->mesh->n_vertices);
  const off_t size = 16 + (off_t)(K + 1) * (off_t)(1 + 6 * (off_t)n) * 8;
  if (truncate(p, size) != 0) return bs_error_set(err, BS_EIO, "cannot cut '%s': %s", p, strerror(errno));
  return 0;
}

/* Removes the VTU and obstacle frames after frame K and every NAME.tmp. */
static int remove_later(const char *dir, int K, bs_error *err) {
  DIR *d = opendir(dir);
  if (!d) return bs_error_set(err, BS_EIO, "cannot read folder '%s': %s", dir, strerror(errno));
  int st = 0;
  for (struct dirent *e; !st && (e = readdir(d));) {
    const char *nm = e->d_name;
    const size_t n = strlen(nm);
    int k, N, later = 0;
    if (sscanf(nm, "frame_%d.vtu", &N) == 1 || sscanf(nm, "obstacle_%d_%d.", &k, &N) == 2) later = N > K;
    if (!later && !(n > 4 && !strcmp(nm + n - 4, BS_TMP_SUFFIX) && bs_runfolder_is_run_file(nm))) continue;
    char p[BS_MAX_PATH + 300];
    snprintf(p, sizeof p, "%s/%s", dir, nm);
    if (unlink(p) != 0 && errno != ENOENT) st = bs_error_set(err, BS_EIO, "cannot remove '%s': %s", p, strerror(errno));
  }
  closedir(d);
  return st;
}

/* frames.pvd and the obstacles' collections of the frames 0..K on disk. */
static int restore_collections(bs_runfolder *rf, const bs_sim *s, int K, bs_error *err) {
  const bs_scene *sc = s->scene;
  if (sc->vtu_every <= 0) return 0;
  int st = 0;
  for (int f = 0; f <= K && !st; f += sc->vtu_every) {
    char name[64], p[BS_MAX_PATH + 80];
    snprintf(name, sizeof name, "frame_%05d.vtu", f);
    snprintf(p, sizeof p, "%s/%s", rf->dir, name);
    if (access(p, F_OK) == 0) st = bs__runfolder_add_vtu(rf, name, f / sc->fps, err);
    if (!st) st = bs_obstacle_output_skip(rf->obstacles, f, f / sc->fps, err);
  }
  if (!st) st = bs__runfolder_write_pvd(rf, err);
  if (!st) st = bs_obstacle_output_write_pvds(rf->obstacles, err);
  return st;
}

/* run.txt with a line "resumed: TIME at frame K: COMMAND" added. */
static int record_resume(const char *dir, const char *command, int K, bs_error *err) {
  char p[BS_MAX_PATH + 32], stamp[64] = "?", old[8192] = "", add[BS_MAX_PATH + 128];
  snprintf(p, sizeof p, "%s/run.txt", dir);
  FILE *f = fopen(p, "r");
  if (f) {
    size_t n = fread(old, 1, sizeof old - 1, f);
    old[n] = 0;
    fclose(f);
  }
  time_t now = time(NULL);
  struct tm tm;
  if (gmtime_r(&now, &tm)) strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &tm);
  snprintf(add, sizeof add, "resumed: %s at frame %d: %s\n", stamp, K, command ? command : "(library call)");
  char *text = malloc(strlen(old) + strlen(add) + 1);
  if (!text) return bs_error_set(err, BS_ENOMEM, "out of memory");
  strcat(strcpy(text, old), add);
  int st = bs_outfile_replace_text(dir, "run.txt", text, err);
  free(text);
  return st;
}

/* The files cut back to frame K, then opened at their end. */
static int cut_back(bs_runfolder *rf, const bs_sim *s, int K, bs_error *err) {
  const bs_scene *sc = s->scene;
  int st = cut_rows(rf->dir, "frames.csv", K, K + 1L, err);
  if (!st && sc->stats_csv) st = cut_rows(rf->dir, "stats.csv", K, (long)K * sc->steps_per_frame, err);
  if (!st && sc->n_qoi > 0) st = cut_rows(rf->dir, "qoi.csv", K, K + 1L, err);
  if (!st && sc->states) st = cut_state(rf->dir, s, K, err);
  if (!st) st = remove_later(rf->dir, K, err);
  if (!st) st = bs__runfolder_rows_open(rf, 1, err);
  if (!st) st = bs__runfolder_outputs(rf, s, 1, err);
  if (!st) st = restore_collections(rf, s, K, err);
  return st;
}

int bs_runfolder_resume(const char *dir, bs_sim *s, const bs_runfolder_opts *o, bs_runfolder **out,
                        bs_run_totals *totals, bs_error *err) {
  *out = NULL;
  bs_runfolder *rf = NULL;
  bs_checkpoint ck = {0};
  const bs_runfolder_run run = bs__runfolder_run_of(s);
  int st = bs__runfolder_begin(dir, &run, &rf, err);
  if (!st) st = resumable(dir, s->scene, err);
  if (!st) st = bs_checkpoint_read(dir, s, rf->scene_hash, &ck, err);
  if (!st) st = bs_sim_restore(s, ck.frame, ck.x, ck.v, err);
  if (!st) bs_integrator_set_carry(s->integrator, &ck.carry);
  if (!st) bs_integrator_set_previous(s->integrator, &ck.prev);
  if (!st) bs_integrator_set_history(s->integrator, &ck.hist);
  if (!st) st = cut_back(rf, s, ck.frame, err);
  if (!st) st = record_resume(dir, o ? o->command_line : NULL, ck.frame, err);
  if (!st) {
    rf->totals = *totals = ck.totals;
    rf->t_open = bs_seconds() - ck.wall_seconds;
  }
  bs_checkpoint_free(&ck);
  if (st) bs_runfolder_destroy(&rf);
  *out = rf;
  return st;
}
