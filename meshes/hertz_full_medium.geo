// Hertz and Cattaneo-Mindlin, full block: no rollers, for solvers without partial constraints on contact nodes; h = a / 16 at the contact (R = 1 m, delta = 1 mm: a = 31.6 mm).
refinement = 16;
symmetry_planes = 0;
Include "sphere_indentation.geo";
