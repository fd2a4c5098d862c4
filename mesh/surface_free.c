/* surface_free.c — bs_surface_free (bs_mesh.h): the arrays of a prepared
 * surface are the shim's, freed by it. */
#include "bs_mesh.h"
#include "bs_shim.h"

void bs_surface_free(void *p) { bs_shim_free(p); }
