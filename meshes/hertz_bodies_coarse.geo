// Hertz between two elastic bodies (ball on block), quarter model, h = a / 6 at the contact.
refinement = 6;
Include "hertz_bodies.geo";
