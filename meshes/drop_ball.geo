// A quarter of a sphere of radius R (x, y >= 0; the symmetry planes x = 0 and y = 0 on rollers)
// for the drop test (cases/drop_test.toml, benchmarks/dynamics_hertz.py): volume "ball";
// surfaces "symmetry_x", "symmetry_y" and "surface" (the rest of the sphere). Tetrahedra of size
// h within "near" of the lowest point (0, 0, -R), growing to "far" beyond near + 8 far.
// The defaults: R = 0.1 m, h = 2 mm within 12.6 mm, three Hertz contact radii of a steel ball
// dropped at 1 m/s on a rigid plane (a = 4.2 mm). A file that sets h, far (or R, near) and then
// includes this one makes another mesh of it (benchmarks/dynamics_hertz.py).
SetFactory("OpenCASCADE");
DefineConstant[ R = {0.1, Name "radius"}, h = {2e-3, Name "size at contact"}, far = {0.02, Name "size far"},
                near = {0.0126, Name "refined radius"} ];
Sphere(1) = {0, 0, 0, R};
Box(2) = {0, 0, -R, R, R, 2 * R};
BooleanIntersection{ Volume{1}; Delete; }{ Volume{2}; Delete; }
eps = 1e-6;
Physical Volume("ball") = {Volume{:}};
sx[] = Surface In BoundingBox{-eps, -eps, -R - eps, eps, R + eps, R + eps};
sy[] = Surface In BoundingBox{-eps, -eps, -R - eps, R + eps, eps, R + eps};
surface[] = Surface In BoundingBox{-eps, -eps, -R - eps, R + eps, R + eps, R + eps};
surface[] -= sx[];
surface[] -= sy[];
Physical Surface("symmetry_x") = sx[];
Physical Surface("symmetry_y") = sy[];
Physical Surface("surface") = surface[];
Point(100) = {0, 0, -R};
Field[1] = Distance; Field[1].PointsList = {100};
Field[2] = Threshold; Field[2].InField = 1; Field[2].SizeMin = h; Field[2].SizeMax = far;
Field[2].DistMin = near; Field[2].DistMax = near + 8 * far;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
