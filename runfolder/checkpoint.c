/* checkpoint.c — checkpoint.bin, the state a run continues from (format:
 * bs_runfolder.h): written through a temporary file, read back with every
 * check. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "outfile.h"
#include "runfolder_internal.h"

#define CK_MAGIC "BSCK"
#define CK_HEADER 48 /* magic, version, n, frame, time, scene hash, wall, frames, 0 */
#define CK_LONGS 12
#define CK_TOTALS (CK_LONGS * 8 + 2 * 8 + 2 * 4 + 256)
#define CK_CARRY 16 /* the minimizer's carry: int64 full, double eta */
#define CK_PREV 24  /* the previous-step guess: int64 have, double dt, uint64 mark */
#define CK_HEAD3 (CK_HEADER + CK_TOTALS + CK_CARRY + CK_PREV) /* version 3 */
#define CK_HIST 32 /* the integrator's history: int64 integrator, int64 have, double dt, uint64 mark */
#define CK_HEAD (CK_HEAD3 + CK_HIST)

int bs__scene_identity(const bs_scene *sc, char **text, bs_error *err) {
  bs_scene *c = malloc(sizeof *c);
  if (!c) return bs_error_set(err, BS_ENOMEM, "out of memory");
  *c = *sc; /* a shallow copy, only written out */
  c->out_dir[0] = 0;
  c->description = NULL;
  int st = bs_scene_write_json(c, text, err);
  free(c);
  return st;
}

/* The totals as CK_LONGS int64, 2 doubles, 2 int32 and the reason (256 bytes). */
static void pack_totals(const bs_run_totals *T, unsigned char *b) {
  const long L[CK_LONGS] = {T->steps, T->failed, T->iterations, T->cg,      T->ls,       T->indefinite,
                            T->fb_dx, T->fb_grad, T->clamps,    T->chol_fb, T->downhill, T->floor};
  for (int i = 0; i < CK_LONGS; i++) {
    int64_t v = L[i];
    memcpy(b + 8 * i, &v, 8);
  }
  unsigned char *r = b + 8 * CK_LONGS;
  memcpy(r, &T->seconds, 8);
  memcpy(r + 8, &T->max_grad, 8);
  int32_t f[2] = {T->first_fail_frame, T->first_fail_step};
  memcpy(r + 16, f, 8);
  memcpy(r + 24, T->first_fail_reason, 256);
}

static void unpack_totals(const unsigned char *b, bs_run_totals *T) {
  long *L[CK_LONGS] = {&T->steps, &T->failed, &T->iterations, &T->cg,      &T->ls,       &T->indefinite,
                       &T->fb_dx, &T->fb_grad, &T->clamps,    &T->chol_fb, &T->downhill, &T->floor};
  for (int i = 0; i < CK_LONGS; i++) {
    int64_t v;
    memcpy(&v, b + 8 * i, 8);
    *L[i] = (long)v;
  }
  const unsigned char *r = b + 8 * CK_LONGS;
  memcpy(&T->seconds, r, 8);
  memcpy(&T->max_grad, r + 8, 8);
  int32_t f[2];
  memcpy(f, r + 16, 8);
  T->first_fail_frame = f[0];
  T->first_fail_step = f[1];
  memcpy(T->first_fail_reason, r + 24, 256);
  T->first_fail_reason[255] = 0;
}

static void pack_header(const bs_sim *s, uint64_t scene_hash, double wall, unsigned char *b) {
  const uint32_t version = BS_CHECKPOINT_VERSION;
  const int32_t i3[3] = {s->mesh->n_vertices, s->frame, s->scene->frames}, zero = 0;
  memcpy(b, CK_MAGIC, 4);
  memcpy(b + 4, &version, 4);
  memcpy(b + 8, i3, 8);
  memcpy(b + 16, &s->time, 8);
  memcpy(b + 24, &scene_hash, 8);
  memcpy(b + 32, &wall, 8);
  memcpy(b + 40, &i3[2], 4);
  memcpy(b + 44, &zero, 4);
}

