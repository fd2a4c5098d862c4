/* vtu_internal.h — the parts of the VTU reader (bs_vtu_read.h), private to
 * mesh/:
 *   vtu_values.c  VTK value types: names, sizes, loading one value, ascii text
 *   vtu_decode.c  one DataArray's bytes: base64, the VTK block header, zlib
 *                 blocks, inline and appended (raw or base64) data
 *   vtu_read.c    the XML structure (expat handlers) into a vtu document
 *   vtu_build.c   the document into a bs_vtu: sizes, points, tets, arrays
 *   pvd_read.c    PVD collections
 *
 * Messages set by vtu_values.c and vtu_decode.c say what is wrong with the
 * data but not which file or array; vtu_build.c prefixes both. Every size
 * read from a file is checked against the bytes present before it sizes an
 * allocation. */
#ifndef BS_VTU_INTERNAL_H
#define BS_VTU_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "bs_vtu_read.h"

/* ---- value types (vtu_values.c) ------------------------------------------ */

typedef enum bs__vtu_type {
  BS__VTU_I8, BS__VTU_U8, BS__VTU_I16, BS__VTU_U16, BS__VTU_I32,
  BS__VTU_U32, BS__VTU_I64, BS__VTU_U64, BS__VTU_F32, BS__VTU_F64,
  BS__VTU_NTYPES
} bs__vtu_type;

/* "Float64" etc. (and VTK's legacy "Float", "Double", "Int", "Char",
 * "UChar") into *t: 0, or -1 for an unknown name. */
int bs__vtu_type_parse(const char *s, bs__vtu_type *t);
const char *bs__vtu_type_name(bs__vtu_type t);
int bs__vtu_type_size(bs__vtu_type t);
int bs__vtu_type_is_float(bs__vtu_type t);

/* Value i of an array of type t in the machine's byte order. */
double bs__vtu_get_double(const unsigned char *data, bs__vtu_type t, size_t i);
/* The same as an integer: 0, or -1 when it is not one (a float with a
 * fraction, or a UInt64 above INT64_MAX). */
int bs__vtu_get_int(const unsigned char *data, bs__vtu_type t, size_t i, int64_t *out);
/* n values into out (a bit-for-bit copy for Float64). */
void bs__vtu_to_doubles(const unsigned char *data, bs__vtu_type t, size_t n, double *out);
/* Reverses the bytes of each of the n values of `size` bytes at data. */
void bs__vtu_swap(unsigned char *data, size_t n, int size);

/* The whitespace-separated numbers of text[0..len) (format="ascii") as
 * exactly `count` values of type t in the machine's byte order, in *out
 * (malloc'ed, the caller frees). BS_EINPUT: fewer or more values than count,
 * a token that is not a number of type t or out of its range; BS_ENOMEM. */
int bs__vtu_ascii_values(const char *text, size_t len, bs__vtu_type t, uint64_t count, unsigned char **out,
                         bs_error *err);

/* ---- the document (vtu_read.c) ------------------------------------------- */

typedef enum bs__vtu_format { BS__VTU_ASCII, BS__VTU_BINARY, BS__VTU_APPENDED } bs__vtu_format;

typedef enum bs__vtu_section {
  BS__VTU_OTHER, /* FieldData, or anything not read */
  BS__VTU_POINTDATA, BS__VTU_CELLDATA, BS__VTU_POINTS, BS__VTU_CELLS
} bs__vtu_section;

/* One DataArray as declared. Arrays of BS__VTU_OTHER are kept only when
 * appended (their offsets delimit the base64 blocks of the others) and carry
 * no checked type or text. */
typedef struct bs__vtu_decl {
  char *name; /* the Name attribute, "" when absent */
  bs__vtu_type type;
  int ncomp;  /* NumberOfComponents, 1..1024 */
  bs__vtu_format format;
  bs__vtu_section section;
  uint64_t offset;                  /* appended: the offset attribute        */
  char *text;                       /* inline: the element's character data  */
  size_t text_len, text_cap;
} bs__vtu_decl;

typedef struct bs__vtu_doc {
  char *buf;   /* the whole file, NUL-terminated */
  size_t len;
  int header8; /* header_type="UInt64" (else UInt32)                       */
  int swap;    /* byte_order differs from the machine's                    */
  int zlib;    /* compressor="vtkZLibDataCompressor"                       */
  int64_t n_points, n_cells; /* of the one Piece                           */
  int n_piece;
  int n_arr, cap_arr;
  bs__vtu_decl *arr;
  const unsigned char *app; /* appended data: the byte after '_' ...        */
  size_t app_len;           /* ... up to </AppendedData>; app NULL if none */
  int app_base64;           /* AppendedData encoding="base64"              */
} bs__vtu_doc;

/* Reads path and parses its XML into d (zeroed first). BS_EIO (unreadable),
 * BS_EINPUT (not VTK XML, malformed, truncated), BS_ENOMEM; the message
 * names the file. On error d holds nothing to free but what
 * bs__vtu_doc_free frees. */
int bs__vtu_doc_read(const char *path, bs__vtu_doc *d, bs_error *err);
void bs__vtu_doc_free(bs__vtu_doc *d);

/* ---- decoding (vtu_decode.c) --------------------------------------------- */

/* Base64 text s[0..n) into *out (malloc'ed) and *outlen. Whitespace is
 * skipped; padding ends a group and decoding goes on with the next one, so
 * that separately encoded pieces (VTK's header, then its data) decode as
 * one. BS_EINPUT: a character outside the alphabet, '=' out of place, or
 * text ending inside a group; BS_ENOMEM. */
int bs__vtu_base64(const char *s, size_t n, unsigned char **out, size_t *outlen, bs_error *err);

/* One VTK data block at p (avail bytes): the header (a byte count, or with
 * zlib [number of blocks, block size, last block size, compressed sizes...],
 * words of the header type) and its data, which must come to exactly
 * `expect` bytes. *used: the bytes the block takes; *data: its payload,
 * pointing into p (uncompressed) or at *owned (inflated; the caller frees).
 * BS_EINPUT: truncated header or data, a size other than expect, a block that
 * claims more than deflate can expand, a zlib error; BS_ENOMEM. */
int bs__vtu_block(const bs__vtu_doc *d, const unsigned char *p, size_t avail, uint64_t expect, size_t *used,
                  const unsigned char **data, unsigned char **owned, bs_error *err);

/* The values of array a, exactly `expect` bytes in the machine's byte order,
 * whatever its format: *data points into the file's buffer or at *owned (the
 * caller frees it; NULL when nothing was allocated). Errors as above, plus
 * an appended array without <AppendedData> or with an offset past its end. */
int bs__vtu_array_bytes(const bs__vtu_doc *d, const bs__vtu_decl *a, uint64_t expect, const unsigned char **data,
                        unsigned char **owned, bs_error *err);

/* ---- assembly (vtu_build.c) ---------------------------------------------- */

/* The bs_vtu of a parsed document (takes the arrays' names out of d). */
int bs__vtu_build(const char *path, bs__vtu_doc *d, bs_vtu **out, bs_error *err);

#endif
