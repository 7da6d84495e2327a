// Cattaneo-Mindlin between two elastic bodies (ball on block), half model, h = a / 10 at the contact.
refinement = 10;
symmetry_planes = 1;
Include "hertz_bodies.geo";
