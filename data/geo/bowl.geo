// A bowl (Figure 1 at small scale): the lower half of a thick spherical
// shell centred at (0, 1.2, 0), outer radius 1.2 m, inner radius 0.9 m. It
// touches the ground y = 0 at its lowest point; the cavity's bottom is at
// y = 0.3 m and its rim (a flat ring at y = 1.2 m) has an inner radius of
// 0.9 m. The wall is 0.3 m thick so that a body moving fast into it meets a
// penalty gradient that points back into the cavity (a thin shell could be
// stepped through at one step per frame). Units: metres. It is a collision
// object, not a simulated body: data/levelsets/bowl.bsls is its signed
// distance, made with
//     bigstep levelset data/geo/bowl.geo data/levelsets/bowl.bsls --h 0.04 --margin 0.2
SetFactory("OpenCASCADE");
Sphere(1) = {0, 1.2, 0, 1.2};
Sphere(2) = {0, 1.2, 0, 0.9};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {-1.3, 1.2, -1.3, 2.6, 1.3, 2.6};
BooleanDifference(5) = { Volume{3}; Delete; }{ Volume{4}; Delete; };

Mesh.MeshSizeMax = 0.06;

Physical Volume("bowl", 1) = {5};
Physical Surface("surface", 1) = {Boundary{Volume{5};}};
