// Torus through a hole (Figure 12). Two volumes, y up:
//  - "plate" (tag 1): a 1.6 m x 0.1 m x 1.6 m plate in the x-z plane, top face
//    at y = 0, with a round hole of radius 0.3 m through its centre; its
//    cylindrical wall is the surface group "hole_wall";
//  - "torus" (tag 2): a solid torus lying flat (axis y) above the hole,
//    centre (0, 0.35, 0), major radius 0.25 m, minor radius 0.1 m, so that its
//    outer radius 0.35 m exceeds the hole's: it must squeeze to pass.
SetFactory("OpenCASCADE");
Box(1) = {-0.8, -0.1, -0.8, 1.6, 0.1, 1.6};
Cylinder(2) = {0, -0.2, 0, 0, 0.3, 0, 0.3};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };

Torus(4) = {0, 0, 0, 0.25, 0.1};
Rotate {{1, 0, 0}, {0, 0, 0}, Pi / 2} { Volume{4}; }
Translate {0, 0.35, 0} { Volume{4}; }

Mesh.MeshSizeMax = 0.1;
Mesh.MeshSizeFromCurvature = 12;

e = 1e-6;
Physical Volume("plate", 1) = {3};
Physical Volume("torus", 2) = {4};
Physical Surface("hole_wall", 1) = Surface In BoundingBox{-0.3 - e, -0.1 - e, -0.3 - e, 0.3 + e, e, 0.3 + e};
Physical Surface("torus_surface", 2) = {Boundary{Volume{4};}};
