// A stack of three blocks under their own weight (tests/test_gravity_stack.py):
// "bottom" [0, 1]^2 x [0, 0.5], "middle" [0, 1]^2 x [0.5, 1], "top" [0, 1]^2 x [1, 1.5],
// meshed independently with tetrahedra of three sizes (non-matching at both
// interfaces; the bodies share no nodes). Coarse on purpose.
// Physical volumes: "bottom", "middle", "top".
// Physical surfaces: "floor" (z = 0), "joint_1" (z = 0.5: the bottom block's top and the
// middle block's bottom), "joint_2" (z = 1: the middle block's top and the top block's
// bottom), "symmetry_x" (x = 0), "symmetry_y" (y = 0), each spanning the blocks it bounds.
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.5, Name "element size of the bottom block (the middle 0.7 h, the top 0.85 h)"} ];
Box(1) = {0, 0, 0, 1, 1, 0.5};
Box(2) = {0, 0, 0.5, 1, 1, 0.5};
Box(3) = {0, 0, 1, 1, 1, 0.5};
MeshSize{ PointsOf{ Volume{1}; } } = h;
MeshSize{ PointsOf{ Volume{2}; } } = 0.7 * h;
MeshSize{ PointsOf{ Volume{3}; } } = 0.85 * h;
eps = 1e-6;
Physical Volume("bottom") = {1};
Physical Volume("middle") = {2};
Physical Volume("top") = {3};
Physical Surface("floor") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Physical Surface("joint_1") = Surface In BoundingBox{-eps, -eps, 0.5 - eps, 1 + eps, 1 + eps, 0.5 + eps};
Physical Surface("joint_2") = Surface In BoundingBox{-eps, -eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -eps, eps, 1 + eps, 1.5 + eps};
Physical Surface("symmetry_y") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, eps, 1.5 + eps};
Mesh.Algorithm3D = 1;
