// Hertz between two elastic bodies (ball on block), quarter model, h = a / 35 at the contact:
// about 1.06 M dofs (benchmarks/hertz_bodies.py --meshes xxfine --name hertz_bodies_xxfine, on 2 ranks).
refinement = 35;
Include "hertz_bodies.geo";
