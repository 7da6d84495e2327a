// A hexahedral block (transfinite, recombined) under a tetrahedral one, touching at z = 1:
// two bodies with cells of two kinds (DOLFINx 0.9 takes one per mesh).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
Transfinite Curve{1:12} = 3;
Transfinite Surface{1:6};
Recombine Surface{1:6};
Transfinite Volume{1};
Recombine Volume{1};
Mesh.MeshSizeMax = 0.5;
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Surface("lower_top") = {6};
Physical Surface("upper_bottom") = {11};