int bs_checkpoint_write(const char *dir, const bs_sim *s, const bs_run_totals *T, double wall, uint64_t scene_hash,
                        bs_error *err) {
  unsigned char head[CK_HEAD];
  pack_header(s, scene_hash, wall, head);
  pack_totals(T, head + CK_HEADER);
  bs_min_carry c;
  bs_integrator_get_carry(s->integrator, &c);
  const int64_t full = c.full;
  memcpy(head + CK_HEADER + CK_TOTALS, &full, 8);
  memcpy(head + CK_HEADER + CK_TOTALS + 8, &c.eta, 8);
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  bs_previous_step p = {0, 0, 0, calloc(n3 ? n3 : 1, sizeof(double))};
  if (!p.d) return bs_error_set(err, BS_ENOMEM, "out of memory (checkpoint)");
  bs_integrator_get_previous(s->integrator, &p);
  const int64_t have = p.have;
  if (!have) memset(p.d, 0, sizeof(double) * n3);
  unsigned char *q = head + CK_HEADER + CK_TOTALS + CK_CARRY;
  memcpy(q, &have, 8);
  memcpy(q + 8, &p.dt, 8);
  memcpy(q + 16, &p.mark, 8);
  const size_t nh = bs_integrator_history_doubles(s->integrator);
  bs_step_history hs = {0, 0, 0, calloc(nh ? nh : 1, sizeof(double))};
  if (!hs.h) {
    free(p.d);
    return bs_error_set(err, BS_ENOMEM, "out of memory (checkpoint)");
  }
  bs_integrator_get_history(s->integrator, &hs);
  if (!hs.have) memset(hs.h, 0, sizeof(double) * nh);
  const int64_t hv[2] = {s->scene->solver.integrator, hs.have};
  memcpy(q + CK_PREV, hv, 16);
  memcpy(q + CK_PREV + 16, &hs.dt, 8);
  memcpy(q + CK_PREV + 24, &hs.mark, 8);
  uint64_t h = bs_fnv1a(BS_FNV_SEED, head, sizeof head);
  h = bs_fnv1a(h, s->x, sizeof(double) * n3);
  h = bs_fnv1a(h, s->v, sizeof(double) * n3);
  h = bs_fnv1a(h, p.d, sizeof(double) * n3);
  h = bs_fnv1a(h, hs.h, sizeof(double) * nh);
  bs_outfile o;
  int st = bs_outfile_open_replace(&o, dir, "checkpoint.bin", err);
  if (!st) {
    bs_outfile_write(&o, head, 1, sizeof head);
    bs_outfile_write(&o, s->x, sizeof(double), n3);
    bs_outfile_write(&o, s->v, sizeof(double), n3);
    bs_outfile_write(&o, p.d, sizeof(double), n3);
    bs_outfile_write(&o, hs.h, sizeof(double), nh);
    bs_outfile_write(&o, &h, 8, 1);
    st = bs_outfile_close(&o, err);
  }
  free(p.d);
  free(hs.h);
  return st;
}

/* The whole file into memory (it was written whole): *buf, *n. */
static int slurp(const char *p, unsigned char **buf, size_t *n, bs_error *err) {
  *buf = NULL;
  FILE *f = fopen(p, "rb");
  struct stat sb;
  if (!f || fstat(fileno(f), &sb) != 0) {
    if (f) fclose(f);
    return bs_error_set(err, BS_EIO, "no checkpoint to continue from: cannot open '%s'", p);
  }
  *n = (size_t)sb.st_size;
  *buf = malloc(*n ? *n : 1);
  int ok = *buf && fread(*buf, 1, *n, f) == *n;
  fclose(f);
  if (!ok) {
    free(*buf);
    *buf = NULL;
    return bs_error_set(err, BS_EIO, "cannot read '%s'", p);
  }
  return 0;
}

