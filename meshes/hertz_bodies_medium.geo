// Hertz between two elastic bodies (ball on block), quarter model, h = a / 10 at the contact.
refinement = 10;
Include "hertz_bodies.geo";
