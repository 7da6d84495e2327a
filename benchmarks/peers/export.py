"""The problems of ``peers_real.py`` as files every code reads: a gmsh ``.msh`` (format 2.2
ASCII, which GetFEM 5.4, our :func:`contactqvi.meshes.read_gmsh` and :func:`common.read_msh`
all read) and a case file in the format of ``cases/*.toml`` next to it.

* :func:`export_box`: the body Omega(d) of seed 000, Sect. 7 at level ``lev``, the nodes where
  :func:`contactqvi.meshes.create_contact_body` puts them (the same hexahedra, the same
  facet names), with load case L1 or L2 and F = 0.23.
* :func:`export_case`: a shipped case (``cases/hertz.toml``, ...) with its ``.geo`` meshed by
  gmsh once, so that every code reads the same nodes; ``steps`` may be replaced.
"""

from __future__ import annotations

import math
import pathlib
import tomllib
import typing

import numpy as np

#: Facet groups of the box (:data:`contactqvi.meshes.BOX_BOUNDARIES`) and its volume group.
BOX_GROUPS = {"dirichlet": 1, "right": 2, "top": 3, "contact": 4, "front": 5, "back": 6}
BODY_GROUP = 7


def box_sizes(lev: int) -> tuple[int, int, int]:
    """nx1, nx2, nx3 of seed 000, Sect. 7 (as :func:`contactqvi.meshes.contact_body_sizes`)."""
    scale = 2.0 ** (lev / 2)
    return math.ceil(4 * scale - 1e-12), math.ceil(2 * scale - 1e-12), math.ceil(2 * scale - 1e-12)


def _write_msh(path: pathlib.Path, points: np.ndarray, cells: np.ndarray, cell_type: int,
               faces: dict[str, tuple[int, np.ndarray]], face_type: int) -> None:
    """Write a first-order mesh as gmsh 2.2 ASCII: one elementary entity per physical group."""
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", str(len(faces) + 1)]
    lines += [f'2 {tag} "{name}"' for name, (tag, _) in faces.items()] + [f'3 {BODY_GROUP} "body"', "$EndPhysicalNames"]
    lines += ["$Nodes", str(len(points))]
    lines += [f"{i + 1} {x!r} {y!r} {z!r}" for i, (x, y, z) in enumerate(points.tolist())]
    lines += ["$EndNodes", "$Elements", str(len(cells) + sum(len(f) for _, f in faces.values()))]
    number = 0
    for tag, conn in faces.values():
        for row in (conn + 1).tolist():
            number += 1
            lines.append(f"{number} {face_type} 2 {tag} {tag} " + " ".join(map(str, row)))
    for row in (cells + 1).tolist():
        number += 1
        lines.append(f"{number} {cell_type} 2 {BODY_GROUP} {BODY_GROUP} " + " ".join(map(str, row)))
    lines.append("$EndElements")
    path.write_text("\n".join(lines) + "\n")


