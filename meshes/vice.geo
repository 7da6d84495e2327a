// A block clamped between two others, as in a vice: a base [0, 1]^2 x [0, 1], a jaw
// block [0.25, 0.75] x [0, 1] x [1, 1.5] in the middle and a top block [0, 1]^2 x
// [1.5, 2.5], meshed independently with tetrahedra of three sizes (non-matching at
// both interfaces); the bodies share no nodes.
// Physical volumes: "base", "middle", "top".
// Physical surfaces: "bottom" (z = 0), "joint_1" (z = 1: the base's top and the
// middle block's bottom), "joint_2" (z = 1.5: the middle block's top and the top
// block's bottom), "load" (z = 2.5), "push" (the middle block's face x = 0.25).
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.2, Name "element size of the base (the middle block 0.7 h, the top 0.85 h)"} ];
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0.25, 0, 1, 0.5, 1, 0.5};
Box(3) = {0, 0, 1.5, 1, 1, 1};
MeshSize{ PointsOf{ Volume{1}; } } = h;
MeshSize{ PointsOf{ Volume{2}; } } = 0.7 * h;
MeshSize{ PointsOf{ Volume{3}; } } = 0.85 * h;
eps = 1e-6;
Physical Volume("base") = {1};
Physical Volume("middle") = {2};
Physical Volume("top") = {3};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Physical Surface("joint_1") = Surface In BoundingBox{-eps, -eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
Physical Surface("joint_2") = Surface In BoundingBox{-eps, -eps, 1.5 - eps, 1 + eps, 1 + eps, 1.5 + eps};
Physical Surface("load") = Surface In BoundingBox{-eps, -eps, 2.5 - eps, 1 + eps, 1 + eps, 2.5 + eps};
Physical Surface("push") = Surface In BoundingBox{0.25 - eps, -eps, 1 - eps, 0.25 + eps, 1 + eps, 1.5 + eps};
Mesh.Algorithm3D = 1;
