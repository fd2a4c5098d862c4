/* audit_list.c — the files an audit reads (bs_audit.h): a folder's
 * frame_N.vtu files, a PVD's list, or one file. */
#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bs_audit.h"
#include "bs_vtu_read.h"

typedef struct list_build {
  bs_audit_list *L;
  int cap;
} list_build;

static int list_add(list_build *b, char *path, int number, double time, int has_time) {
  bs_audit_list *L = b->L;
  if (L->n == b->cap) {
    int nc = b->cap ? 2 * b->cap : 64;
    bs_audit_entry *ne = realloc(L->entries, (size_t)nc * sizeof *ne);
    if (!ne) return -1;
    L->entries = ne;
    b->cap = nc;
  }
  L->entries[L->n++] = (bs_audit_entry){path, number, time, has_time};
  return 0;
}

void bs_audit_list_free(bs_audit_list *L) {
  if (!L) return;
  for (int i = 0; i < L->n; i++) free(L->entries[i].path);
  free(L->entries);
  L->entries = NULL;
  L->n = 0;
}

/* N when name is "frame_N.vtu" (N all digits, at most 9), else -1. */
static long frame_number(const char *name) {
  if (strncmp(name, "frame_", 6)) return -1;
  const char *p = name + 6, *q = p;
  while (*q >= '0' && *q <= '9') q++;
  if (q == p || q - p > 9 || strcmp(q, ".vtu")) return -1;
  return strtol(p, NULL, 10);
}

static long path_frame_number(const char *path) {
  const char *base = strrchr(path, '/');
  return frame_number(base ? base + 1 : path);
}

static int cmp_entry(const void *a, const void *b) {
  const bs_audit_entry *x = a, *y = b;
  if (x->number != y->number) return x->number < y->number ? -1 : 1;
  return strcmp(x->path, y->path);
}

static char *join(const char *dir, const char *name) {
  size_t dl = strlen(dir), nl = strlen(name);
  char *s = malloc(dl + nl + 2);
  if (!s) return NULL;
  memcpy(s, dir, dl);
  size_t k = dl;
  if (dl && dir[dl - 1] != '/') s[k++] = '/';
  memcpy(s + k, name, nl + 1);
  return s;
}

static int ends_with(const char *s, const char *suffix) {
  size_t n = strlen(s), m = strlen(suffix);
  return n >= m && !strcmp(s + n - m, suffix);
}

static int from_pvd(const char *pvd_path, list_build *b, bs_error *err) {
  bs_pvd *pv = NULL;
  int rc = bs_pvd_read(pvd_path, &pv, err);
  if (rc) return rc;
  for (int i = 0; i < pv->n; i++) {
    long num = path_frame_number(pv->files[i]);
    char *p = strdup(pv->files[i]);
    if (!p || list_add(b, p, num >= 0 ? (int)num : i, pv->times[i], 1)) {
      free(p);
      bs_pvd_destroy(&pv);
      return bs_error_set(err, BS_ENOMEM, "'%s': out of memory", pvd_path);
    }
  }
  int n = pv->n;
  bs_pvd_destroy(&pv);
  if (n == 0) return bs_error_set(err, BS_EINPUT, "'%s' lists no data sets", pvd_path);
  return BS_OK;
}

/* The folder's frame_N.vtu files, in the order of N (none is not an error). */
static int from_folder(const char *dir, list_build *b, bs_error *err) {
  DIR *d = opendir(dir);
  if (!d) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot list folder '%s': %s", dir, strerror(e));
  }
  struct dirent *de;
  while ((de = readdir(d))) {
    long num = frame_number(de->d_name);
    if (num < 0) continue;
    char *p = join(dir, de->d_name);
    if (!p || list_add(b, p, (int)num, 0, 0)) {
      free(p);
      closedir(d);
      return bs_error_set(err, BS_ENOMEM, "out of memory");
    }
  }
  closedir(d);
  if (b->L->n > 0) qsort(b->L->entries, (size_t)b->L->n, sizeof *b->L->entries, cmp_entry);
  return BS_OK;
}

/* A folder: its frames, else the files of its frames.pvd. */
static int list_folder(const char *dir, list_build *b, bs_error *err) {
  int rc = from_folder(dir, b, err);
  if (rc || b->L->n > 0) {
    b->L->origin = BS_AUDIT_FRAME_FILES;
    return rc;
  }
  char *pvd = join(dir, "frames.pvd");
  if (!pvd) return bs_error_set(err, BS_ENOMEM, "out of memory");
  struct stat sb;
  if (stat(pvd, &sb) == 0) {
    b->L->origin = BS_AUDIT_FOLDER_PVD;
    rc = from_pvd(pvd, b, err);
  } else {
    rc = bs_error_set(err, BS_EINPUT, "folder '%s' holds no frame_*.vtu files and no frames.pvd", dir);
  }
  free(pvd);
  return rc;
}

static int list_target(const char *target, list_build *b, bs_error *err) {
  struct stat sb;
  if (stat(target, &sb)) {
    int e = errno;
    return bs_error_set(err, BS_EIO, "cannot read '%s': %s", target, strerror(e));
  }
  if (S_ISDIR(sb.st_mode)) return list_folder(target, b, err);
  if (ends_with(target, ".pvd")) {
    b->L->origin = BS_AUDIT_PVD_FILE;
    return from_pvd(target, b, err);
  }
  b->L->origin = BS_AUDIT_ONE_FILE;
  char *p = strdup(target);
  long num = path_frame_number(target);
  if (!p || list_add(b, p, num >= 0 ? (int)num : 0, 0, 0)) {
    free(p);
    return bs_error_set(err, BS_ENOMEM, "out of memory");
  }
  return BS_OK;
}

int bs_audit_list_frames(const char *target, bs_audit_list *L, bs_error *err) {
  *L = (bs_audit_list){0, NULL, BS_AUDIT_ONE_FILE};
  if (!target) return bs_error_set(err, BS_EINPUT, "no folder or file to audit");
  list_build b = {L, 0};
  int rc = list_target(target, &b, err);
  if (rc) bs_audit_list_free(L);
  return rc;
}

double bs_audit_entry_time(const bs_audit_entry *e, const bs_sim *sim) {
  if (e->has_time) return e->time;
  const bs_scene *sc = sim ? sim->scene : NULL;
  return sc && sc->mode == BS_MODE_DYNAMIC ? e->number / sc->fps : 0.0;
}
