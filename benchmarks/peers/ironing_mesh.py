"""Kratos' shallow-ironing mesh as a gmsh mesh of tetrahedra for contactqvi, and back as an mdpa.

    .venv/bin/python benchmarks/peers/ironing_mesh.py [--layers 0 0.2 0.4 0.6 0.8 1.0] \\
        [--msh meshes/shallow_ironing.msh] [--mdpa build/kratos-ironing/shallow_ironing3D_tet.mdpa]

Reads ``build/kratos-ironing/shallow_ironing3D.mdpa`` (KratosMultiphysics/Examples,
``contact_structural_mechanics/validation/shallow_ironing_3D``, commit 9eacc7b): trilinear
hexahedra of two parts, the die ``Parts_Auto1`` (420 hexahedra, x in [0.2, 1.4], y in
[4.0000667, 5.2], a round tip r = 0.75) and the block ``Parts_Auto2`` (120 x 20 x 5 hexahedra,
[0, 12] x [0, 4] x [0, 1]); node sets ``Displacement_Auto1`` (the block's bottom y = 0, clamped),
``Displacement_Auto2`` (the die's top y = 5.2, moved), ``Displacement_Auto3`` (the face z = 0 of
both bodies, z fixed) and ``Contact_Auto1`` (the block's top and the die's round tip).

Each hexahedron is split into six tetrahedra, the cone from its vertex of smallest node id over
the two triangles of each of its three faces away from that vertex, a face's quadrilateral cut
by the diagonal through the face's vertex of smallest id. A face shared by two hexahedra is cut
the same way from both sides (its diagonal depends on the face's node ids only), so the
tetrahedra are conforming; no node is added: the tetrahedral mesh has Kratos' nodes.

``--layers`` keeps only the block's nodes of the listed z planes (the block is an extrusion along
z of a 120 x 20 grid, 5 layers of 0.2), each hexahedron then spanning two consecutive kept
planes; the die is kept as it is: ``--layers 0 1`` is the coarse variant with one element
through the block's thickness.

Physical groups of the ``.msh`` (gmsh 2.2 ASCII, read by :func:`contactqvi.meshes.read_gmsh` and
``benchmarks/peers/common.read_msh``): volumes ``die``, ``block``; surfaces ``top`` (the die's
top), ``bottom`` (the block's bottom), ``symmetry`` (z = 0 of both), ``contact`` (the block's
top and the die's round tip: boundary triangles whose three nodes are in ``Contact_Auto1``).
``--mdpa`` writes the same tetrahedra (``TotalLagrangianElement3D4N``) and node sets as an mdpa
for Kratos (node id = msh node id).
"""

from __future__ import annotations

import argparse
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
HEX_FACES = ((0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))
OPPOSITE_FACES = (((0, 1, 2, 3), (4, 5, 6, 7)), ((0, 1, 5, 4), (3, 2, 6, 7)), ((1, 2, 6, 5), (0, 3, 7, 4)))
PARTS = {"die": "Parts Auto1", "block": "Parts Auto2"}
NODE_SETS = {"bottom": "DISPLACEMENT_Displacement_Auto1", "top": "DISPLACEMENT_Displacement_Auto2",
             "symmetry": "DISPLACEMENT_Displacement_Auto3", "contact": "CONTACT_Contact_Auto1"}
SURFACE_TAGS = {"top": 1, "bottom": 2, "symmetry": 3, "contact": 4}
VOLUME_TAGS = {"die": 11, "block": 12}
#: gmsh 2.2 element types by dimension and node count (triangle, quadrilateral; tetrahedron, hexahedron)
GMSH_TYPES = {2: {3: 2, 4: 3}, 3: {4: 4, 8: 5}}


