// Hertz between two elastic bodies (ball on block), quarter model, h = a / 16 at the contact.
refinement = 16;
Include "hertz_bodies.geo";
