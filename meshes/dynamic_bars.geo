// Two equal bars along x, [0, L] and [L + gap, 2L + gap], square section a x a, meshed apart
// (tetrahedra, size h): physical volumes "left", "right"; surfaces "interface" (their facing
// ends), "sides_y" (y = 0, a) and "sides_z" (z = 0, a) for rollers (tests/test_dynamics.py).
SetFactory("OpenCASCADE");
DefineConstant[ L = {1.0, Name "length"}, a = {0.2, Name "side"}, h = {0.1, Name "size"}, gap = {0.0, Name "gap"} ];
Box(1) = {0, 0, 0, L, a, a};
Box(2) = {L + gap, 0, 0, L, a, a};
MeshSize{ PointsOf{ Volume{1}; Volume{2}; } } = h;
eps = 1e-6;
Physical Volume("left") = {1};
Physical Volume("right") = {2};
Physical Surface("interface") = Surface In BoundingBox{L - eps, -eps, -eps, L + gap + eps, a + eps, a + eps};
sy[] = Surface In BoundingBox{-eps, -eps, -eps, 2*L + gap + eps, eps, a + eps};
sy[] += Surface In BoundingBox{-eps, a - eps, -eps, 2*L + gap + eps, a + eps, a + eps};
Physical Surface("sides_y") = sy[];
sz[] = Surface In BoundingBox{-eps, -eps, -eps, 2*L + gap + eps, a + eps, eps};
sz[] += Surface In BoundingBox{-eps, -eps, a - eps, 2*L + gap + eps, a + eps, a + eps};
Physical Surface("sides_z") = sz[];
