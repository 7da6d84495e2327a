// A 10 mm cube on a rigid plane (tests/test_failure_causes.py): faces named by where they lie.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.01, 0.01, 0.01};
Mesh.CharacteristicLengthMax = 0.005;
Physical Volume("block") = {1};
Physical Surface("symmetry_x") = {1};
Physical Surface("front") = {3};
Physical Surface("bottom") = {5};
Physical Surface("top") = {6};
