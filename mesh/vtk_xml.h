/* vtk_xml.h — what the VTK XML writers of mesh/ share (private: not
 * installed): the byte order attribute, XML attribute escaping, and one
 * appended DataArray's encoding.
 *
 * Appended data (header_type="UInt64", encoding="raw"), one array:
 *  - raw:  a UInt64 byte count, then the bytes;
 *  - zlib (compressor="vtkZLibDataCompressor", VTK's layout): a header of
 *    UInt64 words [n_blocks, block_size, last_block_size, c_0 ... c_{n-1}]
 *    (last_block_size: the uncompressed size of a partial last block, 0 when
 *    the last block is full; c_i: the compressed size of block i), then the
 *    blocks, each the zlib stream (RFC 1950) of BS_VTK_BLOCK bytes of the
 *    array (the last one shorter). An empty array is the header [0, B, 0].
 * The DataArray's offset attribute is the position of the array's first
 * header byte relative to the first byte after the '_' marker.
 *
 * Status: 0 or BS_ENOMEM / BS_EIO, with a message naming the array. */
#ifndef BS_VTK_XML_H
#define BS_VTK_XML_H

#include <stdint.h>
#include <stdio.h>

#include "bs_base.h"

/* VTK's default block size (vtkXMLWriter::BlockSize). */
#define BS_VTK_BLOCK 32768
/* zlib level of compressed output: VTK's default (vtkZLibDataCompressor). */
#define BS_VTK_ZLIB_LEVEL 5

/* "LittleEndian" or "BigEndian": this machine's. */
const char *bs__vtk_byte_order(void);

/* Writes s with &, <, >, " and ' escaped (for an attribute value); 0 or -1. */
int bs__vtk_put_escaped(FILE *fp, const char *s);

/* One appended array: the payload and, when compressed, its encoding. */
typedef struct bs_vtk_blob {
  const void *data;     /* the payload (borrowed)                           */
  uint64_t bytes;
  unsigned char *z;     /* zlib: header and blocks (owned), else NULL       */
  uint64_t encoded;     /* bytes in the appended block: 8 + bytes, or the z size */
} bs_vtk_blob;

/* Sets b for data (bytes long), compressing it with zlib when compress != 0.
 * `name` names the array in messages. */
int bs__vtk_blob_encode(bs_vtk_blob *b, const void *data, uint64_t bytes, int compress, const char *name,
                        bs_error *err);

/* Writes b's appended block; 0 or -1 (errno tells why). */
int bs__vtk_blob_write(FILE *fp, const bs_vtk_blob *b);

/* Frees b's encoding (b->z) and zeroes b. */
void bs__vtk_blob_free(bs_vtk_blob *b);

/* Writes the whitespace and the '_' that start the appended data, fp being
 * just after the <AppendedData encoding="raw"> tag: spaces up to the second
 * 8192-byte boundary after the tag (at most 16 KiB), which readers skip
 * (VTK's, meshio's, bigstep's), so that the binary bytes begin at least one
 * of VTK's 8192-byte read blocks after the block that holds the tag (why:
 * vtk_xml.c). 0 or -1. */
int bs__vtk_start_appended(FILE *fp);

/* Closes fp; on a write error before (bad != 0) or at the close, removes the
 * file and returns BS_EIO naming `what` and path. */
int bs__vtk_close(FILE *fp, int bad, const char *what, const char *path, bs_error *err);

#endif
