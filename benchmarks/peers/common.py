"""What the peer drivers share: the case they read, the mesh file, the result files they write.

Every driver (``getfem_contact.py``, ``kratos_contact.py``, ``ours_contact.py``; between deformable
bodies ``getfem_bodies.py``, ``kratos_bodies.py``) is called as

    PYTHON DRIVER.py CASE.toml --output DIR [--tol TOL] [driver options]

reads the case file (the format of ``cases/*.toml``, :mod:`contactqvi.case`: :func:`load_case`
for a body and rigid obstacles, :func:`load_bodies_case` for ``[[bodies]]``; ``mesh.file``
must be a gmsh ``.msh`` file in format 2.2 ASCII, see :func:`benchmarks.peers_real.export`)
and writes

* ``DIR/result.json``: :data:`RESULT_FIELDS` (SI units: N, m, s; memory in MiB);
* ``DIR/solution.npz``: ``x`` (N, 3) node coordinates and ``u`` (N, 3) displacement of the
  last step, rows sorted as :func:`sort_nodes` does, so files of different codes compare row
  by row (the same sort as :func:`contactqvi.tables.gather_vertex_values`).

This module imports neither DOLFINx nor a peer: the peers' processes hold only their own
libraries (their peak memory is theirs), and the case file is read with :mod:`tomllib`
(the checks are done by :func:`contactqvi.case.load_case` in ``peers_real.py`` before).
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import tomllib
import typing

import numpy as np

#: The fields of ``result.json`` (every driver writes all of them; None where a code has none).
RESULT_FIELDS = {
    "code": "name and version of the code",
    "case": "case file",
    "status": "'converged' or what went wrong",
    "dofs": "displacement dofs of the mesh (3 x nodes)",
    "free_dofs": "dofs not fixed by a Dirichlet condition",
    "contact_nodes": "nodes with a contact condition",
    "unknowns": "size of the code's Newton system (dofs + multipliers where the code has them)",
    "newton_iterations": "Newton iterations, all steps",
    "newton_per_step": "Newton iterations per load step",
    "wall_time": "seconds from the start of the process to the solution in memory (read, set-up, solve)",
    "solve_time": "seconds of the load path's solves only (set-up of the solver included, assembly of A not)",
    "solve_cpu_time": "CPU seconds (user + system, summed over ranks) of the same",
    "peak_memory_mib": "VmHWM of the process (MiB) after the solve",
    "contact_force": "total force of the obstacle on the body, or of the master bodies on the slave bodies "
                     "(N, global components), last step",
    "contact_force_per_step": "the same after each load step",
    "reactions": "reaction force of each clamped / displacement group (N)",
    "settings": "solver settings of the run",
    "threads": "threads the code's linear algebra was allowed",
}


@dataclasses.dataclass
class Case:
    """A contact case as the peers need it (fields as in :class:`contactqvi.case.ContactCase`)."""

    path: pathlib.Path
    mesh: pathlib.Path
    young: float
    poisson: float
    clamped: list[str]
    displacement: dict[str, dict[int, float]]
    traction: dict[str, np.ndarray]
    body_force: np.ndarray | None
    contact: str
    friction: float
    obstacle: dict[str, typing.Any]
    steps: list[tuple[float, np.ndarray]]

    def obstacle_distance(self, x: np.ndarray, translation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Signed distance of the points ``x`` (N, 3) to the obstacle moved by ``translation``
        and the obstacle's unit normal there (pointing to the body's side), as
        :mod:`contactqvi.obstacles` (plane and sphere)."""
        kind = self.obstacle["type"]
        if kind == "plane":
            n = np.asarray(self.obstacle["normal"], float)
            n = n / np.linalg.norm(n)
            p = np.asarray(self.obstacle["point"], float) + translation
            return (x - p) @ n, np.broadcast_to(n, x.shape).copy()
        if kind == "sphere":
            c = np.asarray(self.obstacle["center"], float) + translation
            r = x - c
            dist = np.linalg.norm(r, axis=1)
            return dist - float(self.obstacle["radius"]), r / dist[:, None]
        raise NotImplementedError(f"obstacle type {kind!r}: the peer drivers know 'plane' and 'sphere'")


