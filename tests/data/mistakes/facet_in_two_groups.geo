// A quarter strip whose group "contact" holds the surfaces of "top" and "side_x" too:
// each of those facets is in two physical groups (tests/test_named_errors.py).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.01, 0.002, 0.005};
Mesh.CharacteristicLengthMax = 0.0025;
Physical Volume("block") = {1};
Physical Surface("symmetry_x") = {1};
Physical Surface("side_x") = {2};
Physical Surface("symmetry_y") = {3};
Physical Surface("back") = {4};
Physical Surface("bottom") = {5};
Physical Surface("top") = {6};
Physical Surface("contact") = {2, 6};
