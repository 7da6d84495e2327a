// Elastic block under a rigid sphere of radius R pressed by depth delta at the
// origin of its top face z = 0 (Hertz, Cattaneo-Mindlin). The contact radius is
// a = sqrt(R delta); the block reaches `extent` contact radii from the contact
// point in every direction (the half-space of the closed forms: the compliance
// lost by clamping the bottom falls like 1/extent, about 0.4 % at 160); tetrahedra
// of size h = a / refinement within 1.5 a of the contact point, growing linearly
// with slope `grade` = 2 / refinement away from it, so that a finer `refinement`
// halves every element, not only those at the contact.
//   symmetry_planes = 2: quarter model x, y >= 0, rollers on x = 0 and y = 0 (Hertz);
//   symmetry_planes = 1: half model y >= 0, rollers on y = 0 (Cattaneo-Mindlin,
//                        tangential motion along x);
//   symmetry_planes = 0: the full block (no rollers on the contact surface).
// The blocks are glued from quadrants so that the origin is a mesh vertex.
// Physical surfaces: "contact" (z = 0), "bottom" (z = -L), "symmetry_y" (y = 0,
// models with a symmetry plane), "symmetry_x" (x = 0, quarter model), "sides"
// (the other faces, free).
// Wrappers set the constants and include this file (hertz_*.geo, mindlin_*.geo).
SetFactory("OpenCASCADE");
DefineConstant[
  R = {1.0, Name "sphere radius R (m)"},
  delta = {1e-3, Name "indentation depth delta (m)"},
  refinement = {8, Name "a / h at the contact"},
  extent = {160, Name "block size / a"},
  symmetry_planes = {2, Name "2: quarter model, 1: half model, 0: full block"}
];
DefineConstant[ grade = {2 / refinement, Name "growth of h per unit distance beyond 1.5 a"} ];
a = Sqrt(R * delta);
L = extent * a;
h = a / refinement;
xmin = (symmetry_planes == 2) ? 0 : -L;
ymin = (symmetry_planes >= 1) ? 0 : -L;
If (symmetry_planes == 2)
  Box(1) = {0, 0, -L, L, L, L};
ElseIf (symmetry_planes == 1)
  Box(1) = {-L, 0, -L, L, L, L};
  Box(2) = {0, 0, -L, L, L, L};
  BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Else
  Box(1) = {-L, -L, -L, L, L, L};
  Box(2) = {0, -L, -L, L, L, L};
  Box(3) = {-L, 0, -L, L, L, L};
  Box(4) = {0, 0, -L, L, L, L};
  BooleanFragments{ Volume{1}; Delete; }{ Volume{2:4}; Delete; }
EndIf
eps = 1e-6 * L;
contact[] = Surface In BoundingBox{xmin - eps, ymin - eps, -eps, L + eps, L + eps, eps};
bottom[] = Surface In BoundingBox{xmin - eps, ymin - eps, -L - eps, L + eps, L + eps, -L + eps};
sides[] = Surface In BoundingBox{L - eps, ymin - eps, -L - eps, L + eps, L + eps, eps};
sides[] += Surface In BoundingBox{xmin - eps, L - eps, -L - eps, L + eps, L + eps, eps};
If (xmin < 0)
  sides[] += Surface In BoundingBox{-L - eps, ymin - eps, -L - eps, -L + eps, L + eps, eps};
EndIf
If (ymin < 0)
  sides[] += Surface In BoundingBox{xmin - eps, -L - eps, -L - eps, L + eps, -L + eps, eps};
EndIf
Physical Volume("body") = Volume{:};
Physical Surface("contact") = contact[];
Physical Surface("bottom") = bottom[];
Physical Surface("sides") = sides[];
If (symmetry_planes >= 1)
  Physical Surface("symmetry_y") = Surface In BoundingBox{xmin - eps, -eps, -L - eps, L + eps, eps, eps};
EndIf
If (symmetry_planes == 2)
  Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -L - eps, eps, L + eps, eps};
EndIf
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, Max(%g, %g + %g * (Sqrt(x^2 + y^2 + z^2) - %g)))", L / 4, h, h, grade, 1.5 * a);
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.Algorithm3D = 10;  // HXT: several times faster than Delaunay on the fine meshes