def read_mdpa(path: pathlib.Path) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Nodes (n, 3) in id order (ids 1..n), hexahedra per element block (0-based), node sets (0-based)."""
    nodes, elements, sets = {}, {}, {}
    section, name = None, None
    for line in path.read_text().splitlines():
        s = line.strip()
        if not s or s.startswith("//"):
            continue
        if s.startswith("Begin Nodes"):
            section = "nodes"
        elif s.startswith("Begin Elements"):
            section, name = "elements", s.split("identifier:")[1].strip()
            elements[name] = []
        elif s.startswith("Begin SubModelPart "):
            name = s.split()[2]
            sets[name] = []
        elif s.startswith("Begin SubModelPartNodes"):
            section = "set"
        elif s.startswith("Begin") or s.startswith("End"):
            section = None
        elif section == "nodes":
            a = s.split()
            nodes[int(a[0])] = [float(v) for v in a[1:4]]
        elif section == "elements":
            elements[name].append([int(v) for v in s.split()[2:]])
        elif section == "set":
            sets[name].append(int(s.split()[0]))
    ids = np.array(sorted(nodes))
    assert np.array_equal(ids, np.arange(1, len(ids) + 1)), "node ids are not 1..n"
    x = np.array([nodes[i] for i in ids])
    return (x, {k: np.asarray(v) - 1 for k, v in elements.items()},
            {k: np.asarray(v, dtype=np.int64) - 1 for k, v in sets.items()})


def keep_layers(x: np.ndarray, hexes: dict[str, np.ndarray], sets: dict[str, np.ndarray],
                layers: list[float]) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The block's mesh on the kept z planes (a hexahedron between two consecutive ones per column).

    The block is an exact extrusion of a 2D grid; the die is not (its nodes of one layer differ
    in x, y and z by up to 1e-3) and is kept as it is: the interface is then non-matching in z.
    """
    block = hexes["block"]
    z_all = np.unique(np.round(x[np.unique(block), 2], 9))
    layers = sorted(layers)
    assert all(np.isclose(z_all, z).any() for z in layers) and layers[0] == z_all[0] and layers[-1] == z_all[-1]
    key = {tuple(np.round(x[i], 9)): i for i in np.unique(block)}
    bottom = []  # the quadrilateral at z = 0 of each hexahedron of the first layer
    for cell in block:
        for a, b in OPPOSITE_FACES + tuple((b, a) for a, b in OPPOSITE_FACES):
            if np.allclose(x[cell[list(a)], 2], z_all[0]) and np.allclose(x[cell[list(b)], 2], z_all[1]):
                bottom.append(cell[list(a)])
    rows = []
    for z0, z1 in zip(layers[:-1], layers[1:]):
        for quad in bottom:
            lower = [key[tuple(np.round(x[v, :2], 9)) + (round(z0, 9),)] for v in quad]
            upper = [key[tuple(np.round(x[v, :2], 9)) + (round(z1, 9),)] for v in quad]
            rows.append(lower + upper)
    out = {"die": hexes["die"], "block": np.asarray(rows, dtype=np.int64)}
    used = np.unique(np.concatenate([c.ravel() for c in out.values()]))
    new = -np.ones(len(x), dtype=np.int64)
    new[used] = np.arange(len(used))
    return (x[used], {k: new[v] for k, v in out.items()},
            {k: new[v][new[v] >= 0] for k, v in sets.items()})


def split_hexahedra(x: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Six positively oriented tetrahedra per hexahedron, conforming between neighbours (see module)."""
    tets = []
    for cell in hexes:
        apex = cell[np.argmin(cell)]
        for face in HEX_FACES:
            quad = cell[list(face)]
            if apex in quad:
                continue
            k = int(np.argmin(quad))  # the diagonal through the face's smallest id
            a, b, c, d = (quad[(k + i) % 4] for i in range(4))
            tets += [[apex, a, b, c], [apex, a, c, d]]
    tets = np.asarray(tets)
    p = x[tets]
    volume = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    assert np.all(np.abs(volume) > 0), "degenerate tetrahedron"
    tets[volume < 0] = tets[volume < 0][:, [0, 2, 1, 3]]
    return tets


def boundary_faces(cells: np.ndarray) -> np.ndarray:
    """Faces (triangles of tetrahedra, quadrilaterals of hexahedra) that belong to one cell only."""
    local = HEX_FACES if cells.shape[1] == 8 else ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))
    faces = np.concatenate([cells[:, list(face)] for face in local])
    _, index, count = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    return faces[index[count == 1]]


def build(layers: list[float] | None = None,
          hexahedra: bool = False) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Nodes, cells per body and boundary faces per group (each body's part of it).

    The cells are the tetrahedra of :func:`split_hexahedra`, or Kratos' hexahedra as they are
    (``hexahedra``; Kratos' node order is gmsh's), the faces triangles or quadrilaterals.
    """
    x, hexes, sets = read_mdpa(ROOT / "build" / "kratos-ironing" / "shallow_ironing3D.mdpa")
    hexes = {body: hexes[part] for body, part in PARTS.items()}
    if layers is not None:
        x, hexes, sets = keep_layers(x, hexes, sets, layers)
    tets = hexes if hexahedra else {body: split_hexahedra(x, cells) for body, cells in hexes.items()}
    groups = {}
    for name, node_set in NODE_SETS.items():
        member = np.zeros(len(x), dtype=bool)
        member[sets[node_set]] = True
        rows = []
        for body in tets:
            tri = boundary_faces(tets[body])
            tri = tri[member[tri].all(axis=1)]
            if name == "contact":  # the round tip and the block's top, not the faces z = 0, 1
                normal = np.cross(x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]])
                tri = tri[np.abs(normal[:, 2]) < 1e-9 * np.linalg.norm(normal, axis=1)]
            rows.append(tri)
        groups[name] = np.concatenate(rows)
    return x, tets, groups


