"""GetFEM 5.4 on a peer-benchmark case between deformable bodies: nodal contact on non-matching meshes.

    /usr/bin/python3 benchmarks/peers/getfem_bodies.py CASE.toml --output DIR \\
        [--lsolver mumps] [--max-res 1e-10] [--r-factor 1.0] [--option 1]

Reads a case file with ``[[bodies]]`` and ``[[contacts]]`` (:func:`common.load_bodies_case`) and
its ``.msh``, builds one GetFEM mesh, P1 displacement variable and isotropic elasticity brick per
body, and couples each contact pair with ``add_nodal_contact_between_nonmatching_meshes_brick``
(non-symmetric Alart-Curnier, ``--option 1``); ``Model.solve`` per load step; result files of
:mod:`common`.

The discretisation is not ours. GetFEM's brick is node-to-segment: each slave node is projected
onto the master surface and carries a nodal non-penetration (and Coulomb) condition on the
difference of the slave node's and the projection's displacements, with its nodal weight. Ours
is mortar (seed 000, Remark 6.2, with Wohlmuth's dual multipliers; ``docs/bodies.md``): weighted
gaps integrated over the overlap of slave and master facets. One-pass node-to-segment does not
pass the contact patch test on non-matching meshes in general (Taylor and Papadopoulos); the
mortar conditions do. ``peers_real.py`` measures both against the closed forms (patch test,
Hertz) and times each code at the tolerance where it agrees with its own tightest run.

Pitfalls, and how this driver handles them:

* Merged nodes. GetFEM's gmsh import merges coincident points, which glues two bodies that
  touch at a node (the patch test's blocks share 37 interface points). Each body gets its own
  ``gf.Mesh``, built from its cells (:meth:`common.Mesh.body`).
* Units, regions, clamped slave nodes: as ``getfem_contact.py`` (stresses in GPa; regions
  from the physical groups' nodes on the outer faces; slave faces that touch a clamped node
  are left out of the brick's region).
* Friction history. The brick has no ``w_t`` data (``getfem_contact.py``): its friction acts
  on the total relative tangential displacement. Cases whose steps change the tangential
  loading (Cattaneo-Mindlin) are refused with friction; one-step and frictionless cases mean
  the same as ours.
* Interface bug. With friction, GetFEM 5.4's Python interface of the brick reads the argument
  after ``multname_t`` only to see that it is not an integer and drops it (``gf_model_set.cc``):
  ``dataname_r`` is passed twice, and ``augmented_version`` (default 1) no longer fits in its
  argument count.
* Rollers: nodal ``add_pointwise_constraints_with_multipliers`` on the components the case
  prescribes (value times the step's load factor; ``moved`` groups all three components,
  the step's translation), on nodes that are not clamped.

Contact force: the force of the master bodies on the slave body, K u - f of the slave body
summed over its slave nodes less the prescribed components there (:func:`common.nodal_resultants`);
reactions per ``body.group`` from the same nodal forces.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import common  # noqa: E402
import getfem_contact  # noqa: E402
from getfem_contact import INTEGRATION, STRESS_UNIT  # noqa: E402

import getfem as gf  # noqa: E402

#: GetFEM's geometric transformations of first-order cells.
GEOTRANS = {"tetrahedron": "GT_PK(3,1)", "hexahedron": "GT_QK(3,1)"}


class BodyModel:
    """One body in the GetFEM model: its mesh, P1 variable ``u_<name>``, elasticity brick,
    loads and rollers, and the map from its nodes (:meth:`common.Mesh.body` order) to GetFEM's."""

    def __init__(self, md: gf.Model, body: common.Body, mesh: common.Mesh, nodes: np.ndarray):
        self.body, self.mesh, self.nodes = body, mesh, nodes
        self.var = f"u_{body.name}"
        m = gf.Mesh("empty", 3)
        m.add_convex(gf.GeoTrans(GEOTRANS[mesh.cell_type]), np.transpose(mesh.points[mesh.cells], (2, 1, 0)))
        tolerance = 1e-12 * np.abs(mesh.points).max()
        self.pid = np.asarray(m.pid_from_coords(mesh.points.T, tolerance), dtype=np.int64)
        if (self.pid < 0).any() or len(np.unique(self.pid)) != len(self.pid):
            raise RuntimeError(f"body {body.name!r}: GetFEM merged or lost nodes of its mesh")
        self.gf_mesh = m
        outer = m.outer_faces()
        self._outer = set(zip(outer[0].tolist(), outer[1].tolist()))
        self.mf = gf.MeshFem(m, 3)
        self.mf.set_classical_fem(1)
        dof_pid = np.asarray(m.pid_from_coords(self.mf.basic_dof_nodes()[:, ::3], tolerance), dtype=np.int64)
        order = np.empty(m.nbpts(), dtype=np.int64)
        order[dof_pid] = np.arange(len(dof_pid))
        self.fem_node = order[self.pid]  # our (body) node -> GetFEM's fem node (dofs 3 k .. 3 k + 2)
        volume, boundary = INTEGRATION[mesh.cell_type]
        self.mim, self.mim_b = gf.MeshIm(m, gf.Integ(volume)), gf.MeshIm(m, gf.Integ(boundary))
        self.fixed = mesh.clamped_nodes(body)
        self.regions: dict[str, int] = {}
        for number, group in enumerate(dict.fromkeys([*body.clamped, *body.traction]), start=101):
            self.region(number, mesh.group_nodes(group))
            self.regions[group] = number

        young, nu = body.young / STRESS_UNIT, body.poisson
        md.add_fem_variable(self.var, self.mf)
        self.lame = {f"lambda_{body.name}": young * nu / ((1 + nu) * (1 - 2 * nu)),
                     f"mu_{body.name}": young / (2 * (1 + nu))}
        for name, value in self.lame.items():
            md.add_initialized_data(name, [value])
        md.add_isotropic_linearized_elasticity_brick(self.mim, self.var, *self.lame)
        for group, traction in body.traction.items():
            md.add_initialized_data(self.data("t", group), traction / STRESS_UNIT)
            md.add_source_term_brick(self.mim_b, self.var, self.data("t", group), self.regions[group])
        for group in body.clamped:
            md.add_Dirichlet_condition_with_simplification(self.var, self.regions[group])
        self.rollers: list[tuple[str, int, float | None]] = []  # (group, component, value at load 1 or None: moved)
        for group, components in self.prescribed().items():
            nodes = mesh.roller_nodes(body, group)
            for c, value in components.items():
                name = self.data(f"c{c}", group)
                md.add_initialized_data(f"pt_{name}", mesh.points[nodes].ravel())
                md.add_initialized_data(f"dir_{name}", np.tile(np.eye(3)[c], len(nodes)))
                md.add_initialized_data(f"val_{name}", np.zeros(len(nodes)))
                md.add_pointwise_constraints_with_multipliers(self.var, f"pt_{name}", f"dir_{name}", f"val_{name}")
                self.rollers.append((group, c, value))

    def data(self, kind: str, group: str) -> str:
        return f"{kind}_{self.body.name}_{group}"

    def prescribed(self) -> dict[str, dict[int, float | None]]:
        """Prescribed components per group: value at load factor 1, or None (moved: the translation)."""
        out: dict[str, dict[int, float | None]] = {g: dict(c) for g, c in self.body.displacement.items()}
        for group in self.body.moved:
            out[group] = {0: None, 1: None, 2: None}
        return out

    def region(self, number: int, nodes: np.ndarray) -> None:
        """Region ``number``: the outer faces whose vertices are all in ``nodes`` (body node indices)."""
        faces = np.asarray(self.gf_mesh.faces_from_pid(self.pid[nodes]))
        keep = [i for i, key in enumerate(zip(faces[0].tolist(), faces[1].tolist())) if key in self._outer]
        self.gf_mesh.set_region(number, faces[:, keep])

    def set_step(self, md: gf.Model, load: float, translation: np.ndarray) -> None:
        for group, traction in self.body.traction.items():
            md.set_variable(self.data("t", group), load * traction / STRESS_UNIT)
        for group, c, value in self.rollers:
            size = md.variable(f"val_{self.data(f'c{c}', group)}").size
            prescribed = translation[c] if value is None else load * value
            md.set_variable(f"val_{self.data(f'c{c}', group)}", np.full(size, prescribed))

    def nodal_forces(self, md: gf.Model, u: np.ndarray) -> np.ndarray:
        """K u - f at the body's nodes (N, (n, 3)) for the loads set in the model."""
        stress = "(lambda*Trace(Grad_u)*Id(3)+mu*(Grad_u+Grad_u'))"
        lam, mu = self.lame.values()
        internal = gf.asm_generic(self.mim, 1, f"{stress}:Grad_Test_u", -1, "u", 1, self.mf, u,
                                  "lambda", 0, [lam], "mu", 0, [mu])
        external = np.zeros_like(internal)
        for group in self.body.traction:
            external += gf.asm_generic(self.mim_b, 1, "t.Test_u", self.regions[group], "u", 1, self.mf, u,
                                       "t", 0, md.variable(self.data("t", group)))
        return (internal - external).reshape(-1, 3)[self.fem_node] * STRESS_UNIT


