/* test_dist_output: a petsc-backend run's folder (bs_doutput.h) on 1 and 2
 * ranks: frames.csv with the serial header, one row per frame and the serial
 * run's energies; frames.pvd listing one PVTU per written frame, whose pieces
 * (one per rank) read back with bs_vtu_read and hold every cell once;
 * summary.txt; a second run into the folder refused; the same files as the
 * serial run's folder of the scene (a PVTU for each serial VTU, the pieces
 * aside; the obstacles' files the same bytes) with the same frames.csv and
 * stats.csv headers and rows; what the
 * backend does not write refused by name (bs_dsim_check_output). */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_doutput.h"
#include "bs_runfolder.h"
#include "bs_vtu_read.h"
#include "dist_check.h"

static const char *folder(const char *tag) {
  static char dir[2][256];
  static int k;
  long pid = getpid();
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  k = !k;
  snprintf(dir[k], sizeof dir[k], "/tmp/bs_test_dist_output_%s_%ld", tag, pid);
  return dir[k];
}

static void remove_folder(const char *dir) {
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0, "could not remove %s", dir);
}

/* The pieces of a PVTU (Source attributes) and the cells they hold. */
static int64_t pvtu_cells(const char *dir, const char *pvtu, int *n_pieces) {
  char p[512], line[512];
  snprintf(p, sizeof p, "%s/%s", dir, pvtu);
  FILE *f = fopen(p, "r");
  int64_t cells = 0;
  *n_pieces = 0;
  while (f && fgets(line, sizeof line, f)) {
    char *s = strstr(line, "Source=\"");
    if (!s) continue;
    s += 8;
    *strchr(s, '"') = 0;
    snprintf(p, sizeof p, "%s/%s", dir, s);
    bs_vtu *v = NULL;
    bs_error err = {0};
    CHECK_OK(bs_vtu_read(p, &v, &err), err);
    if (v) cells += v->n_cells, (*n_pieces)++;
    if (v) CHECK(v->displacement != NULL && v->n_cell_data >= 4, "%s: arrays missing", p);
    bs_vtu_destroy(&v);
  }
  if (f) fclose(f);
  return cells;
}

static void check_folder(const char *dir, const bs_dsim *d, const bs_sim_measures *serial) {
  char p[512], line[1024];
  snprintf(p, sizeof p, "%s/frames.csv", dir);
  FILE *f = fopen(p, "r");
  CHECK(f != NULL, "no %s", p);
  if (!f) return;
  int rows = -1;
  double last_total = NAN;
  while (fgets(line, sizeof line, f)) {
    if (rows < 0) CHECK(!strncmp(line, BS_FRAMES_CSV_HEADER, strlen(BS_FRAMES_CSV_HEADER)), "header %s", line);
    else sscanf(line, "%*d,%*g,%*g,%*g,%*g,%lg", &last_total);
    rows++;
  }
  fclose(f);
  CHECK(rows == d->scene->frames + 1, "%d rows for %d frames", rows, d->scene->frames);
  CHECK_REL(last_total, serial->total, 1e-8, "total energy of the last frame vs the serial run");
  bs_pvd *pvd = NULL;
  bs_error err = {0};
  snprintf(p, sizeof p, "%s/frames.pvd", dir);
  CHECK_OK(bs_pvd_read(p, &pvd, &err), err);
  CHECK(pvd && pvd->n == d->scene->frames + 1, "%d frames in frames.pvd", pvd ? pvd->n : -1);
  for (int i = 0; pvd && i < pvd->n; i++) {
    const char *name = strrchr(pvd->files[i], '/');
    int n_pieces = 0;
    int64_t cells = pvtu_cells(dir, name ? name + 1 : pvd->files[i], &n_pieces);
    CHECK(n_pieces == bs_dist_size(), "%s: %d pieces", pvd->files[i], n_pieces);
    CHECK(cells == d->mesh->n_global_cells, "%s: %lld cells of %lld", pvd->files[i], (long long)cells,
          (long long)d->mesh->n_global_cells);
  }
  bs_pvd_destroy(&pvd);
  snprintf(p, sizeof p, "%s/summary.txt", dir);
  CHECK(access(p, F_OK) == 0, "no summary.txt");
}

