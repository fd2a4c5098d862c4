/* fuzz_scene.c — scene JSON text through bs_scene_parse (no file needed). */
#include <stdlib.h>
#include <string.h>

#include "bs_scene.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *json = malloc(size + 1);
  if (!json) return 0;
  memcpy(json, data, size);
  json[size] = '\0';
  bs_scene *s = NULL;
  bs_error err = {0};
  int rc = bs_scene_parse(json, "fuzz.json", 0, NULL, &s, &err);
  free(json);
  fuzz_check("scene", rc, &err);
  bs_scene_destroy(&s);
  return 0;
}
