// Cattaneo-Mindlin between two elastic bodies (ball on block), half model, h = a / 6 at the contact.
refinement = 6;
symmetry_planes = 1;
Include "hertz_bodies.geo";
