// Ball of radius 0.5 m centred at the origin (OpenCASCADE); its volume is
// 4/3 pi r^3 = 0.5236 m^3 (the mesh's is a little less: flat facets).
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 0.5};

Mesh.MeshSizeMax = 0.15;

Physical Volume("body", 1) = {1};
Physical Surface("surface", 1) = {Boundary{Volume{1};}};
