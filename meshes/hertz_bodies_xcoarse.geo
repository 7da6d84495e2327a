// Hertz between two elastic bodies (ball on block), quarter model, h = a / 4 at the contact.
refinement = 4;
Include "hertz_bodies.geo";
