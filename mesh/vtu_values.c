/* vtu_values.c — VTK's value types for the VTU reader: names and sizes,
 * loading one value as a double or an integer, byte swapping, and the
 * numbers of format="ascii" arrays; see vtu_internal.h. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vtu_internal.h"

static const char *const type_names[BS__VTU_NTYPES] = {"Int8",   "UInt8", "Int16",  "UInt16",  "Int32",
                                                       "UInt32", "Int64", "UInt64", "Float32", "Float64"};
static const int type_sizes[BS__VTU_NTYPES] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8};

int bs__vtu_type_parse(const char *s, bs__vtu_type *t) {
  if (!s) return -1;
  for (int i = 0; i < BS__VTU_NTYPES; i++)
    if (!strcmp(s, type_names[i])) {
      *t = (bs__vtu_type)i;
      return 0;
    }
  static const struct {
    const char *s;
    bs__vtu_type t;
  } legacy[] = {{"Float", BS__VTU_F32}, {"Double", BS__VTU_F64}, {"Int", BS__VTU_I32},
                {"Char", BS__VTU_I8},   {"UChar", BS__VTU_U8}};
  for (size_t i = 0; i < sizeof legacy / sizeof legacy[0]; i++)
    if (!strcmp(s, legacy[i].s)) {
      *t = legacy[i].t;
      return 0;
    }
  return -1;
}

const char *bs__vtu_type_name(bs__vtu_type t) { return type_names[t]; }
int bs__vtu_type_size(bs__vtu_type t) { return type_sizes[t]; }
int bs__vtu_type_is_float(bs__vtu_type t) { return t == BS__VTU_F32 || t == BS__VTU_F64; }

/* Loads value i: *kind 0 a signed or small unsigned integer (in *iv), 1 a
 * UInt64 (in *uv), 2 a float (in *fv). */
static void load(const unsigned char *data, bs__vtu_type t, size_t i, int64_t *iv, uint64_t *uv, double *fv,
                 int *kind) {
  const unsigned char *p = data + i * (size_t)type_sizes[t];
  *kind = 0;
  switch (t) {
    case BS__VTU_I8: { int8_t v; memcpy(&v, p, 1); *iv = v; break; }
    case BS__VTU_U8: { uint8_t v; memcpy(&v, p, 1); *iv = v; break; }
    case BS__VTU_I16: { int16_t v; memcpy(&v, p, 2); *iv = v; break; }
    case BS__VTU_U16: { uint16_t v; memcpy(&v, p, 2); *iv = v; break; }
    case BS__VTU_I32: { int32_t v; memcpy(&v, p, 4); *iv = v; break; }
    case BS__VTU_U32: { uint32_t v; memcpy(&v, p, 4); *iv = v; break; }
    case BS__VTU_I64: { int64_t v; memcpy(&v, p, 8); *iv = v; break; }
    case BS__VTU_U64: { memcpy(uv, p, 8); *kind = 1; break; }
    case BS__VTU_F32: { float v; memcpy(&v, p, 4); *fv = v; *kind = 2; break; }
    default: { memcpy(fv, p, 8); *kind = 2; break; }
  }
}

double bs__vtu_get_double(const unsigned char *data, bs__vtu_type t, size_t i) {
  int64_t iv = 0;
  uint64_t uv = 0;
  double fv = 0;
  int kind;
  load(data, t, i, &iv, &uv, &fv, &kind);
  return kind == 2 ? fv : kind == 1 ? (double)uv : (double)iv;
}

int bs__vtu_get_int(const unsigned char *data, bs__vtu_type t, size_t i, int64_t *out) {
  int64_t iv = 0;
  uint64_t uv = 0;
  double fv = 0;
  int kind;
  load(data, t, i, &iv, &uv, &fv, &kind);
  if (kind == 0) {
    *out = iv;
    return 0;
  }
  if (kind == 1) {
    if (uv > (uint64_t)INT64_MAX) return -1;
    *out = (int64_t)uv;
    return 0;
  }
  /* a float type: exact integers only */
  if (!(fabs(fv) < 9.0e15) || fv != floor(fv)) return -1;
  *out = (int64_t)fv;
  return 0;
}

void bs__vtu_to_doubles(const unsigned char *data, bs__vtu_type t, size_t n, double *out) {
  if (t == BS__VTU_F64) {
    memcpy(out, data, n * sizeof(double));
    return;
  }
  for (size_t i = 0; i < n; i++) out[i] = bs__vtu_get_double(data, t, i);
}

