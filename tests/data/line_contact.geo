// Line contact, coarse, for tests/test_support_reactions.py (the model of issue 35's
// reproduction cyl_block.geo with larger elements and 3 layers). Elastic half-cylinder
// (R = 0.05 m, axis along y at z = R + g0, lower half) on an elastic block x in [-W, W],
// z in [-D, 0], both y in [0, L]. The cross-section (x-z) is meshed with triangles, fine
// at the contact line x = z = 0 and graded away, then extruded along y in nlay layers
// (tetrahedra). The cylinder starts g0 = 1 um above the block, so that the bodies share
// no nodes. Groups: block, cyl (volumes); top, bottom, ends (y = 0 and y = L, both
// bodies), load (the cylinder's flat face), curved (its curved face).
SetFactory("OpenCASCADE");
DefineConstant[
  R = {0.05, Name "cylinder radius"},
  L = {0.02, Name "length along y"},
  W = {0.05, Name "block half-width"},
  D = {0.05, Name "block depth"},
  h = {1.5e-3, Name "element size at the contact (block)"},
  hc = {1.5e-3, Name "element size at the contact (cylinder)"},
  zone = {3e-3, Name "radius of the fine zone"},
  grade = {0.5, Name "size growth per m of distance"},
  nlay = {3, Name "layers along y"},
  g0 = {1e-6, Name "initial gap at x = 0 (m)"}
];
Rectangle(1) = {-W, -D, 0, 2*W, D};
Disk(2) = {0, R + g0, 0, R};
Rectangle(3) = {-R, g0, 0, 2*R, R};
BooleanIntersection(4) = { Surface{2}; Delete; }{ Surface{3}; Delete; };
Rotate {{1, 0, 0}, {0, 0, 0}, Pi/2} { Surface{1, 4}; }
blk[] = Extrude {0, L, 0} { Surface{1}; Layers{nlay}; };
cyl[] = Extrude {0, L, 0} { Surface{4}; Layers{nlay}; };
eps = 1e-5;
Physical Volume("block") = {blk[1]};
Physical Volume("cyl") = {cyl[1]};
Physical Surface("top") = Surface In BoundingBox{-W-eps, -eps, -eps, W+eps, L+eps, eps};
Physical Surface("bottom") = Surface In BoundingBox{-W-eps, -eps, -D-eps, W+eps, L+eps, -D+eps};
Physical Surface("ends") = Surface In BoundingBox{-W-eps, -eps, -D-eps, W+eps, eps, R+eps};
Physical Surface("ends") += Surface In BoundingBox{-W-eps, L-eps, -D-eps, W+eps, L+eps, R+eps};
Physical Surface("load") = Surface In BoundingBox{-R-eps, -eps, R+g0-eps, R+eps, L+eps, R+g0+eps};
curved[] = {};
faces[] = Boundary{ Volume{cyl[1]}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]);
  bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > eps && bb[4] - bb[1] > eps && bb[5] - bb[2] > eps)
    curved[] += {f};
  EndIf
EndFor
Physical Surface("curved") = curved[];
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, Max(%g, %g + %g * (Sqrt(x^2 + z^2) - %g)))", D/5, h, h, grade, zone);
Field[2] = MathEval;
Field[2].F = Sprintf("Min(%g, Max(%g, %g + %g * (Sqrt(x^2 + z^2) - %g)))", R/5, hc, hc, grade, zone);
Field[3] = Restrict; Field[3].InField = 1; Field[3].SurfacesList = {1}; Field[3].IncludeBoundary = 1;
Field[4] = Restrict; Field[4].InField = 2; Field[4].SurfacesList = {4}; Field[4].IncludeBoundary = 1;
Field[5] = Min; Field[5].FieldsList = {3, 4};
Background Field = 5;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
