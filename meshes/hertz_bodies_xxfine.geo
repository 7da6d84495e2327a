// Hertz between two elastic bodies (ball on block), quarter model, h = a / 34 at the contact:
// about a million dofs (benchmarks/hertz_bodies.py --meshes xxfine, on 2 ranks).
refinement = 34;
Include "hertz_bodies.geo";
