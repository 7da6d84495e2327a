// Mesh faults (tests/test_mesh_faults.py): two blocks, only the lower one a physical
// volume; the group "top" lies on the upper one, so its facets are faces of no cell.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1.5, 1, 1, 1};
eps = 1e-6;
Physical Volume("lower") = {1};
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 2.5 - eps, 1 + eps, 1 + eps, 2.5 + eps};
Mesh.MeshSizeMax = 0.5;
