// A unit cube of 3 x 3 x 3 hexahedra of 27 nodes (second order, complete), resting with its
// bottom face on the plane z = 0 (tests/test_quadratic_hexahedra.py: quadratic elements
// against a rigid obstacle). Physical groups: volume "block"; surfaces "bottom" (z = 0),
// "top" (z = 1), "symmetry_x" (x = 0), "symmetry_y" (y = 0).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Transfinite Curve {:} = 4;
Transfinite Surface {:};
Recombine Surface {:};
Transfinite Volume {1};
Mesh.ElementOrder = 2;
Mesh.SecondOrderIncomplete = 0;
eps = 1e-6;
Physical Volume("block") = {1};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -eps, eps, 1 + eps, 1 + eps};
Physical Surface("symmetry_y") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, eps, 1 + eps};
