// Mesh faults (tests/test_mesh_faults.py): a block and a free point, whose node lies in no
// cell and no facet; DOLFINx leaves it out, so this mesh is fine.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Point(100) = {3, 3, 3};
eps = 1e-6;
Physical Volume("block") = {1};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Mesh.MeshSizeMax = 0.5;
