// Push-out (docs/press_fit.md, "Push-out"): meshes/shrink_fit.geo lengthened to a pin and a hub
// of length L = b = 20 mm in 4 layers, coarse (h = 3 mm, 16 segments on each interface arc).
t = 0.02;
h = 3e-3;
n_arc = 16;
nlay = 4;
Include "shrink_fit.geo";
