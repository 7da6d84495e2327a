// Hertz, quarter model (x, y >= 0), h = a / 4 at the contact (R = 1 m, delta = 1 mm: a = 31.6 mm).
refinement = 4;
symmetry_planes = 2;
Include "sphere_indentation.geo";
