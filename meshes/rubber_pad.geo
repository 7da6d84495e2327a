// A rubber pad (a seal or bearing pad) on a rigid base, pressed by a rigid roller:
// half model of a pad 2 W x D x H (x in [0, W], y in [0, D], z in [-H, 0]), the roller's
// axis along y above x = 0 (the symmetry plane x = 0). Tetrahedra of size h under the
// roller (x < W / 2), growing to 2 h at x = W.
// Physical surfaces: "top" (z = 0, the contact surface), "bottom" (z = -H, bonded to the
// base), "symmetry_x" (x = 0), "front" (y = 0), "back" (y = D), "side" (x = W).
SetFactory("OpenCASCADE");
DefineConstant[
  W = {0.02, Name "half width (m)"},
  D = {0.01, Name "depth along the roller (m)"},
  H = {0.01, Name "thickness (m)"},
  h = {1.25e-3, Name "element size under the roller (m)"}
];
Box(1) = {0, 0, -H, W, D, H};
Field[1] = MathEval;
Field[1].F = Sprintf("%g * (1 + 2 * x / %g)", h, W);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
eps = 1e-3 * h;
Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -H - eps, eps, D + eps, eps};
Physical Surface("side") = Surface In BoundingBox{W - eps, -eps, -H - eps, W + eps, D + eps, eps};
Physical Surface("front") = Surface In BoundingBox{-eps, -eps, -H - eps, W + eps, eps, eps};
Physical Surface("back") = Surface In BoundingBox{-eps, D - eps, -H - eps, W + eps, D + eps, eps};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -H - eps, W + eps, D + eps, -H + eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, -eps, W + eps, D + eps, eps};
Physical Volume("pad") = {1};
