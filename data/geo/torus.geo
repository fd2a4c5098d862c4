// Solid torus in the x-y plane, centred at the origin (OpenCASCADE): major
// radius R = 0.5 m, minor radius r = 0.2 m; volume 2 pi^2 R r^2 = 0.3948 m^3.
SetFactory("OpenCASCADE");
Torus(1) = {0, 0, 0, 0.5, 0.2};

Mesh.MeshSizeMax = 0.1;

Physical Volume("body", 1) = {1};
Physical Surface("surface", 1) = {Boundary{Volume{1};}};