def write_msh(path: pathlib.Path, x: np.ndarray, tets: dict[str, np.ndarray], groups: dict[str, np.ndarray]) -> None:
    """gmsh 2.2 ASCII: one elementary entity per physical group."""
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", str(len(groups) + len(tets))]
    lines += [f'2 {SURFACE_TAGS[n]} "{n}"' for n in groups] + [f'3 {VOLUME_TAGS[n]} "{n}"' for n in tets]
    lines += ["$EndPhysicalNames", "$Nodes", str(len(x))]
    lines += [f"{i + 1} {a!r} {b!r} {c!r}" for i, (a, b, c) in enumerate(x.tolist())]
    lines += ["$EndNodes", "$Elements", str(sum(map(len, groups.values())) + sum(map(len, tets.values())))]
    number = 0
    for dim, tags, blocks in ((2, SURFACE_TAGS, groups), (3, VOLUME_TAGS, tets)):
        for name, rows in blocks.items():
            kind = GMSH_TYPES[dim][rows.shape[1]]
            for row in (rows + 1).tolist():
                number += 1
                lines.append(f"{number} {kind} 2 {tags[name]} {tags[name]} " + " ".join(map(str, row)))
    lines.append("$EndElements")
    path.write_text("\n".join(lines) + "\n")


def write_mdpa(path: pathlib.Path, x: np.ndarray, tets: dict[str, np.ndarray], groups: dict[str, np.ndarray]) -> None:
    """The same tetrahedra for Kratos, with the reference's part and sub-model part names."""
    lines = ["Begin ModelPartData", "End ModelPartData", "", "Begin Properties 0", "End Properties", "Begin Nodes"]
    lines += [f"{i + 1} {a!r} {b!r} {c!r}" for i, (a, b, c) in enumerate(x.tolist())] + ["End Nodes", ""]
    first, ranges = 1, {}
    for body, part in PARTS.items():  # properties 0, as the reference: materials are assigned per sub-model part
        lines.append("Begin Elements TotalLagrangianElement3D4N")
        lines += [f"{first + k} 0 " + " ".join(map(str, row)) for k, row in enumerate((tets[body] + 1).tolist())]
        lines += ["End Elements", ""]
        ranges[part] = (first, first + len(tets[body]))
        first += len(tets[body])
    parts = {"Parts_Parts_Auto1": ("die", PARTS["die"]), "Parts_Parts_Auto2": ("block", PARTS["block"])}
    for name, (body, part) in parts.items():
        lines += [f"Begin SubModelPart {name}", "Begin SubModelPartNodes"]
        lines += [str(i + 1) for i in np.unique(tets[body])]
        lines += ["End SubModelPartNodes", "Begin SubModelPartElements"]
        lines += [str(i) for i in range(*ranges[part])] + ["End SubModelPartElements", "End SubModelPart"]
    for group, name in NODE_SETS.items():
        nodes = np.unique(groups[group])
        lines += [f"Begin SubModelPart {name}", "Begin SubModelPartNodes"] + [str(i + 1) for i in nodes]
        lines += ["End SubModelPartNodes", "End SubModelPart"]
    path.write_text("\n".join(lines) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--layers", type=float, nargs="+", default=None, help="z planes kept (default: all six)")
    parser.add_argument("--msh", type=pathlib.Path, default=ROOT / "meshes" / "shallow_ironing.msh")
    parser.add_argument("--mdpa", type=pathlib.Path, default=None, help="also write the tetrahedra for Kratos")
    parser.add_argument("--hexahedra", action="store_true", help="Kratos' hexahedra, not split (no --mdpa)")
    args = parser.parse_args()
    if args.hexahedra and args.mdpa:
        parser.error("--mdpa writes tetrahedra: Kratos reads its own hexahedral mdpa")
    x, tets, groups = build(args.layers, args.hexahedra)
    write_msh(args.msh, x, tets, groups)
    if args.mdpa:
        write_mdpa(args.mdpa, x, tets, groups)
    cells, faces = ("hexahedra", "quadrilaterals") if args.hexahedra else ("tetrahedra", "triangles")
    print(f"{args.msh}: {len(x)} nodes, " + ", ".join(f"{b} {len(t)} {cells}" for b, t in tets.items())
          + "; " + ", ".join(f"{g} {len(t)} {faces}" for g, t in groups.items()))


if __name__ == "__main__":
    main()