void bs__vtu_swap(unsigned char *data, size_t n, int size) {
  if (size < 2) return;
  for (size_t i = 0; i < n; i++) {
    unsigned char *p = data + i * (size_t)size;
    for (int a = 0, b = size - 1; a < b; a++, b--) {
      unsigned char c = p[a];
      p[a] = p[b];
      p[b] = c;
    }
  }
}

/* ---- ascii ----------------------------------------------------------------- */

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

/* The ranges of the integer types. */
static void int_range(bs__vtu_type t, int64_t *lo, uint64_t *hi) {
  static const int64_t los[] = {INT8_MIN, 0, INT16_MIN, 0, INT32_MIN, 0, INT64_MIN, 0};
  static const uint64_t his[] = {INT8_MAX, UINT8_MAX, INT16_MAX, UINT16_MAX, INT32_MAX, UINT32_MAX, INT64_MAX,
                                 UINT64_MAX};
  *lo = los[t];
  *hi = his[t];
}

/* Parses the token tok (NUL-terminated) as a value of type t into dst: 0,
 * or -1 when it is not a number of that type or out of its range. */
static int parse_token(const char *tok, bs__vtu_type t, unsigned char *dst) {
  char *e = NULL;
  errno = 0;
  if (bs__vtu_type_is_float(t)) {
    double v = strtod(tok, &e);
    if (e == tok || *e) return -1;
    if (t == BS__VTU_F32) {
      float f = (float)v;
      memcpy(dst, &f, 4);
    } else {
      memcpy(dst, &v, 8);
    }
    return 0;
  }
  int64_t lo;
  uint64_t hi, bits;
  int_range(t, &lo, &hi);
  if (tok[0] == '-') {
    long long s = strtoll(tok, &e, 10);
    if (e == tok || *e || errno || s < lo) return -1;
    bits = (uint64_t)(int64_t)s; /* two's complement: the low bytes are the value */
  } else {
    unsigned long long u = strtoull(tok, &e, 10);
    if (e == tok || *e || errno || u > hi) return -1;
    bits = u;
  }
  switch (type_sizes[t]) {
    case 1: { uint8_t v = (uint8_t)bits; memcpy(dst, &v, 1); break; }
    case 2: { uint16_t v = (uint16_t)bits; memcpy(dst, &v, 2); break; }
    case 4: { uint32_t v = (uint32_t)bits; memcpy(dst, &v, 4); break; }
    default: memcpy(dst, &bits, 8); break;
  }
  return 0;
}

int bs__vtu_ascii_values(const char *text, size_t len, bs__vtu_type t, uint64_t count, unsigned char **out,
                         bs_error *err) {
  *out = NULL;
  /* every value takes at least one character and a separator */
  if (count > (uint64_t)len / 2 + 1)
    return bs_error_set(err, BS_EINPUT, "its %zu characters of ascii text hold at most %llu values, expected %llu",
                        len, (unsigned long long)(len / 2 + 1), (unsigned long long)count);
  const size_t sz = (size_t)type_sizes[t];
  unsigned char *o = malloc((size_t)count * sz + 1);
  if (!o) return bs_error_set(err, BS_ENOMEM, "out of memory for %llu values", (unsigned long long)count);
  uint64_t n = 0;
  for (size_t i = 0; i < len;) {
    while (i < len && is_space(text[i])) i++;
    if (i >= len) break;
    size_t j = i;
    while (j < len && !is_space(text[j])) j++;
    char tok[64];
    size_t tl = j - i;
    if (n == count) {
      free(o);
      return bs_error_set(err, BS_EINPUT, "holds more than the %llu values expected", (unsigned long long)count);
    }
    if (tl >= sizeof tok) {
      free(o);
      return bs_error_set(err, BS_EINPUT, "value %llu ('%.24s...') is too long for a number",
                          (unsigned long long)n, text + i);
    }
    memcpy(tok, text + i, tl);
    tok[tl] = '\0';
    if (parse_token(tok, t, o + (size_t)n * sz)) {
      free(o);
      return bs_error_set(err, BS_EINPUT, "value %llu ('%s') is not %s %s", (unsigned long long)n, tok,
                          bs__vtu_type_is_float(t) ? "a number of type" : "an integer in the range of",
                          type_names[t]);
    }
    n++;
    i = j;
  }
  if (n != count) {
    free(o);
    return bs_error_set(err, BS_EINPUT, "holds %llu values, expected %llu", (unsigned long long)n,
                        (unsigned long long)count);
  }
  *out = o;
  return BS_OK;
}
