/* driver.c — the smoke driver of the fuzz harnesses (a main for the normal
 * gcc build; the libFuzzer build links the same harnesses with
 * -fsanitize=fuzzer instead, see README.md).
 *
 *   fuzz_X [--mutations N] [--save FILE] PATH...
 *
 * Runs LLVMFuzzerTestOneInput on every file given (a folder: on every file in
 * it, in name order), then on N deterministic mutations of them (the same N
 * inputs on every run and machine): bit flips, byte inserts and deletes,
 * truncations, numbers replaced by huge / negative / NaN / inf / 0 values,
 * binary words replaced by extreme values, lines duplicated or deleted, and
 * chunks copied elsewhere, one to three of them stacked. With --save each
 * input is written to FILE before it runs, so that the input of a crash can
 * be replayed. Prints one summary line; a failing input aborts the process
 * (the harness's fuzz_check, or a sanitizer). */
#define _DEFAULT_SOURCE
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz_util.h"

typedef struct {
  unsigned char *b;
  size_t n, cap;
} buf;

typedef struct {
  int n;
  char **path;
  buf *data;
} seeds;

static uint64_t rng_next(uint64_t *s) { /* xorshift64* */
  *s ^= *s >> 12;
  *s ^= *s << 25;
  *s ^= *s >> 27;
  return *s * 2685821657736338717ULL;
}

static size_t rnd(uint64_t *s, size_t n) { return n ? (size_t)(rng_next(s) % n) : 0; }

static void buf_reserve(buf *b, size_t n) {
  if (n <= b->cap) return;
  size_t cap = b->cap ? 2 * b->cap : 256;
  while (cap < n) cap *= 2;
  b->b = realloc(b->b, cap);
  if (!b->b) abort();
  b->cap = cap;
}

/* Replaces [at, at + len) by the n bytes of s. */
static void buf_splice(buf *b, size_t at, size_t len, const void *s, size_t n) {
  buf_reserve(b, b->n - len + n + 1);
  memmove(b->b + at + n, b->b + at + len, b->n - at - len);
  if (n) memcpy(b->b + at, s, n);
  b->n = b->n - len + n;
}

