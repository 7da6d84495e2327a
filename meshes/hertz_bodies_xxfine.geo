// Hertz between two elastic bodies (ball on block), quarter model, h = a / 34 at the contact:
// 966 942 dofs (benchmarks/hertz_bodies.py --meshes xxfine --name hertz_bodies_xxfine, on 2 ranks:
// about 20 GB in all).
refinement = 34;
Include "hertz_bodies.geo";
