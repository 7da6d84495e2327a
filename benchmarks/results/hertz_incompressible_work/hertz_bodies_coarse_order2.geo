refinement = 6;
order = 2;
Include "/work/main/meshes/hertz_bodies.geo";
