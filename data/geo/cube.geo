// Unit cube [0, 1]^3 (OpenCASCADE). Coarse by default; `--size H` (or a
// scene's "mesh_size") overrides Mesh.MeshSizeMax.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};

Mesh.MeshSizeMax = 0.25;

e = 1e-6;
Physical Volume("body", 1) = {1};
Physical Surface("left", 1)   = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 1 + e};         // x = 0
Physical Surface("right", 2)  = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 1 + e, 1 + e};  // x = 1
Physical Surface("bottom", 3) = Surface In BoundingBox{-e, -e, -e, 1 + e, e, 1 + e};         // y = 0
Physical Surface("top", 4)    = Surface In BoundingBox{-e, 1 - e, -e, 1 + e, 1 + e, 1 + e};  // y = 1
Physical Surface("front", 5)  = Surface In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e};  // z = 1
Physical Surface("back", 6)   = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};         // z = 0
