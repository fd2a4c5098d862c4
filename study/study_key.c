/* study_key.c — the cache key of a study run: a digest of the resolved
 * scene content (bs_study.h), so that editing the scene, a setting or a
 * mesh file reruns what changed. */
#include <stdio.h>
#include <string.h>
#include <zlib.h>

#include "bs_study.h"

typedef struct digest {
  uLong crc, adler;
  unsigned long long bytes;
} digest;

static void add(digest *d, const void *p, size_t n) {
  d->crc = crc32(d->crc, p, (uInt)n);
  d->adler = adler32(d->adler, p, (uInt)n);
  d->bytes += n;
}

/* A file's bytes (with its length, so that a concatenation is not ambiguous). */
static int add_file(digest *d, const char *path, bs_error *err) {
  FILE *f = fopen(path, "rb");
  if (!f) return bs_error_set(err, BS_EIO, "cannot read '%s' for the study's cache key", path);
  unsigned char buf[65536];
  size_t n;
  unsigned long long total = 0;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
    add(d, buf, n);
    total += n;
  }
  int bad = ferror(f);
  fclose(f);
  if (bad) return bs_error_set(err, BS_EIO, "cannot read '%s' for the study's cache key", path);
  add(d, &total, sizeof total);
  return 0;
}

/* The files the loaded scene names: body meshes (not "box") and grid level sets. */
static int add_scene_files(digest *d, const bs_scene *sc, bs_error *err) {
  int st = 0;
  for (int b = 0; !st && b < sc->n_bodies; b++)
    if (strcmp(sc->bodies[b].mesh, "box")) st = add_file(d, sc->bodies[b].mesh, err);
  for (int o = 0; !st && o < sc->n_obstacles; o++)
    if (sc->obstacles[o].grid_file[0]) st = add_file(d, sc->obstacles[o].grid_file, err);
  return st;
}

int bs_study_run_key(const bs_study *S, const bs_study_run *r, char key[BS_STUDY_KEY_LEN + 1], bs_error *err) {
  digest d = {crc32(0, Z_NULL, 0), adler32(0, Z_NULL, 0), 0};
  int st = add_file(&d, S->scene_path, err);
  for (int i = 0; !st && i < r->n_sets; i++) add(&d, r->sets[i], strlen(r->sets[i]) + 1);
  bs_scene *sc = NULL;
  if (!st) st = bs_scene_load(S->scene_path, r->n_sets, (const char *const *)r->sets, &sc, err);
  if (!st) st = add_scene_files(&d, sc, err);
  bs_scene_destroy(&sc);
  if (st) return st;
  snprintf(key, BS_STUDY_KEY_LEN + 1, "%08lx%08lx%016llx", d.crc & 0xffffffffUL, d.adler & 0xffffffffUL, d.bytes);
  return 0;
}