/* Header checks against the simulation and the scene: 0 or BS_EINPUT. */
static int check_header(const char *p, const unsigned char *b, size_t n, const bs_sim *s, uint64_t scene_hash,
                        bs_checkpoint *ck, bs_error *err) {
  if (n < 4 || memcmp(b, CK_MAGIC, 4))
    return bs_error_set(err, BS_EINPUT, "'%s' is not a bigstep checkpoint (no BSCK magic)", p);
  if (n < CK_HEAD3 + 8)
    return bs_error_set(err, BS_EINPUT, "'%s' is %zu bytes, shorter than a checkpoint's header: truncated", p, n);
  uint32_t version;
  int32_t i3[2];
  uint64_t hash;
  memcpy(&version, b + 4, 4);
  memcpy(i3, b + 8, 8);
  memcpy(&ck->time, b + 16, 8);
  memcpy(&hash, b + 24, 8);
  memcpy(&ck->wall_seconds, b + 32, 8);
  ck->frame = i3[1];
  if (version != BS_CHECKPOINT_VERSION && version != 3)
    return bs_error_set(err, BS_EINPUT, "'%s': checkpoint version %u; this bigstep reads versions 3 and %d", p,
                        version, BS_CHECKPOINT_VERSION);
  ck->version = (int)version;
  if (i3[0] != s->mesh->n_vertices)
    return bs_error_set(err, BS_EINPUT, "'%s' holds %d vertices, the scene's mesh %d: a checkpoint of another scene", p,
                        i3[0], s->mesh->n_vertices);
  const size_t nh = version == 3 ? 0 : bs_integrator_history_doubles(s->integrator);
  const size_t want = (version == 3 ? CK_HEAD3 : CK_HEAD) + 72 * (size_t)i3[0] + 8 * nh + 8;
  if (n != want)
    return bs_error_set(err, BS_EINPUT, "'%s' is %zu bytes, a checkpoint of %d vertices %zu: truncated or damaged", p,
                        n, i3[0], want);
  if (hash != scene_hash)
    return bs_error_set(err, BS_EINPUT, "'%s' is a checkpoint of another scene (its scene hash differs)", p);
  const bs_scene *sc = s->scene;
  if (ck->frame < 0 || ck->frame > sc->frames || ck->time != ck->frame / sc->fps || !isfinite(ck->wall_seconds))
    return bs_error_set(err, BS_EINPUT, "'%s': frame %d at time %.17g does not fit the scene (%d frames at %g fps)", p,
                        ck->frame, ck->time, sc->frames, sc->fps);
  return 0;
}

/* The previous-step guess's state at q (CK_PREV bytes) into prev (its d
 * already read): 0 or BS_EINPUT when out of range. */
static int read_previous(const char *p, const unsigned char *q, bs_previous_step *prev, bs_error *err) {
  int64_t have;
  memcpy(&have, q, 8);
  memcpy(&prev->dt, q + 8, 8);
  memcpy(&prev->mark, q + 16, 8);
  prev->have = (int)have;
  if (!(have == 0 || have == 1) || (have && !(prev->dt > 0 && isfinite(prev->dt))))
    return bs_error_set(err, BS_EINPUT,
                        "'%s': the previous step's state (%lld, dt %g) is out of range: a damaged checkpoint", p,
                        (long long)have, prev->dt);
  return 0;
}

/* The integrator's history at q (CK_HIST bytes) into hist (its h already
 * read): 0 or BS_EINPUT when it is another integrator's or out of range. */
