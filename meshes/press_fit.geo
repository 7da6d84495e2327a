// Press fit meshed the ordinary way: the quarter slice of meshes/shrink_fit.geo (x, y >= 0, thickness
// t along z; a solid pin of radius b + delta in a ring with hole radius b and outer radius c), in
// unstructured tetrahedra (3D Delaunay, no extrusion, no matched arcs): size h_pin on the pin's
// curved face, h_ring on the ring's bore, h_far at the ring's outer face and the pin's centre.
// order = 2 gives 10-node tetrahedra whose midside nodes lie on the cylinders (curved contact
// surfaces, docs/press_fit.md); order = 1 the flat facets whose chords cut inside them.
// A variant sets its own values before including this file (DefineConstant keeps them).
// Volumes: "pin", "ring". Surfaces: "pin_outer", "ring_inner", "ring_outer", "symmetry_x" (x = 0),
// "symmetry_y" (y = 0), "flat" (z = 0 and z = t).
SetFactory("OpenCASCADE");
DefineConstant[
  b = {0.020, Name "hole radius"},
  delta = {15e-6, Name "radial interference"},
  c = {0.040, Name "ring outer radius"},
  t = {0.002, Name "slice thickness"},
  h_pin = {1.0e-3, Name "element size on the pin's curved face"},
  h_ring = {1.5e-3, Name "element size on the ring's bore"},
  h_far = {3e-3, Name "element size away from the interface"},
  order = {1, Name "element order (1: 4-node, 2: 10-node tetrahedra)"}
];
rp = b + delta;
eps = 1e-6;  // OpenCASCADE widens bounding boxes by 1e-7 and more: extents are compared with t
Box(1) = {0, 0, 0, 2 * c, 2 * c, t};
Cylinder(2) = {0, 0, 0, 0, 0, t, rp};
BooleanIntersection(3) = { Volume{2}; Delete; }{ Volume{1}; };
Cylinder(4) = {0, 0, 0, 0, 0, t, c};
Cylinder(5) = {0, 0, 0, 0, 0, t, b};
BooleanDifference(6) = { Volume{4}; Delete; }{ Volume{5}; Delete; };
BooleanIntersection(7) = { Volume{6}; Delete; }{ Volume{1}; Delete; };
MeshSize{ PointsOf{ Volume{3, 7}; } } = h_far;
MeshSize{ Point In BoundingBox{rp - eps, -eps, -eps, rp + eps, eps, t + eps} } = h_pin;
MeshSize{ Point In BoundingBox{-eps, rp - eps, -eps, eps, rp + eps, t + eps} } = h_pin;
MeshSize{ Point In BoundingBox{b - eps, -eps, -eps, b + eps, eps, t + eps} } = h_ring;
MeshSize{ Point In BoundingBox{-eps, b - eps, -eps, eps, b + eps, t + eps} } = h_ring;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 1;
Mesh.ElementOrder = order;
Physical Volume("pin") = {3};
Physical Volume("ring") = {7};
Physical Surface("flat") = Surface In BoundingBox{-eps, -eps, -eps, c + eps, c + eps, eps};
Physical Surface("flat") += Surface In BoundingBox{-eps, -eps, t - eps, c + eps, c + eps, t + eps};
Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -eps, eps, c + eps, t + eps};
Physical Surface("symmetry_y") = Surface In BoundingBox{-eps, -eps, -eps, c + eps, eps, t + eps};
pin_outer[] = {}; ring_inner[] = {}; ring_outer[] = {};
faces[] = Boundary{ Volume{3}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]); bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > t && bb[4] - bb[1] > t && bb[5] - bb[2] > t / 2)
    pin_outer[] += {f};
  EndIf
EndFor
faces[] = Boundary{ Volume{7}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]); bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > t && bb[4] - bb[1] > t && bb[5] - bb[2] > t / 2)
    If (bb[3] < b + 10 * eps)
      ring_inner[] += {f};
    Else
      ring_outer[] += {f};
    EndIf
  EndIf
EndFor
Physical Surface("pin_outer") = pin_outer[];
Physical Surface("ring_inner") = ring_inner[];
Physical Surface("ring_outer") = ring_outer[];
