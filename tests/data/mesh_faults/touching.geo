// Mesh faults (tests/test_mesh_faults.py): a half-cylinder (R = 0.5, axis along y, lower
// half) standing on a block x in [-1, 1], z in [-0.5, 0], both y in [0, 0.2], touching it
// along the line x = z = 0 (issue 35's cyl_block_touching.geo, coarse). The x-z section
// is meshed with triangles and extruded along y. Variants by the constants (set them
// before an Include): layers > 0 extrudes in that many Layers{} (gmsh's structured
// extrusion merges the two bodies' coincident nodes on the line, leaving the cylinder's
// own in its surface mesh only); fragments = 1 joins the bodies by BooleanFragments
// (the line's nodes shared); g0 > 0 starts the cylinder g0 above the block (the fix).
SetFactory("OpenCASCADE");
DefineConstant[
  layers = {2, Name "layers of the structured extrusion (0: unstructured)"},
  fragments = {0, Name "1: BooleanFragments of the two bodies"},
  g0 = {0, Name "initial gap at x = 0"}
];
R = 0.5; W = 1; D = 0.5; L = 0.2;
Rectangle(1) = {-W, -D, 0, 2*W, D};
Disk(2) = {0, R + g0, 0, R};
Rectangle(3) = {-R, g0, 0, 2*R, R};
BooleanIntersection(4) = { Surface{2}; Delete; }{ Surface{3}; Delete; };
Rotate {{1, 0, 0}, {0, 0, 0}, Pi/2} { Surface{1, 4}; }
If (layers > 0)
  blk[] = Extrude {0, L, 0} { Surface{1}; Layers{layers}; };
  cyl[] = Extrude {0, L, 0} { Surface{4}; Layers{layers}; };
Else
  blk[] = Extrude {0, L, 0} { Surface{1}; };
  cyl[] = Extrude {0, L, 0} { Surface{4}; };
EndIf
If (fragments)
  BooleanFragments{ Volume{blk[1], cyl[1]}; Delete; }{}
EndIf
eps = 1e-5;
Physical Volume("block") = {blk[1]};
Physical Volume("cyl") = {cyl[1]};
Physical Surface("top") = Surface In BoundingBox{-W-eps, -eps, -eps, W+eps, L+eps, eps};
Physical Surface("bottom") = Surface In BoundingBox{-W-eps, -eps, -D-eps, W+eps, L+eps, -D+eps};
Physical Surface("ends") = Surface In BoundingBox{-W-eps, -eps, -D-eps, W+eps, eps, R+g0+eps};
Physical Surface("ends") += Surface In BoundingBox{-W-eps, L-eps, -D-eps, W+eps, L+eps, R+g0+eps};
Physical Surface("load") = Surface In BoundingBox{-R-eps, -eps, R+g0-eps, R+eps, L+eps, R+g0+eps};
curved[] = {};
faces[] = Boundary{ Volume{cyl[1]}; };
For i In {0 : #faces[] - 1}
  f = Abs(faces[i]);
  bb[] = BoundingBox Surface{f};
  If (bb[3] - bb[0] > eps && bb[4] - bb[1] > eps && bb[5] - bb[2] > eps)
    curved[] += {f};
  EndIf
EndFor
Physical Surface("curved") = curved[];
Mesh.MeshSizeMax = 0.2;
