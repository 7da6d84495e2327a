// Hertz and Cattaneo-Mindlin between two elastic bodies: a ball of radius R resting
// on a block, both meshed (symmetry_planes = 2: quarter model x, y >= 0, rollers on
// x = 0 and y = 0; 1: half model y >= 0, rollers on y = 0). The ball's lower
// half touches the block's top face z = 0 at the origin; the bodies share no nodes
// and are meshed independently, finer on the ball (h_ball = 0.7 h) so that the
// interface is non-matching. Tetrahedra of size h = a / refinement within 1.5 a
// of the contact point, growing with slope 2 / refinement away from it; a is the
// contact radius the mesh is made for.
// Physical volumes: "block" ([0, L]^2 x [-L, 0], L = extent a; [-L, L] x [0, L] x
// [-L, 0] for the half model), "ball" (the quarter or half of the lower half-ball,
// centre (0, 0, R)).
// Physical surfaces: "top" (block, z = 0), "bottom" (block, z = -L), "sphere" (the
// ball's curved surface), "load" (the ball's flat face z = R), "symmetry_x"
// (x = 0, both bodies; quarter model), "symmetry_y" (y = 0, both bodies), "sides"
// (block, x = +-L, y = L).
// Wrappers set `refinement` and include this file (hertz_bodies_*.geo); order = 2 gives 10-node
// tetrahedra whose midside nodes lie on the sphere (quadratic elements, docs/quadratic.md).
SetFactory("OpenCASCADE");
DefineConstant[
  R = {1.0, Name "ball radius R (m)"},
  a = {0.0316, Name "contact radius the mesh is made for (m)"},
  refinement = {6, Name "a / h at the contact (block)"},
  extent = {160, Name "block size / a"},
  symmetry_planes = {2, Name "2: quarter model, 1: half model"},
  order = {1, Name "element order (1: 4-node, 2: 10-node tetrahedra)"}
];
Mesh.ElementOrder = order;
L = extent * a;
h = a / refinement;
grade = 2 / refinement;
xmin = (symmetry_planes == 2) ? 0 : -1;
Box(1) = {xmin * L, 0, -L, (1 - xmin) * L, L, L};
Sphere(2) = {0, 0, R, R};
Box(3) = {xmin * R, 0, 0, (1 - xmin) * R, R, R};
BooleanIntersection(4) = { Volume{2}; Delete; }{ Volume{3}; Delete; };
eps = 1e-6 * L;
Physical Volume("block") = {1};
Physical Volume("ball") = {4};
Physical Surface("top") = Surface In BoundingBox{xmin * L - eps, -eps, -eps, L + eps, L + eps, eps};
Physical Surface("bottom") = Surface In BoundingBox{xmin * L - eps, -eps, -L - eps, L + eps, L + eps, -L + eps};
Physical Surface("load") = Surface In BoundingBox{xmin * R - eps, -eps, R - eps, R + eps, R + eps, R + eps};
sides[] = Surface In BoundingBox{L - eps, -eps, -L - eps, L + eps, L + eps, eps};
sides[] += Surface In BoundingBox{xmin * L - eps, L - eps, -L - eps, L + eps, L + eps, eps};
If (symmetry_planes == 1)
  sides[] += Surface In BoundingBox{-L - eps, -eps, -L - eps, -L + eps, L + eps, eps};
EndIf
Physical Surface("sides") = sides[];
If (symmetry_planes == 2)
  Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -L - eps, eps, L + eps, R + eps};
EndIf
Physical Surface("symmetry_y") = Surface In BoundingBox{xmin * L - eps, -eps, -L - eps, L + eps, eps, R + eps};
ball_faces[] = Boundary{ Volume{4}; };
Physical Surface("sphere") = {};
For i In {0 : #ball_faces[] - 1}
  f = Abs(ball_faces[i]);
  bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > eps && bb[4] - bb[1] > eps && bb[5] - bb[2] > eps)
    Physical Surface("sphere") += {f};
  EndIf
EndFor
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, Max(%g, %g + %g * (Sqrt(x^2 + y^2 + z^2) - %g)))", L / 4, h, h, grade, 1.5 * a);
Field[2] = MathEval;
Field[2].F = Sprintf("Min(%g, Max(%g, %g + %g * (Sqrt(x^2 + y^2 + z^2) - %g)))", R / 4, 0.7 * h, 0.7 * h, grade, 1.5 * a);
Field[3] = Restrict;
Field[3].InField = 1;
Field[3].VolumesList = {1};
Field[3].IncludeBoundary = 1;
Field[4] = Restrict;
Field[4].InField = 2;
Field[4].VolumesList = {4};
Field[4].IncludeBoundary = 1;
Field[5] = Min;
Field[5].FieldsList = {3, 4};
Background Field = 5;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.Algorithm3D = 10;
