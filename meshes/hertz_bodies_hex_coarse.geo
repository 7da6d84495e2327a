// Hertz between two elastic bodies (ball on block), quarter model, on HEXAHEDRA: the
// tetrahedra of h = a / 3 split into four hexahedra each (gmsh's SubdivisionAlgorithm 2,
// which halves the edges), h = a / 6 at the contact as hertz_bodies_coarse.geo. Its contact
// facets are triangles cut into three quadrilaterals: no parallelograms, and warped on the ball.
refinement = 3;
Include "hertz_bodies.geo";
Mesh.SubdivisionAlgorithm = 2;