def _read(path: str | os.PathLike) -> tuple[pathlib.Path, dict[str, typing.Any], pathlib.Path, list]:
    """The case file's path, its tables, its ``.msh`` and its steps (load factor, translation)."""
    path = pathlib.Path(path).resolve()
    data = tomllib.loads(path.read_text())
    mesh = path.parent / data["mesh"]["file"]
    if mesh.suffix != ".msh":
        raise ValueError(f"{path}: the peer drivers read .msh files; export {mesh} first (peers_real.py does)")
    steps = [(float(s.get("load", 1.0)), np.asarray(s.get("translation", (0.0, 0.0, 0.0)), float))
             for s in data.get("steps", [])] or [(1.0, np.zeros(3))]
    return path, data, mesh, steps


_AXES = {"x": 0, "y": 1, "z": 2}


def _displacements(boundary: dict[str, typing.Any]) -> dict[str, dict[int, float]]:
    return {name: {_AXES[k]: float(v) for k, v in comp.items()}
            for name, comp in boundary.get("displacement", {}).items()}


def _law(table: dict[str, typing.Any], where: str) -> float:
    """The friction coefficient of a Coulomb or frictionless law (the peers run no other)."""
    law = table.get("law", "coulomb")
    if law not in ("coulomb", "frictionless"):
        raise NotImplementedError(f"{where}: contact law {law!r}: the peer drivers run Coulomb or frictionless cases")
    return float(table.get("friction", 0.0)) if law == "coulomb" else 0.0


def load_case(path: str | os.PathLike) -> Case:
    """Read a one-body case file (format of ``cases/*.toml``); ``mesh.file`` must be a ``.msh`` file."""
    path, data, mesh, steps = _read(path)
    if "bodies" in data:
        raise ValueError(f"{path}: a case with [[bodies]]: read it with load_bodies_case")
    boundary = data.get("boundary", {})
    return Case(
        path=path, mesh=mesh,
        young=float(data["material"]["young"]), poisson=float(data["material"]["poisson"]),
        clamped=list(boundary.get("clamped", [])),
        displacement=_displacements(boundary),
        traction={name: np.asarray(t, float) for name, t in boundary.get("traction", {}).items()},
        body_force=None if boundary.get("body_force") is None else np.asarray(boundary["body_force"], float),
        contact=data["contact"]["surface"], friction=_law(data["contact"], "contact"),
        obstacle=dict(data["obstacle"]), steps=steps,
    )


def is_bodies_case(path: str | os.PathLike) -> bool:
    """Whether the case file has ``[[bodies]]`` (several deformable bodies)."""
    return "bodies" in tomllib.loads(pathlib.Path(path).read_text())


@dataclasses.dataclass
class Body:
    """One ``[[bodies]]`` entry: its physical volume ``name``, material and conditions on its
    surface groups (names without the body's; displacement values are scaled by the step's
    load factor, ``moved`` groups follow the step's translation)."""

    name: str
    young: float
    poisson: float
    clamped: list[str]
    displacement: dict[str, dict[int, float]]
    traction: dict[str, np.ndarray]
    moved: list[str]


@dataclasses.dataclass
class Pair:
    """One ``[[contacts]]`` entry between two bodies: ``(body, group)`` of the slave and master."""

    slave: tuple[str, str]
    master: tuple[str, str]
    friction: float


@dataclasses.dataclass
class BodiesCase:
    """A contact case between deformable bodies (fields as in :class:`contactqvi.case.ContactCase`)."""

    path: pathlib.Path
    mesh: pathlib.Path
    bodies: list[Body]
    pairs: list[Pair]
    steps: list[tuple[float, np.ndarray]]


