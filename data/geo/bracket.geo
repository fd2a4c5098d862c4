// An L bracket (OpenCASCADE booleans), the CAD part among bigstep's inputs. It
// was exported once to bracket.step with
//     gmsh bracket.geo -0 -setstring Geometry.OCCTargetUnit M -o bracket.step
// The STEP file states millimetres (coordinates x 1000) and carries no physical
// groups; bigstep reads STEP and IGES with Geometry.OCCTargetUnit = "M", so the
// part comes back in metres, with default groups ("body" and one
// "surface_<tag>" per face). Units here: metres.
//  - base flange 0.10 x 0.01 x 0.06 m on y = 0, upright flange 0.01 x 0.08 x 0.06 m
//    at x = 0; a fillet of radius 0.01 m in the inner corner;
//  - a bolt hole of radius 0.008 m through the base flange at (0.065, *, 0.03).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.10, 0.01, 0.06};
Box(2) = {0, 0, 0, 0.01, 0.08, 0.06};
BooleanUnion(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };

// The inner corner edge runs along z at (0.01, 0.01).
e = 1e-6;
corner() = Curve In BoundingBox{0.01 - e, 0.01 - e, -e, 0.01 + e, 0.01 + e, 0.06 + e};
f() = Fillet{3}{corner()}{0.01};

Cylinder(5) = {0.065, -0.01, 0.03, 0, 0.03, 0, 0.008};
BooleanDifference(6) = { Volume{f(0)}; Delete; }{ Volume{5}; Delete; };

Mesh.MeshSizeMax = 0.008;