def export_box(out: pathlib.Path, lev: int, geometry: str, load: str) -> pathlib.Path:
    """Write ``box_{geometry}_{lev}.msh`` and the case ``box_{geometry}_{load}_{lev}.toml``; return the case."""
    from contactqvi.problems import coulomb as data  # the seed's data (imports DOLFINx)

    out.mkdir(parents=True, exist_ok=True)
    nx, ny, nz = box_sizes(lev)
    length, width, height = 2.0, 1.0, 1.0
    i, j, k = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij")
    x1, x2 = i.ravel() * length / nx, j.ravel() * width / ny
    s = k.ravel() / nz
    d = np.broadcast_to(data.gap_function(geometry)(x1, x2), x1.shape)
    points = np.column_stack([x1, x2, d + s * (height - d)])  # create_contact_body: x3 = d + s (H - d)

    def node(a, b, c):
        return (a * (ny + 1) + b) * (nz + 1) + c

    a, b, c = (g.ravel() for g in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    # gmsh hexahedron: bottom face 0-1-2-3 counter-clockwise, top face 4-7 above it.
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    cells = np.column_stack([node(a + i, b + j, c + k) for i, j, k in corners])

    def quads(fixed_axis: int, value: int) -> np.ndarray:
        ranges = [np.arange(nx), np.arange(ny), np.arange(nz)]
        ranges[fixed_axis] = np.array([value])
        g = [v.ravel() for v in np.meshgrid(*ranges, indexing="ij")]
        e = [np.eye(3, dtype=int)[m] for m in range(3) if m != fixed_axis]
        corners = [np.zeros(3, int), e[0], e[0] + e[1], e[1]]
        return np.column_stack([node(g[0] + o[0], g[1] + o[1], g[2] + o[2]) for o in corners])

    faces = {"dirichlet": quads(0, 0), "right": quads(0, nx), "front": quads(1, 0), "back": quads(1, ny),
             "contact": quads(2, 0), "top": quads(2, nz)}
    mesh = out / f"box_{geometry}_{lev}.msh"
    if not mesh.exists():
        _write_msh(mesh, points, cells, 5, {name: (BOX_GROUPS[name], faces[name]) for name in BOX_GROUPS}, 3)
    traction = data.tractions(load)
    case = out / f"box_{geometry}_{load}_{lev}.toml"
    case.write_text(f"""# Seed 000, Sect. 7: body {geometry} at lev {lev}, load {load}, F = {data.FRICTION}
# (written by benchmarks/peers_real.py).
[mesh]
file = "{mesh.name}"

[material]
young = {data.YOUNG!r}
poisson = {data.POISSON!r}

[boundary]
clamped = ["dirichlet"]

[boundary.traction]
top = {list(traction['top'])}
right = {list(traction['right'])}

[contact]
surface = "contact"
law = "coulomb"
friction = {data.FRICTION!r}

[obstacle]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[solver]
start = "contact"
""")
    return case


def mesh_geo(geo: pathlib.Path, msh: pathlib.Path) -> None:
    """Mesh a gmsh script once and save it as 2.2 ASCII (all elements in physical groups)."""
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(geo))
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.write(str(msh))
    finally:
        gmsh.finalize()


def export_case(out: pathlib.Path, case: pathlib.Path, name: str, mesh: pathlib.Path | None = None,
                **tables: typing.Any) -> pathlib.Path:
    """Copy the case file ``case`` to ``out/name.toml`` with its mesh (or ``mesh``, a ``.geo``
    or ``.msh``) as ``.msh`` (meshed once) and the top-level ``tables`` replaced (e.g.
    ``steps=[{"load":, "translation":}, ...]``, ``solver={...}``, ``boundary={...}``)."""
    out.mkdir(parents=True, exist_ok=True)
    data = tomllib.loads(case.read_text())
    source = pathlib.Path(mesh).resolve() if mesh is not None else (case.parent / data["mesh"]["file"]).resolve()
    msh = out / (source.stem + ".msh")
    if source.suffix == ".geo" and not msh.exists():
        mesh_geo(source, msh)
    elif source.suffix == ".msh":
        msh.write_bytes(source.read_bytes())
    data["mesh"]["file"] = msh.name
    data.update(tables)
    target = out / f"{name}.toml"
    target.write_text(f"# {case.name} with its mesh exported (written by peers_real.py)\n" + _toml(data))
    return target


def _toml(data: dict[str, typing.Any], prefix: str = "") -> str:
    """The small subset of TOML that case files use (tables, arrays of tables, scalars, lists)."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)

    lines, tables = [], []
    for key, v in data.items():
        if isinstance(v, dict):
            tables.append((key, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((key, v))
        else:
            lines.append(f"{key} = {value(v)}")
    text = "\n".join(lines) + ("\n" if lines else "")
    for key, v in tables:
        name = f"{prefix}{key}"
        if isinstance(v, dict):
            text += f"\n[{name}]\n" + _toml(v, name + ".")
        else:
            for item in v:
                text += f"\n[[{name}]]\n" + _toml(item, name + ".")
    return text