def load_bodies_case(path: str | os.PathLike) -> BodiesCase:
    """Read a case file with ``[[bodies]]`` and ``[[contacts]]`` between them."""
    path, data, mesh, steps = _read(path)
    bodies = []
    for body in data["bodies"]:
        boundary = body.get("boundary", {})
        bodies.append(Body(
            name=body["name"], young=float(body["material"]["young"]), poisson=float(body["material"]["poisson"]),
            clamped=list(boundary.get("clamped", [])), displacement=_displacements(boundary),
            traction={name: np.asarray(t, float) for name, t in boundary.get("traction", {}).items()},
            moved=list(boundary.get("moved", []))))
    pairs = []
    for i, pair in enumerate(data.get("contacts", [])):
        if "master" not in pair:
            raise NotImplementedError(f"contacts[{i}]: the peer drivers' body pairs need a master surface")
        pairs.append(Pair(slave=tuple(pair["slave"].split(".", 1)), master=tuple(pair["master"].split(".", 1)),
                          friction=_law(pair, f"contacts[{i}]")))
    return BodiesCase(path=path, mesh=mesh, bodies=bodies, pairs=pairs, steps=steps)


@dataclasses.dataclass
class Mesh:
    """A first-order gmsh mesh: nodes, cells and the faces of each named surface group.

    Attributes:
        points: (N, 3) node coordinates, in file order.
        cells: (M, 8) hexahedra or (M, 4) tetrahedra as rows into ``points`` (gmsh node order).
        faces: physical surface name -> (K, 4) quadrilaterals or (K, 3) triangles.
        volumes: physical volume name -> indices of its cells.
    """

    points: np.ndarray
    cells: np.ndarray
    faces: dict[str, np.ndarray]
    volumes: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)

    @property
    def cell_type(self) -> str:
        return {8: "hexahedron", 4: "tetrahedron"}[self.cells.shape[1]]

    def group_nodes(self, name: str) -> np.ndarray:
        """Sorted node indices of surface group ``name``."""
        if name not in self.faces:
            raise KeyError(f"physical group {name!r} not in the mesh (it has: {', '.join(sorted(self.faces))})")
        return np.unique(self.faces[name])

    def clamped_nodes(self, case: Case | Body) -> np.ndarray:
        """Sorted indices of the nodes of the case's clamped groups."""
        return np.unique(np.concatenate([self.group_nodes(g) for g in case.clamped] + [np.empty(0, np.int64)]))

    def roller_nodes(self, case: Case | Body, name: str) -> np.ndarray:
        """Nodes of displacement group ``name`` that are not clamped (a clamped node needs no second condition)."""
        return np.setdiff1d(self.group_nodes(name), self.clamped_nodes(case))

    def body(self, name: str) -> tuple[Mesh, np.ndarray]:
        """The mesh of physical volume ``name`` (its nodes renumbered, the faces of every surface
        group that lie on it) and the indices of its nodes in this mesh."""
        if name not in self.volumes:
            raise KeyError(f"physical volume {name!r} not in the mesh (it has: {', '.join(sorted(self.volumes))})")
        cells = self.cells[self.volumes[name]]
        nodes = np.unique(cells)
        local = np.full(len(self.points), -1, dtype=np.int64)
        local[nodes] = np.arange(len(nodes))
        faces = {group: local[f[(local[f] >= 0).all(axis=1)]] for group, f in self.faces.items()}
        return Mesh(self.points[nodes], local[cells], {g: f for g, f in faces.items() if len(f)},
                    {name: np.arange(len(cells))}), nodes


#: gmsh element type -> nodes (first order only).
_GMSH_NODES = {2: 3, 3: 4, 4: 4, 5: 8, 15: 1, 1: 2}