static void cube_stretch_folder(void) {
  const char *dir = folder("run");
  bs_error err = {0};
  const char *sets[] = {"time.frames=2", "output.vtu_every=1", "output.checkpoint_every=0"};
  bs_scene *sc = NULL;
  CHECK_OK(bs_scene_load("data/scenes/cube_stretch.json", 3, sets, &sc, &err), err);
  bs_dsim *d = NULL;
  bs_sim *s = NULL;
  bs_dout *o = NULL;
  if (sc) CHECK_OK(bs_dsim_create(sc, &d, &err), err);
  if (sc) CHECK_OK(bs_sim_create(sc, &s, &err), err);
  const bs_runfolder_opts replace = {.replace = 1};
  if (d) CHECK_OK(bs_dout_open(d, dir, &replace, &o, &err), err);
  bs_frame_stats fs, ss;
  bs_frame_sums(0, 0, 0, NULL, &fs);
  if (o) CHECK_OK(bs_dout_frame(o, d, &fs, &err), err);
  for (int f = 0; o && s && f < sc->frames; f++) {
    CHECK_OK(bs_dsim_advance_frame(d, &fs, &err), err);
    CHECK_OK(bs_sim_advance_frame(s, &ss, &err), err);
    CHECK_OK(bs_dout_frame(o, d, &fs, &err), err);
  }
  if (o) CHECK_OK(bs_dout_finish(o, "summary\n", &err), err);
  /* A second run into the folder is refused: while the first holds it, and
   * after, without replace. */
  bs_dout *again = NULL;
  if (d) {
    int rc = bs_dout_open(d, dir, NULL, &again, &err);
    CHECK(rc == BS_EINPUT && strstr(err.msg, "in use by another run"), "status %d: %s", rc, err.msg);
    bs_dout_destroy(&o);
    rc = bs_dout_open(d, dir, NULL, &again, &err);
    CHECK(rc == BS_EINPUT && strstr(err.msg, "earlier run"), "status %d: %s", rc, err.msg);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (s && d && bs_dist_rank() == 0) {
    bs_sim_measures m;
    bs_sim_measure(s, 0, &m);
    check_folder(dir, d, &m);
    remove_folder(dir);
  }
  bs_dout_destroy(&o);
  bs_dsim_destroy(&d);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

/* The run files of dir, sorted, one per line into buf; a distributed run's
 * PVTU frame_NNNNN.pvtu listed as the serial frame_NNNNN.vtu, its pieces
 * (the backend's own) left out. */
static int compare_names(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }
static void run_files(const char *dir, char *buf, size_t n) {
  char *names[256];
  int k = 0;
  DIR *dd = opendir(dir);
  CHECK(dd != NULL, "cannot read %s", dir);
  for (struct dirent *e; dd && (e = readdir(dd)) && k < 256;) {
    const char *nm = e->d_name, *dot = strrchr(nm, '.');
    if (!bs_runfolder_is_run_file(nm) && strcmp(nm, BS_RUNFOLDER_LOCK) != 0) continue;
    if (!strncmp(nm, "frame_", 6) && strstr(nm, "_p") && dot && !strcmp(dot, ".vtu")) continue; /* a piece */
    names[k] = malloc(strlen(nm) + 2);
    strcpy(names[k], nm);
    if (dot && !strcmp(dot, ".pvtu")) strcpy(names[k] + (dot - nm), ".vtu");
    k++;
  }
  if (dd) closedir(dd);
  qsort(names, (size_t)k, sizeof *names, compare_names);
  buf[0] = 0;
  for (int i = 0; i < k; i++) {
    size_t len = strlen(buf);
    snprintf(buf + len, n - len, "%s\n", names[i]);
    free(names[i]);
  }
}

/* Line `line` (0: the header) of dir/name into buf ("" when missing); the
 * number of lines into *n. */
static void csv_line(const char *dir, const char *name, int line, char *buf, size_t nb, int *n) {
  char p[512], l[2048];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "r");
  buf[0] = 0, *n = 0;
  while (f && fgets(l, sizeof l, f))
    if ((*n)++ == line) snprintf(buf, nb, "%s", l);
  if (f) fclose(f);
}

/* The serial folder of the scene (rank 0): bs_runfolder_open, its frames. */
static void serial_folder(const bs_scene *sc, const char *dir) {
  bs_error err = {0};
  bs_sim *s = NULL;
  bs_runfolder *rf = NULL;
  const bs_runfolder_opts replace = {.replace = 1};
  CHECK_OK(bs_sim_create(sc, &s, &err), err);
  if (s) CHECK_OK(bs_runfolder_open(dir, s, &replace, &rf, &err), err);
  bs_frame_stats fs;
  bs_frame_sums(0, 0, 0, NULL, &fs);
  if (rf) CHECK_OK(bs_runfolder_frame(s, &fs, rf, &err), err);
  for (int f = 0; rf && f < sc->frames; f++) {
    CHECK_OK(bs_sim_advance_frame(s, &fs, &err), err);
    CHECK_OK(bs_runfolder_frame(s, &fs, rf, &err), err);
  }
  if (rf) CHECK_OK(bs_runfolder_finish(rf, "summary\n", &err), err);
  bs_runfolder_destroy(&rf);
  bs_sim_destroy(&s);
}

/* The petsc folder of the scene (every rank): bs_dout_open, its frames. */
static void petsc_folder(const bs_scene *sc, const char *dir) {
  bs_error err = {0};
  bs_dsim *d = NULL;
  bs_dout *o = NULL;
  const bs_runfolder_opts replace = {.replace = 1};
  CHECK_OK(bs_dsim_create(sc, &d, &err), err);
  if (d) CHECK_OK(bs_dout_open(d, dir, &replace, &o, &err), err);
  bs_frame_stats fs;
  bs_frame_sums(0, 0, 0, NULL, &fs);
  if (o) CHECK_OK(bs_dout_frame(o, d, &fs, &err), err);
  for (int f = 0; o && f < sc->frames; f++) {
    CHECK_OK(bs_dsim_advance_frame(d, &fs, &err), err);
    CHECK_OK(bs_dout_frame(o, d, &fs, &err), err);
  }
  if (o) CHECK_OK(bs_dout_finish(o, "summary\n", &err), err);
  bs_dout_destroy(&o);
  bs_dsim_destroy(&d);
}

/* Whether dir1/name and dir2/name hold the same bytes. */
static int same_bytes(const char *dir1, const char *dir2, const char *name) {
  char p[4608];
  snprintf(p, sizeof p, "%s/%s", dir1, name);
  FILE *a = fopen(p, "rb");
  snprintf(p, sizeof p, "%s/%s", dir2, name);
  FILE *b = fopen(p, "rb");
  int same = a && b, ca, cb;
  while (same && ((ca = getc(a)) != EOF) + ((cb = getc(b)) != EOF)) same = ca == cb;
  if (a) fclose(a);
  if (b) fclose(b);
  return same;
}

/* Rank 0: the same run files (the obstacles' the same bytes), the same CSV
 * headers and row counts, the frames' energies to 1e-8 (as check_folder). */
static void compare_folders(const char *ser, const char *par) {
  static char fs_[4096], fp[4096];
  run_files(ser, fs_, sizeof fs_);
  run_files(par, fp, sizeof fp);
  CHECK(!strcmp(fs_, fp), "run files differ:\nserial:\n%spetsc:\n%s", fs_, fp);
  int n_obstacle = 0;
  for (char *line = fs_, *end; (end = strchr(line, '\n')); line = end + 1) {
    *end = 0;
    if (!strncmp(line, "obstacle", 8)) n_obstacle++;
    if (!strncmp(line, "obstacle", 8)) CHECK(same_bytes(ser, par, line), "%s differs", line);
  }
  CHECK(n_obstacle > 0, "no obstacle files:\n%s", fp);
  const char *csv[] = {"frames.csv", "stats.csv"};
  for (int c = 0; c < 2; c++) {
    char a[2048], b[2048];
    int na, nb;
    csv_line(ser, csv[c], 0, a, sizeof a, &na);
    csv_line(par, csv[c], 0, b, sizeof b, &nb);
    CHECK(a[0] && !strcmp(a, b), "%s: headers differ:\n%s%s", csv[c], a, b);
    CHECK(na == nb && na > 1, "%s: %d rows serial, %d petsc", csv[c], na - 1, nb - 1);
  }
  char a[2048], b[2048];
  int na, nb;
  for (int r = 1; r < 4; r++) {
    double ea = NAN, eb = NAN;
    csv_line(ser, "frames.csv", r, a, sizeof a, &na);
    csv_line(par, "frames.csv", r, b, sizeof b, &nb);
    sscanf(a, "%*d,%*g,%*g,%*g,%*g,%lg", &ea);
    sscanf(b, "%*d,%*g,%*g,%*g,%*g,%lg", &eb);
    CHECK_REL(eb, ea, 1e-8, "total energy of a frame vs the serial run");
  }
}

/* state.bin of the two folders: the same header and frame times, the first
 * frame (the rest state) the same bits, the others' x within 1e-9 of max |x|
 * (as dist_compare.h) and v within 1e-7 of max |v| (v = dx/dt: CG's rounding
 * amplified). */
static void compare_states(const char *ser, const char *par) {
  bs_state_reader a = {0}, b = {0};
  bs_error err = {0};
  CHECK_OK(bs_state_open(ser, &a, &err), err);
  CHECK_OK(bs_state_open(par, &b, &err), err);
  CHECK(a.n == b.n && a.frames == b.frames && a.frames == 3, "state.bin: %d vertices and %ld frames serial, %d and "
        "%ld petsc", (int)a.n, a.frames, (int)b.n, b.frames);
  for (int f = 0; a.f && b.f && a.n == b.n && !bs_state_next(&a) && !bs_state_next(&b); f++) {
    double dx = 0, dv = 0, xmax = 0, vmax = 0;
    for (int32_t i = 0; i < 3 * a.n; i++) {
      dx = fmax(dx, fabs(a.x[i] - b.x[i])), dv = fmax(dv, fabs(a.v[i] - b.v[i]));
      xmax = fmax(xmax, fabs(a.x[i])), vmax = fmax(vmax, fabs(a.v[i]));
    }
    CHECK(a.time == b.time, "state.bin frame %d: time %.17g and %.17g", f, a.time, b.time);
    CHECK(f > 0 ? dx <= 1e-9 * xmax && dv <= 1e-7 * vmax : dx == 0 && dv == 0,
          "state.bin frame %d: x differ by %.3g (max |x| %.3g), v by %.3g (max |v| %.3g)", f, dx, xmax, dv, vmax);
  }
  bs_state_close(&a);
  bs_state_close(&b);
}

static void same_files_as_serial(void) {
  const char *ser = folder("serial"), *par = folder("petsc");
  bs_error err = {0};
  const char *sets[] = {"time.frames=2", "output.vtu_every=2", "output.checkpoint_every=0",
                        "obstacles.0.friction=0", "output.states=true"};
  bs_scene *sc = NULL;
  CHECK_OK(bs_scene_load("data/scenes/box_squeeze.json", 5, sets, &sc, &err), err);
  if (sc && bs_dist_rank() == 0) serial_folder(sc, ser);
  if (sc) petsc_folder(sc, par);
  MPI_Barrier(MPI_COMM_WORLD);
  if (sc && bs_dist_rank() == 0) {
    compare_folders(ser, par);
    compare_states(ser, par);
    remove_folder(ser);
    remove_folder(par);
  }
  bs_scene_destroy(&sc);
}

/* What the backend does not write is refused by name, before any file. */
static void refused_outputs(void) {
  static const char *const cases[][2] = {{"output.states=true", "output.states: state.bin is written in the serial"},
                                         {"output.checkpoint_every=1", "output.checkpoint_every: checkpoints"},
                                         {"output.fields=[\"von_mises\"]", "output.fields: the VTU pieces"}};
  for (int i = 0; i < 3; i++) {
    bs_error err = {0};
    const char *sets[] = {"time.frames=1", "output.checkpoint_every=0", "bodies.0.refine=1", cases[i][0]};
    bs_scene *sc = NULL;
    bs_dsim *d = NULL;
    bs_dout *o = NULL;
    CHECK_OK(bs_scene_load("data/scenes/cube_stretch.json", 4, sets, &sc, &err), err);
    if (sc) CHECK_OK(bs_dsim_create(sc, &d, &err), err);
    int rc = d ? bs_dout_open(d, folder("refused"), NULL, &o, &err) : BS_OK;
    CHECK(rc == BS_EINPUT && strstr(err.msg, cases[i][1]) && strstr(err.msg, "solver.backend petsc"),
          "%s: status %d: %s", cases[i][0], rc, err.msg);
    bs_dout_destroy(&o);
    bs_dsim_destroy(&d);
    bs_scene_destroy(&sc);
  }
  bs_error err = {0};
  bs_scene *sc = NULL;
  CHECK_OK(bs_scene_load("data/scenes/cube_stretch.json", 0, NULL, &sc, &err), err);
  int rc = sc ? bs_dsim_check_output(sc, 1, &err) : BS_OK;
  CHECK(rc == BS_EINPUT && strstr(err.msg, "--resume: no checkpoint"), "--resume: status %d: %s", rc, err.msg);
  bs_scene_destroy(&sc);
}

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"cube_stretch_folder", cube_stretch_folder},
                                    {"same_files_as_serial", same_files_as_serial},
                                    {"refused_outputs", refused_outputs}};
  return dist_check_main(argc, argv, tests, 3);
}
