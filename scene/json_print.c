/* json_print.c — JSON text with two-space indents (json_print.h). */
#include <stdlib.h>
#include <string.h>

#include "json_print.h"

typedef struct buf {
  char *p;
  size_t n, cap;
  int oom;
} buf;

static void put(buf *b, const char *s, size_t n) {
  if (b->oom) return;
  if (b->n + n + 1 > b->cap) {
    size_t cap = b->cap ? b->cap : 4096;
    while (b->n + n + 1 > cap) cap *= 2;
    char *p = realloc(b->p, cap);
    if (!p) {
      b->oom = 1;
      return;
    }
    b->p = p;
    b->cap = cap;
  }
  memcpy(b->p + b->n, s, n);
  b->n += n;
  b->p[b->n] = '\0';
}

static void puts_(buf *b, const char *s) { put(b, s, strlen(s)); }

static void indent(buf *b, int depth) {
  for (int i = 0; i < depth; i++) put(b, "  ", 2);
}

/* A scalar (or an empty container) as cJSON prints it, unformatted. */
static void scalar(buf *b, const cJSON *v) {
  char *t = cJSON_PrintUnformatted(v);
  if (!t) b->oom = 1;
  else puts_(b, t);
  free(t);
}

static void key(buf *b, const char *k) {
  cJSON *s = cJSON_CreateString(k);
  if (!s) b->oom = 1;
  else scalar(b, s);
  cJSON_Delete(s);
  put(b, ": ", 2);
}

/* 1 when every element of the array is neither an object nor an array. */
static int flat(const cJSON *a) {
  for (const cJSON *e = a->child; e; e = e->next)
    if (cJSON_IsObject(e) || cJSON_IsArray(e)) return 0;
  return 1;
}

static void value(buf *b, const cJSON *v, int depth) {
  int obj = cJSON_IsObject(v);
  if ((!obj && !cJSON_IsArray(v)) || !v->child) {
    scalar(b, v);
    return;
  }
  if (!obj && flat(v)) {
    put(b, "[", 1);
    for (const cJSON *e = v->child; e; e = e->next) {
      scalar(b, e);
      if (e->next) put(b, ", ", 2);
    }
    put(b, "]", 1);
    return;
  }
  put(b, obj ? "{\n" : "[\n", 2);
  for (const cJSON *e = v->child; e; e = e->next) {
    indent(b, depth + 1);
    if (obj) key(b, e->string);
    value(b, e, depth + 1);
    put(b, e->next ? ",\n" : "\n", e->next ? 2 : 1);
  }
  indent(b, depth);
  put(b, obj ? "}" : "]", 1);
}

char *bs__json_print(const cJSON *v) {
  buf b = {0};
  value(&b, v, 0);
  put(&b, "\n", 1);
  if (b.oom) {
    free(b.p);
    return NULL;
  }
  return b.p;
}
