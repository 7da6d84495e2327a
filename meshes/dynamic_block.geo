// A block 0.2 x 0.1 x 0.1 m on the plane z = 0: volume "block", surfaces "bottom" and "top"
// (the sliding block of tests/test_dynamics.py).
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.05, Name "size"} ];
Box(1) = {0, 0, 0, 0.2, 0.1, 0.1};
MeshSize{ PointsOf{ Volume{1}; } } = h;
eps = 1e-6;
Physical Volume("block") = {1};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 0.2 + eps, 0.1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 0.1 - eps, 0.2 + eps, 0.1 + eps, 0.1 + eps};
