delta = 1.5e-05; h_pin = 0.001; h_ring = 0.0015; order = 2; 
Include "/work/main/meshes/press_fit.geo";
