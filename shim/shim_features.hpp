// shim_features.hpp — sharp edges of a closed Surface_mesh and whether they
// make the surface CAD-like (not public API; C++ only). Used by the surface
// remesher (shim_remesh.cpp) and by Mesh_3 (shim_mesh3.cpp) to decide
// whether to protect features.
#ifndef BS_SHIM_FEATURES_HPP
#define BS_SHIM_FEATURES_HPP

#include <cstdint>

#include "shim_surface_mesh.hpp"

namespace bs_shim {

// The sharp edges of sm (faces turning by more than angle degrees) chained
// between the vertices where chains end or branch (closed loops as they
// are). A CAD part's sharp edges are long chains; a scan's creases are many
// short ones: the surface is taken as CAD-like when the chains of length >=
// min_length make at least 80% of the sharp edges' length, and no two sharp
// edges leave a vertex at less than BS_SHIM_FEATURE_MIN_CORNER degrees
// apart (bs_shim.h: such curves cannot be protected). Returns that answer;
// *n_long: how many such chains (0 when refused for a corner). sm is left
// as it was.
bool cad_like(Surface &sm, double angle, double min_length, int64_t *n_long);

} // namespace bs_shim

#endif
