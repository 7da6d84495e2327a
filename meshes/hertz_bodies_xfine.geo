// Hertz between two elastic bodies (ball on block), quarter model, h = a / 21 at the contact.
refinement = 21;
Include "hertz_bodies.geo";
