// A thin plate 1 m x 1 m x 2 mm (OpenCASCADE) meshed at 0.25 m: with no room
// for interior vertices, Gmsh's tets span the thickness as flat slabs, and a
// tenth of them are slivers (dihedral angles below 1 degree; the smallest is a
// few hundredths of a degree). For the stability tests: `bigstep mesh info`
// must warn about them, and a scene on this mesh must still run.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 0.002};

Mesh.MeshSizeMax = 0.25;

e = 1e-6;
Physical Volume("body", 1) = {1};
Physical Surface("left", 1)  = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 0.002 + e};         // x = 0
Physical Surface("right", 2) = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 1 + e, 0.002 + e};  // x = 1
