"""Kratos Multiphysics 10.4 on a peer-benchmark case between deformable bodies: mortar ALM contact.

    build/kratos-venv/bin/python benchmarks/peers/kratos_bodies.py CASE.toml --output DIR \\
        [--tol 1e-8] [--threads 1] [--linear-solver sparse_lu] [--move-mesh] [--substeps N] \\
        [--builder elimination] [--contact-parameters JSON]

Reads a case with ``[[bodies]]`` and ``[[contacts]]`` and its ``.msh`` (:mod:`common`), writes
Kratos' input (``DIR/kratos/bodies.mdpa``, ``materials.json``, ``ProjectParameters.json``) and
runs Kratos' ``StructuralMechanicsAnalysis`` with the contact static solver: every body its own
elements (SmallDisplacementElement3D4N / 3D8N, LinearElastic3DLaw, its E and nu) and nodes (Kratos
node id = the mesh file's node index + 1; bodies share no nodes), clamped groups, displacement
groups (value x load factor), moved groups (the step's translation), surface loads (traction x
load factor, SurfaceLoadCondition) and per pair an ``ALMContactProcess`` interface (dual mortar
augmented Lagrangian; ``Frictional`` with the Coulomb coefficient if a pair has friction,
``Frictionless`` otherwise), Eigen ``sparse_lu``, ``contact_residual_criterion`` with ``--tol``
on every ratio. One Kratos time step per load step (``--substeps`` splits it, the load ramped).
Result fields: :mod:`common`.

Pitfalls, and how this driver handles them (measured on ``patch.toml`` and ``hertz_bodies.toml``):

* Geometry update. ``move_mesh_flag`` false (default, small strain as ours): Kratos evaluates
  gaps, normals and mortar projections on the node coordinates, which then stay the initial
  ones; the Newton steps keep the weighted gap of an active node at its initial value, and a
  node that starts open never closes. Right for the patch test (interface closed from the
  start), wrong for Hertz: only the pole node is active, 58 kN instead of 654 kN. ``--move-mesh``
  moves the nodes: the elements stay linear (SmallDisplacement differentiates on the reference
  configuration), contact is evaluated on the deformed surfaces (ours linearises the gap: a
  difference of order |u|^2 / R), and surface loads act on the deformed area (the patch test's
  load grows by (1 + nu p / E)^2, +6e-4). Frictional with ``--move-mesh``: Newton stalls on the
  patch test (active and stick sets settled, residual ratio ~1) with every normal_variation,
  without the normal update and with the MixedULM solver.
* Builder. Kratos' default block builder keeps fixed dofs as rows: on the frictional patch
  test the slave nodes on the symmetry planes go to SLIP with tangential multipliers mu |lambda_n|
  normal to their plane and Newton cycles with period 2; fixing those multiplier components
  makes the system singular (a fixed multiplier row keeps its zero diagonal). The elimination
  builder (default here) removes fixed dofs: 1 iteration, no slip node. ``multi_point_constraints_used``
  is switched off: with it Kratos picks its elimination builder with constraints, whose
  REACTION is zero at the supports.
* Slave nodes on Dirichlet groups. No multiplier is fixed: a slave node's multiplier acts on the
  master nodes too (fixing it would drop the contact there), and with the elimination builder
  neither case is singular (the patch test's rollers on the slave surface: 1 iteration; Hertz:
  the block's top on its symmetry planes).
* Normals. Slave and master faces are ordered so that their normals point out of their body
  (away from the centre of the cell each face bounds, whatever the body's shape).
* A body held by contact alone (the patch test's upper block along z): its initial gap is zero,
  Kratos marks all its slave nodes active in the first iteration, so the first system is regular.
  A body held by contact alone that starts at a gap would give a singular first system (not in
  these cases).

Contact force (``contact_force``, ``pair_forces``): the force of the master body on the slave body,
from the slave body's balance: minus the sum of Kratos' ``REACTION`` at its fixed components and
of its applied surface loads (area x SURFACE_LOAD of Kratos' load conditions). Checks: the
multipliers integrated, sum_j A_j SCALE_FACTOR lambda_j (frictionless: times the nodal normal;
A_j the lumped area of the slave faces, which is D_jj of the dual basis; ``multiplier_mismatch``),
and the master body's balance (``equilibrium_error``). ``reactions``: REACTION summed over each
group's fixed components, a node counted for its first group (clamped, displacement, moved), as
ours; Kratos' REACTION includes the contact force on a fixed component of a contact node.
``unknowns``: the size of Kratos' system (free displacement dofs and multipliers);
``solve_time``: the load loop (contact search, assembly, solves), the model's set-up excluded.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import time

import numpy as np
from scipy import sparse

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import common  # noqa: E402
from kratos_contact import (ELEMENTS, alm_contact_process, analysis_settings, command_line,  # noqa: E402
                            oriented, start_kratos, sub_model_parts)


def outward(mesh: common.Mesh, faces: np.ndarray) -> np.ndarray:
    """``faces`` (boundary faces of the mesh's cells) ordered so that their normals point out of
    the cell each bounds (face centre minus cell centre), whatever the shape of the body."""
    n = len(mesh.points)

    def incidence(rows: np.ndarray) -> sparse.csr_matrix:
        return sparse.csr_matrix((np.ones(rows.size), (np.repeat(np.arange(len(rows)), rows.shape[1]), rows.ravel())),
                                 shape=(len(rows), n))

    shared = (incidence(faces) @ incidence(mesh.cells).T).tocoo()
    hit = shared.data == faces.shape[1]
    cell = np.empty(len(faces), dtype=np.int64)
    cell[shared.row[hit]] = shared.col[hit]
    return oriented(faces, mesh.points,
                    mesh.points[faces].mean(axis=1) - mesh.points[mesh.cells[cell]].mean(axis=1))


def body_groups(case: common.BodiesCase, mesh: common.Mesh) -> dict[str, dict]:
    """Per body: its node indices (into the full mesh), its cells and the faces of each surface group on it."""
    groups = {}
    for body in case.bodies:
        sub, nodes = mesh.body(body.name)
        groups[body.name] = {"nodes": nodes, "cells": mesh.volumes[body.name],
                             "faces": {g: nodes[f] for g, f in sub.faces.items()}}
    return groups


def supports(body: common.Body) -> list[str]:
    """The body's Dirichlet groups in the order ours counts reactions: clamped, displacement, moved."""
    return list(dict.fromkeys([*body.clamped, *body.displacement, *body.moved]))


def prescribed(case: common.BodiesCase, groups: dict[str, dict], n_nodes: int) -> np.ndarray:
    """(N, 3) bool: the displacement components prescribed at each node (clamped, displacement, moved groups)."""
    fixed = np.zeros((n_nodes, 3), dtype=bool)
    for body in case.bodies:
        faces = groups[body.name]["faces"]
        for group in [*body.clamped, *body.moved]:
            fixed[np.unique(faces[group])] = True
        for group, components in body.displacement.items():
            fixed[np.ix_(np.unique(faces[group]), list(components))] = True
    return fixed


def lumped_areas(mesh: common.Mesh, surfaces: list[np.ndarray]) -> np.ndarray:
    """(N,) the integral of each node's hat function over the triangles of ``surfaces`` (the
    diagonal D_jj of the dual mortar operator, which turns a dual multiplier into a nodal force)."""
    area = np.zeros(len(mesh.points))
    for faces in surfaces:
        p = mesh.points[faces]
        a = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        np.add.at(area, faces.ravel(), np.repeat(a / 3, 3))
    return area


def write_mdpa(path: pathlib.Path, case: common.BodiesCase, mesh: common.Mesh, groups: dict[str, dict]
               ) -> dict[str, np.ndarray]:
    """Write the Kratos model: nodes (ids: the mesh file's order + 1), each body's elements (properties
    k + 1), surface loads, contact surfaces (normals out of their bodies) and node sub-model parts;
    return the Kratos node ids per sub-model part."""
    element, surface, load_condition = ELEMENTS[mesh.cell_type]
    lines = ["Begin ModelPartData", "End ModelPartData"]
    lines += [f"Begin Properties {k + 1}\nEnd Properties" for k in range(len(case.bodies))]
    lines += ["Begin Nodes"]
    lines += [f"{k + 1} {x!r} {y!r} {z!r}" for k, (x, y, z) in enumerate(mesh.points.tolist())]
    lines += ["End Nodes", f"Begin Elements {element}"]
    parts: dict[str, dict[str, list]] = {}
    for k, body in enumerate(case.bodies):
        cells = groups[body.name]["cells"]
        # gmsh's and Kratos' node orders of hexahedra and tetrahedra agree
        lines += [f"{e + 1} {k + 1} " + " ".join(map(str, row))
                  for e, row in zip(cells.tolist(), (mesh.cells[cells] + 1).tolist())]
        parts[f"body_{body.name}"] = {"nodes": (groups[body.name]["nodes"] + 1).tolist(),
                                      "elements": (cells + 1).tolist()}
    lines.append("End Elements")
    condition = 1

    def conditions(name: str, kind: str, prop: int, faces: np.ndarray) -> None:
        nonlocal condition
        ids = list(range(condition, condition + len(faces)))
        lines.append(f"Begin Conditions {kind}")
        lines.extend(f"{c} {prop} " + " ".join(map(str, row)) for c, row in zip(ids, (faces + 1).tolist()))
        lines.append("End Conditions")
        parts[name] = {"nodes": (np.unique(faces) + 1).tolist(), "conditions": ids}
        condition += len(faces)

    prop = {body.name: k + 1 for k, body in enumerate(case.bodies)}
    for body in case.bodies:
        for group in body.traction:
            conditions(f"load_{body.name}_{group}", load_condition, prop[body.name], groups[body.name]["faces"][group])
    for i, pair in enumerate(case.pairs):
        for role, (name, group) in (("slave", pair.slave), ("master", pair.master)):
            conditions(f"{role}_{i}", surface, prop[name], outward(mesh, groups[name]["faces"][group]))
    for body in case.bodies:
        faces = groups[body.name]["faces"]
        clamped = np.unique(np.concatenate([faces[g].ravel() for g in body.clamped] + [np.empty(0, np.int64)]))
        for group in supports(body):
            nodes = np.unique(faces[group])
            if group not in body.clamped:
                nodes = np.setdiff1d(nodes, clamped)
            parts[f"fix_{body.name}_{group}"] = {"nodes": (nodes + 1).tolist()}
    lines += sub_model_parts(parts)
    path.write_text("\n".join(lines) + "\n")
    return {name: np.asarray(part["nodes"], dtype=np.int64) for name, part in parts.items()}


def project_parameters(case: common.BodiesCase, args: argparse.Namespace, materials: pathlib.Path,
                       mdpa: pathlib.Path) -> dict:
    """ProjectParameters of a static contact analysis with ``--substeps`` time steps per load step."""
    frictional = any(pair.friction > 0 for pair in case.pairs)
    constraints, loads = [], []

    def assign(process: str, part: str, variable: str, value: list, interval: list, constrained=None) -> dict:
        parameters = {"model_part_name": f"Structure.{part}", "variable_name": variable, "value": value,
                      "interval": interval}
        if constrained is not None:
            parameters["constrained"] = constrained
        return {"python_module": process, "kratos_module": "KratosMultiphysics", "Parameters": parameters}

    # Case step k spans the time (k, k + 1]: load factor and translation go linearly from step k's
    # values to step k + 1's (with one Kratos step per case step, the values).
    previous = (0.0, np.zeros(3))
    for k, (load, translation) in enumerate(case.steps):
        interval = [k + 1e-9, k + 1 + 1e-9] if k > 0 else [0.0, k + 1 + 1e-9]
        if k == len(case.steps) - 1:
            interval[1] = "End"

        def ramp(a: float, b: float) -> str:
            return f"({float(a)!r})+(({float(b)!r})-({float(a)!r}))*(t-{k})"

        for body in case.bodies:
            for group in body.clamped:
                constraints.append(assign("assign_vector_variable_process", f"fix_{body.name}_{group}",
                                          "DISPLACEMENT", [0.0] * 3, interval, [True] * 3))
            for group, components in body.displacement.items():
                constraints.append(assign(
                    "assign_vector_variable_process", f"fix_{body.name}_{group}", "DISPLACEMENT",
                    [ramp(previous[0] * components[c], load * components[c]) if c in components else None
                     for c in range(3)], interval, [c in components for c in range(3)]))
            for group in body.moved:
                constraints.append(assign("assign_vector_variable_process", f"fix_{body.name}_{group}",
                                          "DISPLACEMENT", [ramp(previous[1][c], translation[c]) for c in range(3)],
                                          interval, [True] * 3))
            for group, traction in body.traction.items():
                loads.append(assign("assign_vector_variable_to_conditions_process", f"load_{body.name}_{group}",
                                    "SURFACE_LOAD", [ramp(previous[0] * traction[c], load * traction[c])
                                                     for c in range(3)], interval))
        previous = (load, translation)
    settings = analysis_settings(args, materials, mdpa, len(case.steps), frictional)
    settings["solver_settings"].update({"builder_and_solver_settings": {"type": args.builder},
                                        "multi_point_constraints_used": False})
    n_bodies = len(case.bodies)
    return {
        **settings,
        "processes": {
            "constraints_process_list": constraints,
            "loads_process_list": loads,
            "contact_process_list": [alm_contact_process(
                [(f"slave_{i}", f"master_{i}", n_bodies + 1 + i, pair.friction) for i, pair in enumerate(case.pairs)],
                **json.loads(args.contact_parameters))],
        },
        "output_processes": {},
    }


def main() -> int:
    parser = command_line(__doc__.split("\n")[0])
    parser.add_argument("--builder", default="elimination", choices=["elimination", "block"],
                        help="Kratos builder and solver (block: fixed dofs kept as rows with their diagonal)")
    parser.add_argument("--contact-parameters", default="{}",
                        help="JSON merged into ALMContactProcess' Parameters, e.g. "
                             "'{\"normal_variation\": \"nodal_elemental_derivatives\"}'")
    parser.add_argument("--move-mesh", action="store_true",
                        help="move_mesh_flag true (Kratos' default): needed when the contact zone grows (Hertz)")
    args = parser.parse_args()
    KM, CSMA, StructuralMechanicsAnalysis = start_kratos(args)
    import KratosMultiphysics.StructuralMechanicsApplication as SMA
    case = common.load_bodies_case(args.case)
    slave_bodies = [pair.slave[0] for pair in case.pairs]
    if len(set(slave_bodies)) < len(slave_bodies) or set(slave_bodies) & {pair.master[0] for pair in case.pairs}:
        raise NotImplementedError("the contact force is a slave body's balance: each slave body in one pair only")
    mesh = common.read_msh(case.mesh)
    groups = body_groups(case, mesh)
    out = pathlib.Path(args.output)
    work = out / "kratos"
    work.mkdir(parents=True, exist_ok=True)
    mdpa = work / "bodies.mdpa"
    parts = write_mdpa(mdpa, case, mesh, groups)
    materials = work / "materials.json"
    materials.write_text(json.dumps({"properties": [
        {"model_part_name": f"Structure.body_{body.name}", "properties_id": k + 1,
         "Material": {"constitutive_law": {"name": "LinearElastic3DLaw"},
                      "Variables": {"YOUNG_MODULUS": body.young, "POISSON_RATIO": body.poisson, "DENSITY": 1.0}}}
        for k, body in enumerate(case.bodies)]}, indent=1))
    parameters = project_parameters(case, args, materials, mdpa)
    (work / "ProjectParameters.json").write_text(json.dumps(parameters, indent=1))

    frictional = any(pair.friction > 0 for pair in case.pairs)
    fixed = prescribed(case, groups, len(mesh.points))
    supported = np.flatnonzero(fixed.any(axis=1))
    slaves = [parts[f"slave_{i}"] - 1 for i in range(len(case.pairs))]
    areas = lumped_areas(mesh, [groups[pair.slave[0]]["faces"][pair.slave[1]] for pair in case.pairs])
    displacement = (KM.DISPLACEMENT_X, KM.DISPLACEMENT_Y, KM.DISPLACEMENT_Z)
    reaction = (KM.REACTION_X, KM.REACTION_Y, KM.REACTION_Z)

    def nodal(structure, variables, nodes: np.ndarray | None = None) -> np.ndarray:
        """(N, len(variables)) values of historical ``variables`` at ``nodes`` (indices; all nodes if None)."""
        ids = range(1, len(mesh.points) + 1) if nodes is None else (nodes + 1).tolist()
        return np.array([[structure.GetNode(i).GetSolutionStepValue(v) for v in variables] for i in ids])

    def resultants(structure) -> dict:
        """Contact force of each pair from Kratos' reactions and from its multipliers, reactions per group."""
        support = np.zeros_like(fixed, dtype=float)  # the supports' forces on the bodies (Kratos: REACTION),
        support[supported] = nodal(structure, reaction, supported) * fixed[supported]  # read at fixed nodes only
        applied = {body.name: np.zeros(3) for body in case.bodies}
        for body in case.bodies:
            for group in body.traction:
                for condition in structure.GetSubModelPart(f"load_{body.name}_{group}").Conditions:
                    applied[body.name] += condition.GetGeometry().Area() * np.asarray(
                        condition.GetValue(SMA.SURFACE_LOAD))
        scale = structure.ProcessInfo[KM.SCALE_FACTOR]
        pairs, pressures = {}, []
        for i, pair in enumerate(case.pairs):
            nodes = slaves[i]
            normal = nodal(structure, (KM.NORMAL_X, KM.NORMAL_Y, KM.NORMAL_Z), nodes)
            if frictional:
                traction = scale * nodal(structure, (KM.VECTOR_LAGRANGE_MULTIPLIER_X, KM.VECTOR_LAGRANGE_MULTIPLIER_Y,
                                                     KM.VECTOR_LAGRANGE_MULTIPLIER_Z), nodes)
            else:
                traction = scale * nodal(structure, (CSMA.LAGRANGE_MULTIPLIER_CONTACT_PRESSURE,), nodes) * normal
            pressure = -np.einsum("ij,ij->i", traction, normal)
            pressures.append(pressure)
            slave_body, master_body = pair.slave[0], pair.master[0]
            force = -(support[groups[slave_body]["nodes"]].sum(axis=0) + applied[slave_body])
            pairs[f"{pair.slave[0]}.{pair.slave[1]}/{pair.master[0]}.{pair.master[1]}"] = {
                "reactions": force, "multipliers": (areas[nodes, None] * traction).sum(axis=0),
                "master_balance": support[groups[master_body]["nodes"]].sum(axis=0) + applied[master_body] - force}
        reactions = {}
        for body in case.bodies:
            counted = np.zeros(len(mesh.points), dtype=bool)
            for group in supports(body):
                nodes = np.setdiff1d(np.unique(groups[body.name]["faces"][group]), np.flatnonzero(counted))
                counted[nodes] = True
                reactions[f"{body.name}.{group}"] = support[nodes].sum(axis=0)
        return {"pairs": pairs, "reactions": reactions, "pressure": np.concatenate(pressures)}

    class Analysis(StructuralMechanicsAnalysis):
        """Counts Newton iterations per step, records convergence and the system size."""

        newton_per_step: list[int] = []
        converged: list[bool] = []
        steps: list[dict] = []
        unknowns: int = 0

        def SolveSolutionStep(self):
            converged = super().SolveSolutionStep()
            self.converged.append(bool(converged))
            return converged

        def FinalizeSolutionStep(self):
            super().FinalizeSolutionStep()
            solver = self._GetSolver()
            info = solver.GetComputingModelPart().ProcessInfo
            self.newton_per_step.append(int(info[KM.NL_ITERATION_NUMBER]))
            Analysis.unknowns = max(Analysis.unknowns, solver._GetBuilderAndSolver().GetEquationSystemSize())
            self.steps.append(resultants(self.model.GetModelPart("Structure")))

    model = KM.Model()
    analysis = Analysis(model, KM.Parameters(json.dumps(parameters)))
    analysis.Initialize()
    t0, c0 = time.perf_counter(), time.process_time()
    analysis.RunSolutionLoop()
    solve_time, solve_cpu = time.perf_counter() - t0, time.process_time() - c0
    wall_time = common.clock()
    peak = common.peak_memory_mib()
    analysis.Finalize()
    structure = model.GetModelPart("Structure")
    u = nodal(structure, displacement)
    ends = slice(args.substeps - 1, None, args.substeps)  # the Kratos steps that end a load step
    last = Analysis.steps[-1]
    forces = {name: force["reactions"] for name, force in last["pairs"].items()}
    size = max(float(np.linalg.norm(f["reactions"])) for f in last["pairs"].values()) or 1.0
    mismatch = max(float(np.linalg.norm(f["reactions"] - f["multipliers"])) for f in last["pairs"].values()) / size
    balance = max(float(np.linalg.norm(f["master_balance"])) for f in last["pairs"].values()) / size
    n_steps = len(case.steps) * args.substeps
    status = ("converged" if len(Analysis.converged) == n_steps and all(Analysis.converged)
              else f"not converged (steps {[k + 1 for k, c in enumerate(Analysis.converged) if not c]} of {n_steps})")
    active = last["pressure"][last["pressure"] > 0]
    record = {
        "code": "Kratos 10.4.4 (ContactStructuralMechanics, mortar ALM)",
        "case": str(case.path), "status": status,
        "dofs": 3 * len(mesh.points), "free_dofs": int(3 * len(mesh.points) - fixed.sum()),
        "contact_nodes": int(sum(len(nodes) for nodes in slaves)),
        "unknowns": int(Analysis.unknowns),
        "newton_iterations": int(sum(Analysis.newton_per_step)),
        "newton_per_step": [sum(Analysis.newton_per_step[k:k + args.substeps])
                            for k in range(0, len(Analysis.newton_per_step), args.substeps)],
        "wall_time": wall_time, "solve_time": solve_time, "solve_cpu_time": solve_cpu, "peak_memory_mib": peak,
        "contact_force": np.sum(list(forces.values()), axis=0), "pair_forces": forces,
        "pair_forces_multipliers": {name: f["multipliers"] for name, f in last["pairs"].items()},
        "multiplier_mismatch": mismatch, "equilibrium_error": balance,
        "contact_force_per_step": [np.sum([f["reactions"] for f in step["pairs"].values()], axis=0)
                                   for step in Analysis.steps[ends]],
        "contact_pressure_range": [float(active.min()), float(active.max())] if len(active) else None,
        "active_nodes": int(len(active)),
        "reactions": last["reactions"],
        "settings": {"linear_solver": args.linear_solver, "builder": args.builder, "tol": args.tol,
                     "atol": args.atol, "move_mesh_flag": args.move_mesh, "substeps": args.substeps,
                     "mixed_ulm": args.mixed_ulm, "contact_parameters": json.loads(args.contact_parameters),
                     "contact_type": "Frictional" if frictional else "Frictionless"},
        "threads": args.threads,
    }
    common.write_result(out, record, mesh.points, u)
    print(f"kratos: {status}, {record['newton_iterations']} Newton {record['newton_per_step']}, {solve_time:.2f} s, "
          f"contact force {np.array2string(np.asarray(record['contact_force']), precision=6)} "
          f"(multipliers: mismatch {mismatch:.1e}; master body's balance {balance:.1e})")
    return 0 if status == "converged" else 1


if __name__ == "__main__":
    sys.exit(main())
