// Elastic block under a rigid sphere of radius R pressed by depth delta at the
// origin of its top face z = 0 (Hertz, Cattaneo-Mindlin). The contact radius is
// a = sqrt(R delta); the block reaches `extent` contact radii from the contact
// point in every direction (the half-space of the closed forms: the compliance
// lost by clamping the bottom falls like 1/extent, about 0.4 % at 160); tetrahedra
// of size h = a / refinement within 1.5 a of the contact point, growing linearly
// with slope `grade` = 2 / refinement away from it, so that a finer `refinement`
// halves every element, not only those at the contact.
//   half = 0: quarter model x, y >= 0 (Hertz): symmetry planes x = 0 and y = 0;
//   half = 1: half model y >= 0 (Cattaneo-Mindlin, tangential motion along x).
// Physical surfaces: "contact" (z = 0), "bottom" (z = -L), "symmetry_y" (y = 0),
// "symmetry_x" (x = 0, quarter model only), "sides" (the other faces, free).
// Wrappers set the constants and include this file (hertz_*.geo, mindlin_*.geo).
SetFactory("OpenCASCADE");
DefineConstant[
  R = {1.0, Name "sphere radius R (m)"},
  delta = {1e-3, Name "indentation depth delta (m)"},
  refinement = {8, Name "a / h at the contact"},
  extent = {160, Name "block size / a"},
  half = {0, Name "0: quarter model, 1: half model"}
];
DefineConstant[ grade = {2 / refinement, Name "growth of h per unit distance beyond 1.5 a"} ];
a = Sqrt(R * delta);
L = extent * a;
h = a / refinement;
If (half == 1)  // two halves glued at x = 0: a vertex at the first contact point
  Box(1) = {-L, 0, -L, L, L, L};
  Box(2) = {0, 0, -L, L, L, L};
  BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
  x0 = -L;
Else
  Box(1) = {0, 0, -L, L, L, L};
  x0 = 0;
EndIf
eps = 1e-6 * L;
contact[] = Surface In BoundingBox{x0 - eps, -eps, -eps, L + eps, L + eps, eps};
bottom[] = Surface In BoundingBox{x0 - eps, -eps, -L - eps, L + eps, L + eps, -L + eps};
symmetry_y[] = Surface In BoundingBox{x0 - eps, -eps, -L - eps, L + eps, eps, eps};
symmetry_x[] = Surface In BoundingBox{-eps, -eps, -L - eps, eps, L + eps, eps};
side_x[] = Surface In BoundingBox{L - eps, -eps, -L - eps, L + eps, L + eps, eps};
side_y[] = Surface In BoundingBox{x0 - eps, L - eps, -L - eps, L + eps, L + eps, eps};
Physical Volume("body") = Volume{:};
Physical Surface("contact") = contact[];
Physical Surface("bottom") = bottom[];
Physical Surface("symmetry_y") = symmetry_y[];
If (half == 1)
  side_minus_x[] = Surface In BoundingBox{-L - eps, -eps, -L - eps, -L + eps, L + eps, eps};
  Physical Surface("sides") = {side_x[], side_y[], side_minus_x[]};
Else
  Physical Surface("symmetry_x") = symmetry_x[];
  Physical Surface("sides") = {side_x[], side_y[]};
EndIf
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, Max(%g, %g + %g * (Sqrt(x^2 + y^2 + z^2) - %g)))", L / 4, h, h, grade, 1.5 * a);
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
