// Contact patch test with HEXAHEDRA (cases/hex_patch.toml). Two unit blocks stacked along z,
// transfinite + recombined independently (n_lower, n_upper cells per edge), so the
// interface z = 1 is non-matching. The bodies share no nodes.
// Groups as meshes/patch_blocks.geo: volumes "lower", "upper"; surfaces "bottom" (z=0),
// "top" (z=2), "interface" (z=1, both blocks), "symmetry_x" (x=0), "symmetry_y" (y=0), "sides".
SetFactory("OpenCASCADE");
DefineConstant[
  n_lower = {4, Name "cells per edge, lower block"},
  n_upper = {5, Name "cells per edge, upper block"}
];
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
eps = 1e-5;
Transfinite Curve{ Abs(Boundary{ Boundary{ Volume{1}; } }) } = n_lower + 1;
Transfinite Curve{ Abs(Boundary{ Boundary{ Volume{2}; } }) } = n_upper + 1;
Transfinite Surface{ Abs(Boundary{ Volume{1}; }) };
Transfinite Surface{ Abs(Boundary{ Volume{2}; }) };
Recombine Surface{ Abs(Boundary{ Volume{1}; }) };
Recombine Surface{ Abs(Boundary{ Volume{2}; }) };
Transfinite Volume{1, 2};
Recombine Volume{1, 2};
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 2 - eps, 1 + eps, 1 + eps, 2 + eps};
Physical Surface("interface") = Surface In BoundingBox{-eps, -eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -eps, eps, 1 + eps, 2 + eps};
Physical Surface("symmetry_y") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, eps, 2 + eps};
sides[] = Surface In BoundingBox{1 - eps, -eps, -eps, 1 + eps, 1 + eps, 2 + eps};
sides[] += Surface In BoundingBox{-eps, 1 - eps, -eps, 1 + eps, 1 + eps, 2 + eps};
Physical Surface("sides") = sides[];