static int read_history(const char *p, const unsigned char *q, const bs_sim *s, bs_step_history *hist,
                        bs_error *err) {
  int64_t hv[2];
  memcpy(hv, q, 16);
  memcpy(&hist->dt, q + 16, 8);
  memcpy(&hist->mark, q + 24, 8);
  hist->have = (int)hv[1];
  const int want = s->scene->solver.integrator;
  if (hv[0] != want)
    return bs_error_set(err, BS_EINPUT, "'%s': a checkpoint of solver.integrator %s, the scene's is %s", p,
                        bs_time_integrator_name((bs_time_integrator)hv[0]),
                        bs_time_integrator_name((bs_time_integrator)want));
  if (!(hv[1] == 0 || hv[1] == 1) || (hv[1] && !(hist->dt > 0 && isfinite(hist->dt))))
    return bs_error_set(err, BS_EINPUT,
                        "'%s': the integrator's history (%lld, dt %g) is out of range: a damaged checkpoint", p,
                        (long long)hv[1], hist->dt);
  return 0;
}

/* The body of a checkpoint (after its header checks and checksum) into ck. */
static int read_body(const char *p, const unsigned char *b, const bs_sim *s, bs_checkpoint *ck, bs_error *err) {
  const size_t n3 = 3 * (size_t)s->mesh->n_vertices;
  const size_t nh = ck->version == 3 ? 0 : bs_integrator_history_doubles(s->integrator);
  if (!(ck->x = malloc(sizeof(double) * (3 * n3 + nh + 1)))) return bs_error_set(err, BS_ENOMEM, "out of memory");
  unpack_totals(b + CK_HEADER, &ck->totals);
  int64_t full;
  memcpy(&full, b + CK_HEADER + CK_TOTALS, 8);
  memcpy(&ck->carry.eta, b + CK_HEADER + CK_TOTALS + 8, 8);
  ck->carry.full = (int)full;
  int st = 0;
  if (!(full == 0 || full == 1) || !(ck->carry.eta >= 0 && ck->carry.eta <= 0.5))
    st = bs_error_set(err, BS_EINPUT, "'%s': the solver state (%lld, %g) is out of range: a damaged checkpoint", p,
                      (long long)full, ck->carry.eta);
  ck->v = ck->x + n3;
  ck->prev.d = ck->x + 2 * n3;
  ck->hist.h = ck->x + 3 * n3;
  const size_t head = ck->version == 3 ? CK_HEAD3 : CK_HEAD;
  memcpy(ck->x, b + head, sizeof(double) * (3 * n3 + nh));
  if (!st) st = read_previous(p, b + CK_HEADER + CK_TOTALS + CK_CARRY, &ck->prev, err);
  if (!st && ck->version != 3) st = read_history(p, b + CK_HEAD3, s, &ck->hist, err);
  static const char *what[4] = {"position", "velocity", "previous step's displacement", "integrator's history"};
  for (size_t i = 0; i < 3 * n3 + nh && !st; i++)
    if (!isfinite(ck->x[i]))
      st = bs_error_set(err, BS_EINPUT, "'%s': the %s of vertex %zu is not finite", p, what[i < 3 * n3 ? i / n3 : 3],
                        ((i < 3 * n3 ? i : i - 3 * n3) % n3) / 3);
  return st;
}

int bs_checkpoint_read(const char *dir, const bs_sim *s, uint64_t scene_hash, bs_checkpoint *ck, bs_error *err) {
  memset(ck, 0, sizeof *ck);
  char p[BS_MAX_PATH + 32];
  snprintf(p, sizeof p, "%s/checkpoint.bin", dir);
  unsigned char *b;
  size_t n = 0;
  int st = slurp(p, &b, &n, err);
  if (st) return st;
  st = check_header(p, b, n, s, scene_hash, ck, err);
  uint64_t h = 0;
  if (!st) memcpy(&h, b + n - 8, 8);
  if (!st && h != bs_fnv1a(BS_FNV_SEED, b, n - 8))
    st = bs_error_set(err, BS_EINPUT, "'%s': the checksum does not match: a damaged checkpoint", p);
  if (!st) st = read_body(p, b, s, ck, err);
  free(b);
  if (st) bs_checkpoint_free(ck);
  return st;
}

void bs_checkpoint_free(bs_checkpoint *ck) {
  free(ck->x);
  ck->x = ck->v = ck->prev.d = ck->hist.h = NULL;
}
