// Contact patch test, hexahedra on an unstructured block: the lower unit cube meshed with
// tetrahedra (size 0.3), the upper one with 3^3 transfinite hexahedra, then every cell
// subdivided into hexahedra (gmsh's SubdivisionAlgorithm 2: a tetrahedron into four, a
// hexahedron into eight). The lower block's facets at the interface z = 1 are its triangles
// cut into three quadrilaterals through the edge midpoints and the centroid: flat, convex,
// no parallelograms (the general path of the mortar integration); the upper one's are squares.
// Groups as meshes/hex_blocks.geo.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {0, 0, 1, 1, 1, 1};
eps = 1e-5;
MeshSize{ PointsOf{ Volume{1}; } } = 0.3;
Transfinite Curve{ Abs(Boundary{ Boundary{ Volume{2}; } }) } = 4;
Transfinite Surface{ Abs(Boundary{ Volume{2}; }) };
Recombine Surface{ Abs(Boundary{ Volume{2}; }) };
Transfinite Volume{2};
Recombine Volume{2};
Mesh.SubdivisionAlgorithm = 2;
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
