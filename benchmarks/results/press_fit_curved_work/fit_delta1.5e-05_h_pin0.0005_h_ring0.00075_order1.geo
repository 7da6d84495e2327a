delta = 1.5e-05; h_pin = 0.0005; h_ring = 0.00075; order = 1; 
Include "/work/main/meshes/press_fit.geo";
