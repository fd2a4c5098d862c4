/* audit.c — auditing a list of frames with totals (bs_audit.h). */
#include <string.h>

#include "bs_audit.h"

static void add_frame(bs_audit_totals *T, const bs_audit_counts *c) {
  T->inverted += c->inverted;
  T->self_pairs += c->self_pairs;
  T->penetrating += c->penetrating;
  if (c->max_depth > T->max_depth) T->max_depth = c->max_depth;
  T->bad_frames += c->inverted > 0 || c->self_pairs > 0 || c->penetrating > 0;
}

int bs_audit_run(const bs_audit_list *L, bs_sim *sim, bs_audit_frame_fn fn, void *ctx, bs_audit_totals *T,
                 bs_error *err) {
  memset(T, 0, sizeof *T);
  bs_auditor *a = NULL;
  int rc = bs_auditor_create(sim, &a, err);
  if (rc) return rc;
  bs_error ferr;
  for (int i = 0; i < L->n; i++) {
    const bs_audit_entry *e = &L->entries[i];
    bs_audit_counts c;
    bs_error_clear(&ferr);
    int st = bs_auditor_frame(a, e->path, bs_audit_entry_time(e, sim), &c, &ferr);
    T->n_frames++;
    if (st) {
      memset(&c, 0, sizeof c);
      T->unreadable++;
    } else {
      add_frame(T, &c);
    }
    if (fn) fn(ctx, e, st, &c, &ferr);
  }
  bs_auditor_destroy(&a);
  return BS_OK;
}
