/* bs_base.h — what every bigstep library shares: the error record, status
 * codes, a wall clock, and checked allocation.
 *
 * Conventions (all of bigstep):
 *  - A function that can fail returns int status: 0 (BS_OK) on success, a
 *    negative BS_E* code on error. It then has filled the caller's bs_error
 *    (when non-NULL) with a one-line message naming the file, key, element or
 *    value at fault. Nothing in a library prints, exits or aborts.
 *  - Positive return values are warnings (e.g. a solve that did not converge is
 *    reported through its statistics, not as an error).
 *  - Objects come as bs_x_create / bs_x_destroy pairs; destroy takes T **,
 *    accepts NULL and nulls the pointer. The caller owns what it creates.
 */
#ifndef BS_BASE_H
#define BS_BASE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum {
  BS_OK = 0,
  BS_EIO = -1,      /* a file is missing, unreadable or unwritable        */
  BS_EINPUT = -2,   /* malformed input: a scene key, a mesh, a value        */
  BS_ENOMEM = -3,   /* allocation failed                                    */
  BS_ENUMERIC = -4, /* NaN/Inf, a singular or degenerate quantity           */
  BS_EGMSH = -5,    /* Gmsh reported an error                               */
  BS_EINTERNAL = -6 /* an invariant was broken (a bug: please report)       */
};

#define BS_ERROR_MSG 1024

/* The longest path (bytes, with its terminating NUL) bigstep keeps: a
 * scene's mesh and output folder, a run folder's files. Longer paths are
 * refused as input errors. */
#define BS_MAX_PATH 1024

typedef struct bs_error {
  int code;                /* the status last set; 0 if none */
  char msg[BS_ERROR_MSG];  /* one line, no trailing newline  */
} bs_error;

/* Clears err (may be NULL). */
void bs_error_clear(bs_error *err);

/* Records code and a printf-style message in err (may be NULL); returns code,
 * so that `return bs_error_set(err, BS_EINPUT, "...")` reads naturally. */
int bs_error_set(bs_error *err, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Prepends "prefix: " to the message already in err (context on the way up). */
void bs_error_prefix(bs_error *err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Name of a status code ("io", "input", ...). */
const char *bs_status_name(int code);

/* Seconds on a monotonic wall clock. */
double bs_seconds(void);

/* bigstep's version, "MAJOR.MINOR.PATCH" (the CMake project version). */
const char *bs_version(void);

/* Peak resident memory in bytes (0 if unknown): of this process, or of the
 * largest child process it has waited for when that is larger (Mesh_3
 * meshes in one, bs_shim_mesh_surface). */
size_t bs_peak_rss(void);

/* Physical memory of this machine in bytes (sysconf; 0 if unknown). */
double bs_machine_memory(void);

/* calloc that records a BS_ENOMEM message naming `what` on failure. */
void *bs_calloc(size_t n, size_t size, const char *what, bs_error *err);
/* bs_calloc for large arrays (hot matrices and vectors): from 8 MiB on, the
 * memory is aligned to 2 MiB and the kernel is advised to back it with huge
 * pages (madvise MADV_HUGEPAGE, where transparent huge pages are enabled "madvise"),
 * which removes most TLB misses of scattered accesses; smaller requests are
 * bs_calloc. Free with free(). */
void *bs_calloc_large(size_t n, size_t size, const char *what, bs_error *err);

/* Strict number parsing: the whole string must be a finite number (strtod
 * syntax). 0 with *out set, else -1 and *out untouched. */
int bs_parse_double(const char *s, double *out);

/* Strict integer parsing: the whole string a base-10 integer in [lo, hi].
 * 0 with *out set, else -1 and *out untouched. */
int bs_parse_int(const char *s, long lo, long hi, int *out);

/* Creates the folder dir and its missing parents (mode 0755), like
 * `mkdir -p`: 0, or BS_EIO naming the folder that could not be made. */
int bs_mkdir_p(const char *dir, bs_error *err);

/* FNV-1a over n bytes at p, continuing from h (BS_FNV_SEED to start): the
 * checksums of checkpoint.bin and the scene's identity, the integrator's
 * mark of the state it left. */
#define BS_FNV_SEED 1469598103934665603ULL
uint64_t bs_fnv1a(uint64_t h, const void *p, size_t n);

/* qsort/bsearch comparison of two int32_t (ascending). */
int bs_cmp_i32(const void *a, const void *b);

#ifdef __cplusplus
}
#endif
#endif
