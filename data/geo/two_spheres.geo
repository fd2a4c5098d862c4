// Two balls of radius 0.5 m (Figure 7): "sphere_a" at the origin and
// "sphere_b" above it at (0.3, 1.4, 0), offset so that they hit off-centre.
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 0.5};
Sphere(2) = {0.3, 1.4, 0, 0.5};

Mesh.MeshSizeMax = 0.15;

Physical Volume("sphere_a", 1) = {1};
Physical Volume("sphere_b", 2) = {2};
Physical Surface("surface_a", 1) = {Boundary{Volume{1};}};
Physical Surface("surface_b", 2) = {Boundary{Volume{2};}};
