// A block slid along a longer one (sliding contact follows the bodies): the lower block
// [-1,2.6] x [0,1] x [0,0.5] (h = h_lower), the upper block [0,1] x [0,1] x [0.5,1]
// (h = h_upper), meshed independently, so the interface z = 0.5 is non-matching.
// Physical volumes "lower" and "upper"; physical surfaces "bottom" (z = 0), "top"
// (z = 1) and "interface" (z = 0.5: the lower block's top and the upper block's bottom).
SetFactory("OpenCASCADE");
DefineConstant[
  h_lower = {0.25, Name "element size of the lower block"},
  h_upper = {0.18, Name "element size of the upper block"}
];
Box(1) = {-1, 0, 0, 3.6, 1, 0.5};
Box(2) = {0, 0, 0.5, 1, 1, 0.5};
MeshSize{ PointsOf{ Volume{1}; } } = h_lower;
MeshSize{ PointsOf{ Volume{2}; } } = h_upper;
eps = 1e-6;
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Surface("bottom") = Surface In BoundingBox{-1 - eps, -eps, -eps, 2.6 + eps, 1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
Physical Surface("interface") = Surface In BoundingBox{-1 - eps, -eps, 0.5 - eps, 2.6 + eps, 1 + eps, 0.5 + eps};
Mesh.Algorithm3D = 1;