def main() -> int:
    parser = getfem_contact.command_line(__doc__.split("\n")[0])
    parser.add_argument("--r-factor", type=float, default=1.0,
                        help="Alart-Curnier augmentation r as a multiple of the slave body's E (GetFEM's advice: ~E)")
    args = parser.parse_args()
    options = getfem_contact.set_up(args)
    case = common.load_bodies_case(args.case)
    full = common.read_msh(case.mesh)
    frictional = any(p.friction > 0 for p in case.pairs)
    if frictional and any(np.linalg.norm(t[:2] - case.steps[0][1][:2]) > 0 for _, t in case.steps):
        raise ValueError(f"{case.path}: a frictional load path with tangential translations; GetFEM's "
                         "non-matching brick has no slip history (see the module docstring)")

    md = gf.Model("real")
    bodies = {b.name: BodyModel(md, b, *full.body(b.name)) for b in case.bodies}
    slave_nodes: dict[str, list[np.ndarray]] = {}
    for k, pair in enumerate(case.pairs):
        slave, master = bodies[pair.slave[0]], bodies[pair.master[0]]
        # Slave faces that touch a clamped node stay out of the brick's region (their rows would be empty).
        faces = slave.mesh.faces[pair.slave[1]]
        faces = faces[~np.isin(faces, slave.fixed).any(axis=1)]
        slave.region(201 + k, np.unique(faces))
        master.region(301 + k, master.mesh.group_nodes(pair.master[1]))
        nodes = np.unique(faces)  # the brick adds its multipliers lambda_n_k (, lambda_t_k) itself
        slave_nodes.setdefault(slave.body.name, []).append(nodes)
        md.add_initialized_data(f"r_{k}", [args.r_factor * slave.body.young / STRESS_UNIT])
        if pair.friction > 0:
            md.add_initialized_data(f"friction_{k}", [pair.friction])
            # r twice: GetFEM 5.4's interface drops the argument after multname_t (pitfalls); no
            # room is left for augmented_version, whose default is 1.
            if args.option != 1:
                raise ValueError("--option: GetFEM 5.4's interface takes only option 1 with friction")
            md.add_nodal_contact_between_nonmatching_meshes_brick(
                slave.mim_b, master.mim_b, slave.var, master.var, f"lambda_n_{k}", f"lambda_t_{k}", f"r_{k}",
                f"r_{k}", f"friction_{k}", 201 + k, 301 + k, 1, 0)
        else:
            md.add_nodal_contact_between_nonmatching_meshes_brick(
                slave.mim_b, master.mim_b, slave.var, master.var, f"lambda_n_{k}", f"r_{k}",
                201 + k, 301 + k, 1, 0, args.option)

    per_step, status, states = [], "converged", []
    t0, c0 = time.perf_counter(), time.process_time()
    for load, translation in case.steps:
        for body in bodies.values():
            body.set_step(md, load, translation)
        its, converged = getfem_contact.newton(md, options, args.max_iter)
        per_step.append(its)
        states.append({b.var: md.variable(b.var).copy() for b in bodies.values()})
        if not converged:
            status = f"not converged in {args.max_iter} Newton iterations"
            break
    solve_time, solve_cpu = time.perf_counter() - t0, time.process_time() - c0
    wall_time = common.clock()
    peak = common.peak_memory_mib()

    # Forces of each step (the last step's loads are set for the last; earlier steps reset theirs).
    step_forces, reactions = [], {}
    u_all = np.zeros_like(full.points)
    for (load, translation), state in zip(case.steps, states):
        contact = np.zeros(3)
        for body in bodies.values():
            body.set_step(md, load, translation)
            u = state[body.var]
            nodal = body.nodal_forces(md, u)
            prescribed = {g: {c: 0.0 for c in comps} for g, comps in body.prescribed().items()}
            view = common.Body(body.body.name, body.body.young, body.body.poisson, body.body.clamped,
                               prescribed, body.body.traction, [])
            nodes = np.unique(np.concatenate(slave_nodes.get(body.body.name, [np.empty(0, np.int64)])))
            force, body_reactions = common.nodal_resultants(view, body.mesh, nodal, nodes)
            contact += force
            reactions.update({f"{body.body.name}.{g}": r for g, r in body_reactions.items()})
            u_all[body.nodes] = u.reshape(-1, 3)[body.fem_node]
        step_forces.append(contact.tolist())
    record = {
        "code": f"GetFEM 5.4.4 (nodal contact between non-matching meshes, Alart-Curnier option {args.option})",
        "case": str(case.path), "status": status,
        "dofs": 3 * len(full.points),
        "free_dofs": 3 * sum(len(b.mesh.points) - len(b.fixed) for b in bodies.values()),
        "contact_nodes": int(sum(len(n) for ns in slave_nodes.values() for n in ns)), "unknowns": int(md.nbdof()),
        "newton_iterations": int(sum(per_step)), "newton_per_step": per_step,
        "wall_time": wall_time, "solve_time": solve_time, "solve_cpu_time": solve_cpu, "peak_memory_mib": peak,
        "contact_force": step_forces[-1], "contact_force_per_step": step_forces, "reactions": reactions,
        "settings": {"lsolver": args.lsolver, "lsearch": args.lsearch, "max_res": args.max_res,
                     "r_factor": args.r_factor, "option": args.option, "stress_unit": STRESS_UNIT},
        "threads": args.threads,
    }
    common.write_result(args.output, record, full.points, u_all)
    print(f"getfem: {status}, {record['newton_iterations']} Newton {per_step}, {solve_time:.2f} s, "
          f"contact force {np.array2string(np.asarray(record['contact_force']), precision=6)}")
    return 0 if status == "converged" else 1


if __name__ == "__main__":
    sys.exit(main())
