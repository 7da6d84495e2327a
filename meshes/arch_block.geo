// A non-cuboid contact body: a block (2 x 1 x 0.6 m) whose bottom is a shallow
// arch (circle segment, rise 0.05 m) touching a flat foundation x3 = 0 at x1 = 1.
// Physical surfaces: "dirichlet" (x1 = 0), "right" (x1 = 2), "top", "contact".
SetFactory("OpenCASCADE");
h = 0.15;
Point(1) = {0, 0, 0.05, h};
Point(2) = {1, 0, 10.025, h};  // centre of the arc through (0,0,0.05), (1,0,0), (2,0,0.05)
Point(3) = {2, 0, 0.05, h};
Point(4) = {2, 0, 0.6, h};
Point(5) = {0, 0, 0.6, h};
Circle(1) = {1, 2, 3};
Line(2) = {3, 4};
Line(3) = {4, 5};
Line(4) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
out[] = Extrude {0, 1, 0} { Surface{1}; };
Physical Volume("body") = {out[1]};
Physical Surface("contact") = {out[2]};
Physical Surface("right") = {out[3]};
Physical Surface("top") = {out[4]};
Physical Surface("dirichlet") = {out[5]};
Mesh.CharacteristicLengthMax = h;