static int read_file(const char *path, buf *out) {
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  memset(out, 0, sizeof *out);
  unsigned char chunk[65536];
  size_t r;
  while ((r = fread(chunk, 1, sizeof chunk, f)) > 0) buf_splice(out, out->n, 0, chunk, r);
  fclose(f);
  buf_reserve(out, 1);
  return 0;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static void add_seed(seeds *s, const char *path) {
  s->path = realloc(s->path, (size_t)(s->n + 1) * sizeof *s->path);
  s->data = realloc(s->data, (size_t)(s->n + 1) * sizeof *s->data);
  if (!s->path || !s->data || read_file(path, &s->data[s->n])) {
    fprintf(stderr, "fuzz driver: cannot read %s\n", path);
    exit(2);
  }
  s->path[s->n++] = strdup(path);
}

static void add_path(seeds *s, const char *path) {
  struct stat st;
  if (stat(path, &st) != 0) {
    fprintf(stderr, "fuzz driver: no such file or folder: %s\n", path);
    exit(2);
  }
  if (!S_ISDIR(st.st_mode)) {
    add_seed(s, path);
    return;
  }
  DIR *d = opendir(path);
  struct dirent *e;
  char **names = NULL;
  int n = 0;
  while (d && (e = readdir(d))) {
    if (e->d_name[0] == '.' || strcmp(e->d_name, "README.md") == 0) continue;
    names = realloc(names, (size_t)(n + 1) * sizeof *names);
    names[n] = malloc(strlen(path) + strlen(e->d_name) + 2);
    sprintf(names[n++], "%s/%s", path, e->d_name);
  }
  if (d) closedir(d);
  if (n) qsort(names, (size_t)n, sizeof *names, cmp_str);
  for (int i = 0; i < n; i++) {
    struct stat fs;
    if (stat(names[i], &fs) == 0 && S_ISREG(fs.st_mode)) add_seed(s, names[i]);
    free(names[i]);
  }
  free(names);
}

static const char *const numbers[] = {"1e30", "-1", "nan", "inf", "-inf", "0", "99999999999999999999", "2147483648",
                                      "-2147483649", "1e308", "4294967296", "18446744073709551616", "-0", "1e-320",
                                      "3.5", "1099511627776", "9223372036854775807", "65536"};

static int is_num(unsigned char c) { return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E'; }

/* The next number of the text at or after a random place, replaced. */
static void replace_number(buf *b, uint64_t *r) {
  size_t i = rnd(r, b->n);
  while (i < b->n && !(b->b[i] >= '0' && b->b[i] <= '9')) i++;
  if (i >= b->n) return;
  while (i > 0 && is_num(b->b[i - 1])) i--;
  size_t j = i;
  while (j < b->n && is_num(b->b[j])) j++;
  const char *s = numbers[rnd(r, sizeof numbers / sizeof *numbers)];
  buf_splice(b, i, j - i, s, strlen(s));
}

/* A 4- or 8-byte word at a random place replaced by an extreme value. */
static void replace_word(buf *b, uint64_t *r) {
  static const uint64_t words[] = {0xFFFFFFFFFFFFFFFFULL, 0x7FFFFFFFULL, 0x80000000ULL, 0, 0x7FF8000000000000ULL,
                                   0x7FF0000000000000ULL, 0x4E6E6B28ULL, 0x7E37E43C8800759CULL, 0x10000000000ULL,
                                   0x0000000100000000ULL};
  size_t w = rnd(r, 2) ? 8 : 4;
  if (b->n < w) return;
  uint64_t v = words[rnd(r, sizeof words / sizeof *words)];
  memcpy(b->b + rnd(r, b->n - w + 1), &v, w);
}

/* [line start, line end + newline) around a random place. */
static void line_at(const buf *b, uint64_t *r, size_t *lo, size_t *hi) {
  size_t i = rnd(r, b->n);
  *lo = i;
  while (*lo > 0 && b->b[*lo - 1] != '\n') (*lo)--;
  *hi = i;
  while (*hi < b->n && b->b[*hi] != '\n') (*hi)++;
  if (*hi < b->n) (*hi)++;
}

static void mutate_once(buf *b, uint64_t *r) {
  static const char inserts[] = "\n -9$\"{}<>,:0.e\t#";
  size_t lo, hi;
  switch (rnd(r, 10)) {
  case 0: /* bit flips */
    for (size_t k = 0, n = 1 + rnd(r, 4); k < n && b->n; k++) b->b[rnd(r, b->n)] ^= (unsigned char)(1u << rnd(r, 8));
    break;
  case 1: { /* byte insert */
    unsigned char c = rnd(r, 2) ? (unsigned char)inserts[rnd(r, sizeof inserts - 1)] : (unsigned char)rnd(r, 256);
    buf_splice(b, rnd(r, b->n + 1), 0, &c, 1);
  } break;
  case 2: { /* byte delete */
    size_t at = rnd(r, b->n), len = 1 + rnd(r, 16);
    if (at + len > b->n) len = b->n - at;
    buf_splice(b, at, len, NULL, 0);
  } break;
  case 3: /* truncation */
    b->n = rnd(r, b->n + 1);
    break;
  case 4:
  case 5:
    replace_number(b, r);
    break;
  case 6:
    replace_word(b, r);
    break;
  case 7: /* duplicate a line */
    if (!b->n) break;
    line_at(b, r, &lo, &hi);
    {
      buf line = {0};
      buf_splice(&line, 0, 0, b->b + lo, hi - lo);
      buf_splice(b, hi, 0, line.b, line.n);
      free(line.b);
    }
    break;
  case 8: /* delete a line */
    if (!b->n) break;
    line_at(b, r, &lo, &hi);
    buf_splice(b, lo, hi - lo, NULL, 0);
    break;
  default: { /* copy a chunk elsewhere */
    if (!b->n) break;
    size_t from = rnd(r, b->n), len = 1 + rnd(r, 64);
    if (from + len > b->n) len = b->n - from;
    buf chunk = {0};
    buf_splice(&chunk, 0, 0, b->b + from, len);
    buf_splice(b, rnd(r, b->n + 1), 0, chunk.b, chunk.n);
    free(chunk.b);
  } break;
  }
}

static void run(const buf *b, const char *save) {
  if (save) {
    FILE *f = fopen(save, "wb");
    if (f) {
      fwrite(b->b, 1, b->n, f);
      fclose(f);
    }
  }
  LLVMFuzzerTestOneInput(b->b, b->n);
}

int main(int argc, char **argv) {
  long mutations = 0;
  const char *save = NULL;
  seeds s = {0};
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--mutations") == 0 && i + 1 < argc) mutations = strtol(argv[++i], NULL, 10);
    else if (strcmp(argv[i], "--save") == 0 && i + 1 < argc) save = argv[++i];
    else add_path(&s, argv[i]);
  }
  if (s.n == 0) {
    fprintf(stderr, "usage: %s [--mutations N] [--save FILE] FILE_OR_FOLDER...\n", argv[0]);
    return 2;
  }
  for (int i = 0; i < s.n; i++) run(&s.data[i], save);
  buf b = {0};
  for (long m = 0; m < mutations; m++) {
    uint64_t r = 0x9E3779B97F4A7C15ULL * (uint64_t)(m + 1) + 1;
    const buf *src = &s.data[m % s.n];
    b.n = 0;
    buf_splice(&b, 0, 0, src->b, src->n);
    for (size_t k = 0, n = 1 + rnd(&r, 3); k < n; k++) mutate_once(&b, &r);
    run(&b, save);
  }
  printf("fuzz driver: %d files and %ld mutations, no failure\n", s.n, mutations);
  for (int i = 0; i < s.n; i++) {
    free(s.path[i]);
    free(s.data[i].b);
  }
  free(s.path);
  free(s.data);
  free(b.b);
  return 0;
}
