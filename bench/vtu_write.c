/* bench_vtu_write [CELLS] [REPEATS] [DIR] — the time to write one VTU frame,
 * raw against zlib-compressed (output.compress), with the default output
 * fields (sim/bs_fields.h) of a box of CELLS^2 x (CELLS + 5) cells x 6 tets
 * (CELLS 24: 100224 tets), deformed by a smooth non-affine map.
 *
 * Prints, per mode, the median and the range of REPEATS writes (seconds),
 * the same with fsync (the bytes on the disk), and the file size; and the
 * time to compute the fields once. Files go to DIR (default /tmp) and are
 * removed. */
#define _GNU_SOURCE
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bs_fields.h"
#include "bs_scene.h"
#include "bs_sim.h"

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static void deform(bs_sim *s) {
  for (int32_t v = 0; v < s->mesh->n_vertices; v++) {
    double *x = s->x + 3 * v;
    const double *X = s->x0 + 3 * v;
    x[0] = X[0] * (1 + 0.1 * sin(3 * X[1]));
    x[1] = X[1] + 0.05 * sin(2 * X[0] + X[2]);
    x[2] = X[2] * (1 - 0.05 * X[0]);
    for (int k = 0; k < 3; k++) s->v[3 * v + k] = x[k] - X[k];
  }
}

/* One write of the frame; seconds, and with fsync when sync. */
static double write_once(const bs_sim *s, const bs_fields *fl, int compress, int sync, const char *path, long *bytes) {
  bs_vtu_fields f = {.x = s->x, .velocity = s->v, .custom_cells = 1, .n_point_data = fl->n_point_data,
                     .point_data = fl->point_data, .n_cell_data = fl->n_cell_data, .cell_data = fl->cell_data,
                     .compress = compress};
  bs_error err;
  double t0 = bs_seconds();
  if (bs_mesh_write_vtu(s->mesh, &f, path, &err)) {
    fprintf(stderr, "bench_vtu_write: %s\n", err.msg);
    exit(1);
  }
  if (sync) {
    int fd = open(path, O_RDONLY);
    if (fd >= 0) {
      fsync(fd);
      close(fd);
    }
  }
  double t = bs_seconds() - t0;
  struct stat sb;
  *bytes = stat(path, &sb) ? -1 : (long)sb.st_size;
  return t;
}

static void row(const bs_sim *s, const bs_fields *fl, int compress, int reps, const char *path) {
  double t[2][64];
  long bytes = 0;
  for (int sync = 0; sync < 2; sync++)
    for (int r = 0; r < reps; r++) t[sync][r] = write_once(s, fl, compress, sync, path, &bytes);
  qsort(t[0], (size_t)reps, sizeof(double), cmp);
  qsort(t[1], (size_t)reps, sizeof(double), cmp);
  printf("%-6s %10.4f %7.4f-%-7.4f %12.4f %7.4f-%-7.4f %12.2f\n", compress ? "zlib" : "raw", t[0][reps / 2], t[0][0],
         t[0][reps - 1], t[1][reps / 2], t[1][0], t[1][reps - 1], bytes / 1048576.0);
  unlink(path);
}

int main(int argc, char **argv) {
  int cells = argc > 1 ? atoi(argv[1]) : 24, reps = argc > 2 ? atoi(argv[2]) : 7;
  const char *dir = argc > 3 ? argv[3] : "/tmp";
  if (cells < 1 || reps < 1 || reps > 64) return fprintf(stderr, "usage: bench_vtu_write [CELLS] [REPEATS<=64] [DIR]\n"), 2;
  bs_scene *sc = NULL;
  bs_scene_body *b = NULL;
  bs_sim *s = NULL;
  bs_fields *fl = NULL;
  bs_error err;
  if (bs_scene_create(&sc, &err) || bs_scene_add_body(sc, "box", &b, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
  b->box_cells[0] = b->box_cells[1] = cells;
  b->box_cells[2] = cells + 5;
  b->materials[0] = (bs_scene_material){.model = BS_MODEL_NEO_HOOKEAN, .youngs = 1e6, .poisson = 0.3, .density = 1000};
  if (bs_scene_validate(sc, &err) || bs_sim_create(sc, &s, &err) || bs_fields_create(s, BS_FIELDS_DEFAULT, &fl, &err))
    return fprintf(stderr, "%s\n", err.msg), 1;
  deform(s);
  double t0 = bs_seconds();
  bs_fields_compute(fl, s);
  double tc = bs_seconds() - t0;
  char path[1024];
  snprintf(path, sizeof path, "%s/bench_vtu_write_%d.vtu", dir, (int)getpid());
  printf("VTU frame: %d vertices, %d tets, default fields (%d point, %d cell arrays); fields computed in %.4f s\n",
         s->mesh->n_vertices, s->mesh->n_tets, fl->n_point_data + 2, fl->n_cell_data, tc);
  printf("%d writes per mode to %s; seconds: median, min-max; then with fsync; file MiB\n", reps, dir);
  printf("%-6s %10s %15s %12s %15s %12s\n", "mode", "write", "range", "write+fsync", "range", "MiB");
  row(s, fl, 0, reps, path);
  row(s, fl, 1, reps, path);
  bs_fields_destroy(&fl);
  bs_sim_destroy(&s);
  bs_scene_destroy(&sc);
  return 0;
}
