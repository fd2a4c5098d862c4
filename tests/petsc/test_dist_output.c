/* test_dist_output: a petsc-backend run's folder (bs_doutput.h) on 1 and 2
 * ranks: frames.csv with the serial header, one row per frame and the serial
 * run's energies; frames.pvd listing one PVTU per written frame, whose pieces
 * (one per rank) read back with bs_vtu_read and hold every cell once;
 * summary.txt. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bs_doutput.h"
#include "bs_runfolder.h"
#include "bs_vtu_read.h"
#include "dist_check.h"

static const char *folder(void) {
  static char dir[256];
  long pid = getpid();
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  snprintf(dir, sizeof dir, "/tmp/bs_test_dist_output_%ld", pid);
  return dir;
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
  const char *dir = folder();
  bs_error err = {0};
  const char *sets[] = {"time.frames=2", "output.vtu_every=1"};
  bs_scene *sc = NULL;
  CHECK_OK(bs_scene_load("data/scenes/cube_stretch.json", 2, sets, &sc, &err), err);
  bs_dsim *d = NULL;
  bs_sim *s = NULL;
  bs_dout *o = NULL;
  if (sc) CHECK_OK(bs_dsim_create(sc, &d, &err), err);
  if (sc) CHECK_OK(bs_sim_create(sc, &s, &err), err);
  if (d) CHECK_OK(bs_dout_open(d, dir, 1, &o, &err), err);
  bs_frame_stats fs, ss;
  bs_frame_sums(0, 0, 0, NULL, &fs);
  if (o) CHECK_OK(bs_dout_frame(o, d, &fs, &err), err);
  for (int f = 0; o && s && f < sc->frames; f++) {
    CHECK_OK(bs_dsim_advance_frame(d, &fs, &err), err);
    CHECK_OK(bs_sim_advance_frame(s, &ss, &err), err);
    CHECK_OK(bs_dout_frame(o, d, &fs, &err), err);
  }
  if (o) CHECK_OK(bs_dout_finish(o, "summary\n", &err), err);
  /* A second run into the folder is refused without replace. */
  bs_dout *again = NULL;
  if (d) {
    int rc = bs_dout_open(d, dir, 0, &again, &err);
    CHECK(rc == BS_EINPUT && strstr(err.msg, "earlier run"), "status %d: %s", rc, err.msg);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (s && d && bs_dist_rank() == 0) {
    bs_sim_measures m;
    bs_sim_measure(s, 0, &m);
    check_folder(dir, d, &m);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    CHECK(system(cmd) == 0, "could not remove %s", dir);
  }
  bs_dout_destroy(&o);
  bs_dsim_destroy(&d);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
}

int main(int argc, char **argv) {
  static const dist_test tests[] = {{"cube_stretch_folder", cube_stretch_folder}};
  return dist_check_main(argc, argv, tests, 1);
}
