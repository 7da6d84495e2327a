// Mesh faults (tests/test_mesh_faults.py): gmsh volume 2 in two physical volumes, so that
// DOLFINx would get each of its cells twice (a heap corruption in 0.9).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1.5, 1, 1, 1};
eps = 1e-6;
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
Physical Volume("both") = {1, 2};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Mesh.MeshSizeMax = 0.5;
