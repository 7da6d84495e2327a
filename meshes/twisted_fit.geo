// A press fit as a full model (cases/twisted_fit.toml; a quarter's symmetry rollers cannot
// twist): meshes/shrink_fit.geo's solid pin of radius b + delta in a ring with hole radius b and
// outer radius c, both of length t in nlay layers, the interface arcs in n_arc segments each.
// Volumes: "pin", "ring". Surfaces: "pin_outer", "ring_inner", "ring_outer", "flat" (z = 0 and z = t).
b = 0.02;
delta = 1e-4;
c = 0.04;
t = 0.01;
h = 5e-3;
n_arc = 32;
nlay = 1;
SetFactory("OpenCASCADE");
rp = b + delta;
Disk(1) = {0, 0, 0, rp};
Disk(4) = {0, 0, 0, c};
Disk(5) = {0, 0, 0, b};
BooleanDifference(6) = { Surface{4}; Delete; }{ Surface{5}; Delete; };
MeshSize{ PointsOf{ Surface{1}; } } = h;
MeshSize{ PointsOf{ Surface{6}; } } = h;
eps = 1e-6;
arcs[] = Curve In BoundingBox{-rp - eps, -rp - eps, -eps, rp + eps, rp + eps, eps};
Transfinite Curve{arcs[]} = n_arc + 1;
pin[] = Extrude {0, 0, t} { Surface{1}; Layers{nlay}; };
ring[] = Extrude {0, 0, t} { Surface{6}; Layers{nlay}; };
Physical Volume("pin") = {pin[1]};
Physical Volume("ring") = {ring[1]};
Physical Surface("flat") = Surface In BoundingBox{-c - eps, -c - eps, -eps, c + eps, c + eps, eps};
Physical Surface("flat") += Surface In BoundingBox{-c - eps, -c - eps, t - eps, c + eps, c + eps, t + eps};
Physical Surface("pin_outer") = {pin[2]};
ring_inner[] = {}; ring_outer[] = {};
faces[] = Boundary{ Volume{ring[1]}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]); bb[] = BoundingBox Surface{f};
  If (bb[5] - bb[2] > eps)
    If (bb[3] < b + 10 * eps)
      ring_inner[] += {f};
    Else
      ring_outer[] += {f};
    EndIf
  EndIf
EndFor
Physical Surface("ring_inner") = ring_inner[];
Physical Surface("ring_outer") = ring_outer[];
