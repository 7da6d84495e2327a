// Contact patch test (Taylor-Papadopoulos, in 3D): two unit blocks stacked along z,
// meshed independently with tetrahedra of different sizes, so that the interface
// z = 1 is non-matching. The bodies share no nodes.
// Physical volumes: "lower" ([0,1]^3, h = h_lower), "upper" ([0,1]^2 x [1,2], h = h_upper).
// Physical surfaces (each spanning both blocks where it applies):
//   "bottom" (z = 0), "top" (z = 2), "interface" (z = 1: the lower block's top and
//   the upper block's bottom), "symmetry_x" (x = 0), "symmetry_y" (y = 0),
//   "sides" (x = 1 and y = 1).
SetFactory("OpenCASCADE");
DefineConstant[
  h_lower = {0.25, Name "element size of the lower block"},
  h_upper = {0.16, Name "element size of the upper block"}
];
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
MeshSize{ PointsOf{ Volume{1}; } } = h_lower;
MeshSize{ PointsOf{ Volume{2}; } } = h_upper;
eps = 1e-6;
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
Mesh.Algorithm3D = 1;
