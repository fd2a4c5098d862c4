/* fuzz_stl.c — .stl bytes through bs_shim_read_surface. */
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_file(data, size, ".stl", "stl", fuzz_read_surface);
  return 0;
}