def read_msh(path: str | os.PathLike) -> Mesh:
    """Read a gmsh ``.msh`` file in format 2.2 ASCII (volume cells, physical surfaces)."""
    text = pathlib.Path(path).read_text()

    def section(name: str) -> list[str]:
        start = text.index(f"${name}\n") + len(name) + 2
        return text[start:text.index(f"$End{name}", start)].splitlines()

    if not section("MeshFormat")[0].startswith("2."):
        raise ValueError(f"{path}: need gmsh format 2.2 ASCII")
    names = {}
    for line in section("PhysicalNames")[1:]:
        dim, tag, name = line.split(maxsplit=2)
        names[(int(dim), int(tag))] = name.strip('"')
    node_lines = section("Nodes")[1:]
    nodes = np.array(" ".join(node_lines).split(), dtype=float).reshape(len(node_lines), 4)
    index = np.full(int(nodes[:, 0].max()) + 1, -1, dtype=np.int64)
    index[nodes[:, 0].astype(np.int64)] = np.arange(len(nodes))
    by_type: dict[int, list[list[int]]] = {}
    for line in section("Elements")[1:]:
        values = line.split()
        by_type.setdefault(int(values[1]), []).append([int(v) for v in values])
    cells, volume = None, None
    faces: dict[str, list[np.ndarray]] = {}
    for etype, rows in by_type.items():
        n_tags = rows[0][2]
        array = np.array(rows, dtype=np.int64)
        conn = index[array[:, 3 + n_tags:3 + n_tags + _GMSH_NODES[etype]]]
        physical = array[:, 3]
        if etype in (4, 5):
            if cells is not None:
                raise ValueError(f"{path}: one kind of volume cell only")
            cells, volume = conn, physical
        elif etype in (2, 3):
            for tag in np.unique(physical):
                name = names.get((2, int(tag)), str(tag))
                faces.setdefault(name, []).append(conn[physical == tag])
    volumes = {names.get((3, int(tag)), str(tag)): np.flatnonzero(volume == tag) for tag in np.unique(volume)}
    return Mesh(nodes[:, 1:].copy(), cells, {k: np.vstack(v) for k, v in faces.items()}, volumes)


def nodal_resultants(case: Case, mesh: Mesh, nodal: np.ndarray, contact_nodes: np.ndarray
                     ) -> tuple[list[float], dict[str, list[float]]]:
    """Contact force and reactions (N) from the nodal forces K u - f (N, 3) of a solution.

    K u = f + contact forces + reactions node by node: the contact force is the sum of K u - f
    over ``contact_nodes`` less the components prescribed there (a roller's reaction), a
    clamped group's reaction the sum over its nodes, a roller group's the sum of its
    prescribed components.
    """
    prescribed = np.zeros((len(mesh.points), 3), dtype=bool)
    for name, components in case.displacement.items():
        prescribed[np.ix_(mesh.roller_nodes(case, name), list(components))] = True
    contact = np.where(prescribed[contact_nodes], 0.0, nodal[contact_nodes]).sum(axis=0)
    reactions = {name: nodal[mesh.group_nodes(name)].sum(axis=0).tolist() for name in case.clamped}
    for name, components in case.displacement.items():
        nodes = mesh.roller_nodes(case, name)
        mask = np.zeros(3, dtype=bool)
        mask[list(components)] = True
        reactions[name] = np.where(mask, nodal[nodes], 0.0).sum(axis=0).tolist()
    return contact.tolist(), reactions


def sort_nodes(x: np.ndarray) -> np.ndarray:
    """The order that sorts node coordinates ``x`` (N, 3, rows in the mesh file's node order) like
    :func:`contactqvi.tables.gather_vertex_values`: by coordinate, nodes at one point (two bodies
    touching there) by their file order."""
    keys = np.round(x / max(np.abs(x).max(), 1e-300), 10)
    return np.lexsort((np.arange(len(x)), keys[:, 0], keys[:, 1], keys[:, 2]))


def peak_memory_mib() -> float:
    """VmHWM (peak resident set) of this process, MiB."""
    for line in pathlib.Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def clock() -> float:
    """Seconds since this process started (interpreter start-up and imports included)."""
    ticks = os.sysconf("SC_CLK_TCK")
    started = int(pathlib.Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19]) / ticks
    return float(pathlib.Path("/proc/uptime").read_text().split()[0]) - started


def write_result(out: str | os.PathLike, result: dict[str, typing.Any], x: np.ndarray, u: np.ndarray) -> None:
    """Write ``result.json`` (every key of :data:`RESULT_FIELDS` present) and ``solution.npz``."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    missing = [k for k in RESULT_FIELDS if k not in result]
    if missing:
        raise KeyError(f"result lacks {missing}")
    order = sort_nodes(x)
    np.savez(out / "solution.npz", x=x[order], u=u[order])
    (out / "result.json").write_text(json.dumps(_plain(result), indent=1) + "\n")


def _plain(value: typing.Any) -> typing.Any:
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value
