// Mesh faults (tests/test_mesh_faults.py): two unit blocks stacked along z and joined by
// BooleanFragments, so that one conforming mesh shares the interface z = 1 (a body of two
// volumes, but not two bodies).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
BooleanFragments{ Volume{1, 2}; Delete; }{}
eps = 1e-6;
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 2 - eps, 1 + eps, 1 + eps, 2 + eps};
Physical Surface("interface") = Surface In BoundingBox{-eps, -eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
Mesh.MeshSizeMax = 0.5;
