// Cantilever beam 1 m x 0.1 m x 0.1 m along x (OpenCASCADE): clamped end
// "clamp" at x = 0, free end "tip" at x = 1.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.1, 0.1};

Mesh.MeshSizeMax = 0.05;

e = 1e-6;
Physical Volume("body", 1) = {1};
Physical Surface("clamp", 1) = Surface In BoundingBox{-e, -e, -e, e, 0.1 + e, 0.1 + e};
Physical Surface("tip", 2)   = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 0.1 + e, 0.1 + e};
