// Shrink (press) fit: quarter model (x, y >= 0) of a thin slice (thickness t along z) of a
// solid pin of radius b + delta inside a ring with hole radius b and outer radius c: the pin
// overlaps the ring by delta (radial interference) as meshed, to be declared in the case file
// ([[contacts]] interference = delta; docs/press_fit.md). Cross-section meshed with triangles
// of size h; both interface arcs get n_arc equal segments, so the two faceted surfaces are
// similar polygons (non-matching: n_arc = 0, size h_if along the arcs; or n_pin > 0 segments
// on the pin's arc), extruded along z in nlay layers (tetrahedra). Bodies share no nodes.
// A variant sets its own values before including this file (DefineConstant keeps them).
// Volumes: "pin", "ring". Surfaces: "pin_outer" (pin's curved face), "ring_inner",
// "ring_outer", "symmetry_x" (x = 0), "symmetry_y" (y = 0), "flat" (z = 0 and z = t).
SetFactory("OpenCASCADE");
DefineConstant[
  b = {0.020, Name "hole radius"},
  delta = {1e-4, Name "radial interference"},
  c = {0.040, Name "ring outer radius"},
  t = {0.002, Name "slice thickness"},
  h = {1.5e-3, Name "element size"},
  h_if = {0.7e-3, Name "element size at the interface"},
  n_arc = {32, Name "if > 0: both interface arcs get n_arc equal segments"},
  n_pin = {0, Name "if > 0 (with n_arc > 0): the pin's arc gets n_pin segments (non-matching)"},
  nlay = {2, Name "layers along z"}
];
rp = b + delta;
Disk(1) = {0, 0, 0, rp};
Rectangle(2) = {0, 0, 0, c, c};
BooleanIntersection(3) = { Surface{1}; Delete; }{ Surface{2}; };
Disk(4) = {0, 0, 0, c};
Disk(5) = {0, 0, 0, b};
BooleanDifference(6) = { Surface{4}; Delete; }{ Surface{5}; Delete; };
BooleanIntersection(7) = { Surface{6}; Delete; }{ Surface{2}; Delete; };
MeshSize{ PointsOf{ Surface{3}; } } = h;
MeshSize{ PointsOf{ Surface{7}; } } = h;
eps = 1e-6;
MeshSize{ Point In BoundingBox{-eps, -eps, -eps, rp + eps, rp + eps, eps} } = h_if;
MeshSize{ Point In BoundingBox{-eps, b - eps, -eps, eps, b + eps, eps} } = h_if;
MeshSize{ Point In BoundingBox{b - eps, -eps, -eps, b + eps, eps, eps} } = h_if;
MeshSize{ Point In BoundingBox{-eps, -eps, -eps, eps, eps, eps} } = h;
If (n_arc > 0)
  arcs[] = Curve In BoundingBox{-eps, -eps, -eps, rp + eps, rp + eps, eps};
  For i In {0 : #arcs[] - 1}
    bb[] = BoundingBox Curve{arcs[i]};
    If (bb[3] - bb[0] > eps && bb[4] - bb[1] > eps)
      If (n_pin > 0 && bb[3] > b + eps)
        Transfinite Curve{arcs[i]} = n_pin + 1;
      Else
        Transfinite Curve{arcs[i]} = n_arc + 1;
      EndIf
    EndIf
  EndFor
EndIf
pin[] = Extrude {0, 0, t} { Surface{3}; Layers{nlay}; };
ring[] = Extrude {0, 0, t} { Surface{7}; Layers{nlay}; };
Physical Volume("pin") = {pin[1]};
Physical Volume("ring") = {ring[1]};
Physical Surface("flat") = Surface In BoundingBox{-eps, -eps, -eps, c + eps, c + eps, eps};
Physical Surface("flat") += Surface In BoundingBox{-eps, -eps, t - eps, c + eps, c + eps, t + eps};
Physical Surface("symmetry_x") = Surface In BoundingBox{-eps, -eps, -eps, eps, c + eps, t + eps};
Physical Surface("symmetry_y") = Surface In BoundingBox{-eps, -eps, -eps, c + eps, eps, t + eps};
pin_outer[] = {}; ring_inner[] = {}; ring_outer[] = {};
faces[] = Boundary{ Volume{pin[1]}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]); bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > eps && bb[4] - bb[1] > eps && bb[5] - bb[2] > eps)
    pin_outer[] += {f};
  EndIf
EndFor
faces[] = Boundary{ Volume{ring[1]}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]); bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > eps && bb[4] - bb[1] > eps && bb[5] - bb[2] > eps)
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
Mesh.MeshSizeFromCurvature = 0;
