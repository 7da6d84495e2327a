// The body Omega(d1) of seed 000 (2 x 1 x 0.99 m, its bottom 0.01 m above the
// foundation), meshed like the paper's lev 4 (16 x 8 x 8 hexahedra), rotated
// about the x2-axis by `angle` degrees: it lies on a slope that descends along
// the rotated x1-axis, i.e. on the plane through the origin with unit normal
// n = (sin(angle), 0, cos(angle)); the rotated x1-axis is (cos(angle), 0, -sin(angle)).
// Physical surfaces (as Omega(d) of contactqvi.meshes): "dirichlet" (x1 = 0, uphill
// end), "right" (x1 = 2, downhill end), "top", "contact" (bottom), "front" (x2 = 0),
// "back" (x2 = 1).
DefineConstant[
  angle = {20, Name "slope (degrees)"},
  gap = {0.01, Name "initial gap to the slope (m)"},
  nx = {16, Name "elements along x1"},
  ny = {8, Name "elements along x2"},
  nz = {8, Name "elements across the thickness"}
];
theta = angle * Pi / 180;
n[] = {Sin(theta), 0, Cos(theta)};  // slope normal
t[] = {Cos(theta), 0, -Sin(theta)};  // rotated x1-axis, down the slope
Point(1) = {gap * n[0], 0, gap * n[2]};
Point(2) = {gap * n[0] + 2 * t[0], 0, gap * n[2] + 2 * t[2]};
Point(3) = {gap * n[0] + 2 * t[0], 1, gap * n[2] + 2 * t[2]};
Point(4) = {gap * n[0], 1, gap * n[2]};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1};
Recombine Surface{1};
out[] = Extrude {(1 - gap) * n[0], 0, (1 - gap) * n[2]} { Surface{1}; Layers{nz}; Recombine; };
Physical Volume("body") = {out[1]};
Physical Surface("contact") = {1};
Physical Surface("top") = {out[0]};
Physical Surface("front") = {out[2]};
Physical Surface("right") = {out[3]};
Physical Surface("back") = {out[4]};
Physical Surface("dirichlet") = {out[5]};
