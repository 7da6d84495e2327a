"""Kratos Multiphysics 10.4 on a peer-benchmark case: mortar ALM contact with Coulomb friction.

    build/kratos-venv/bin/python benchmarks/peers/kratos_contact.py CASE.toml --output DIR \\
        [--linear-solver sparse_lu] [--tol 1e-8] [--threads 1]

Reads the case file and its ``.msh`` (:mod:`common`), writes Kratos' input (``DIR/kratos/body.mdpa``,
``materials.json``, ``ProjectParameters.json``) and runs Kratos' ``StructuralMechanicsAnalysis``
with the contact static solver (``ALMContactProcess``: dual mortar augmented Lagrangian,
``Frictional`` for F > 0, ``Frictionless`` otherwise) over the case's load steps (one Kratos time
step per load step). Result fields: :mod:`common`.

The discretisation is not ours: Kratos couples the contact surfaces by mortar integrals (dual
Lagrange multipliers, weighted gaps), ours is nodal. The two discrete solutions differ by a
discretisation error, measured by ``peers_real.py`` against ours and against the closed forms.

Pitfalls, and how this driver handles them:

* Rigid obstacle. Kratos' mortar contact needs a master surface of a meshed body: the plane is
  a slab of hexahedra under the contact surface (one layer, larger than the body's footprint;
  a sphere is not meshed yet); every obstacle node is fixed (DISPLACEMENT prescribed: zero, or
  the step's translation, ramped over ``--substeps`` time steps with the load).
* Geometry update. Kratos moves the mesh by the displacement unless ``move_mesh_flag`` is
  false, the default here (small strain, as ours). Measured: then the weighted gaps stay those
  of the initial configuration and a body that starts at a gap never comes into contact;
  ``--move-mesh`` turns the update on (docs/peers.md, Kratos: neither converged).
* Clamped contact nodes. A node both clamped and on the slave surface makes the system
  singular (its contact rows act on fixed dofs only): its Lagrange multiplier is fixed to zero
  (``LAGRANGE_MULTIPLIER_CONTACT_PRESSURE`` / ``VECTOR_LAGRANGE_MULTIPLIER``).
* Units. SI as the case (Kratos scales its ALM penalty with Young's modulus itself).

Contact force and reactions: Kratos' ``REACTION`` at the fixed body nodes, and the contact force
as the sum of the reactions of the obstacle's fixed nodes with the sign turned (the force the
body exerts on the obstacle, reversed).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import time
import types
import typing

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
import common  # noqa: E402

ELEMENTS = {"hexahedron": ("SmallDisplacementElement3D8N", "SurfaceCondition3D4N", "SurfaceLoadCondition3D4N"),
            "tetrahedron": ("SmallDisplacementElement3D4N", "SurfaceCondition3D3N", "SurfaceLoadCondition3D3N")}


def obstacle_mesh(case: common.Case, mesh: common.Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A meshed rigid obstacle under the contact surface: (points, hexahedra, top quadrilaterals).

    A plane only: a slab one cell thick (a tenth of the footprint), 10 % larger than the contact
    surface's footprint, n x n cells on its top face (n = 2 sqrt(contact faces)). A sphere would
    need a meshed cap; not done (Kratos did not converge on the plane, docs/peers.md).
    """
    contact = mesh.points[mesh.group_nodes(case.contact)]
    kind = case.obstacle["type"]
    n_side = max(4, int(2 * np.sqrt(len(mesh.faces[case.contact]))))
    if kind == "plane":
        normal = np.asarray(case.obstacle["normal"], float)
        normal /= np.linalg.norm(normal)
        point = np.asarray(case.obstacle["point"], float)
        t1 = np.cross(normal, [1.0, 0, 0] if abs(normal[0]) < 0.9 else [0, 1.0, 0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(normal, t1)
        local = (contact - point) @ np.column_stack([t1, t2])
        low, high = local.min(axis=0), local.max(axis=0)
        margin = 0.05 * (high - low)
        s = np.linspace(low[0] - margin[0], high[0] + margin[0], n_side + 1)
        t = np.linspace(low[1] - margin[1], high[1] + margin[1], n_side + 1)
        thickness = 0.1 * float((high - low).max())
        S, T = np.meshgrid(s, t, indexing="ij")
        top = point + S.ravel()[:, None] * t1 + T.ravel()[:, None] * t2
        bottom = top - thickness * normal
    else:
        raise NotImplementedError(f"obstacle {kind!r}: the Kratos driver meshes planes only")
    points = np.vstack([bottom, top])
    n_layer = (n_side + 1) ** 2

    def node(i, j, layer):
        return layer * n_layer + i * (n_side + 1) + j

    i, j = (g.ravel() for g in np.meshgrid(np.arange(n_side), np.arange(n_side), indexing="ij"))
    quad = lambda layer: np.column_stack([node(i, j, layer), node(i + 1, j, layer),  # noqa: E731
                                          node(i + 1, j + 1, layer), node(i, j + 1, layer)])
    cells = np.hstack([quad(0), quad(1)])
    # Outward normal of the master surface (towards the body): the top face, counter-clockwise seen from the body.
    top_faces = quad(1)
    return points, cells, top_faces


def oriented(faces: np.ndarray, points: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """``faces`` with their node order flipped where their normal points against ``outward`` (per face)."""
    p = points[faces]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    flip = np.einsum("ij,ij->i", normal, outward) < 0
    faces = faces.copy()
    faces[flip] = faces[flip][:, ::-1]
    return faces


def sub_model_parts(parts: dict[str, dict[str, list]]) -> list[str]:
    """The ``.mdpa`` lines of sub-model parts: name -> {"nodes", "elements", "conditions": Kratos ids}."""
    lines = []
    for name, part in parts.items():
        lines.append(f"Begin SubModelPart {name}")
        for kind, key in (("Nodes", "nodes"), ("Elements", "elements"), ("Conditions", "conditions")):
            lines.append(f"Begin SubModelPart{kind}")
            lines += [str(v) for v in part.get(key, [])]
            lines.append(f"End SubModelPart{kind}")
        lines.append("End SubModelPart")
    return lines


def write_mdpa(path: pathlib.Path, case: common.Case, mesh: common.Mesh, obstacle: tuple) -> dict[str, np.ndarray]:
    """Write the Kratos model: body (properties 1), obstacle (properties 2), load and contact
    conditions, and the node sub-model parts; return the Kratos node ids (1-based) per part."""
    element, surface, load_condition = ELEMENTS[mesh.cell_type]
    o_points, o_cells, o_top = obstacle
    n_body = len(mesh.points)
    o_ids = np.arange(len(o_points)) + n_body + 1
    lines = ["Begin ModelPartData", "End ModelPartData", "Begin Properties 1", "End Properties",
             "Begin Properties 2", "End Properties", "Begin Nodes"]
    lines += [f"{k + 1} {x!r} {y!r} {z!r}" for k, (x, y, z) in enumerate(mesh.points.tolist())]
    lines += [f"{k} {x!r} {y!r} {z!r}" for k, (x, y, z) in zip(o_ids.tolist(), o_points.tolist())]
    lines += ["End Nodes", f"Begin Elements {element}"]
    body_cells = mesh.cells  # gmsh's and Kratos' node orders of hexahedra and tetrahedra agree
    lines += [f"{e + 1} 1 " + " ".join(map(str, row)) for e, row in enumerate((body_cells + 1).tolist())]
    lines += ["End Elements", "Begin Elements SmallDisplacementElement3D8N"]
    first_obstacle_element = len(body_cells) + 1
    lines += [f"{first_obstacle_element + e} 2 " + " ".join(map(str, row))
              for e, row in enumerate((o_cells + n_body + 1).tolist())]
    lines += ["End Elements"]
    condition = 1
    parts: dict[str, dict[str, list]] = {}
    centroid = mesh.points.mean(axis=0)
    for name in case.traction:
        faces = mesh.faces[name]
        lines.append(f"Begin Conditions {load_condition}")
        ids = []
        for row in (faces + 1).tolist():
            lines.append(f"{condition} 1 " + " ".join(map(str, row)))
            ids.append(condition)
            condition += 1
        lines.append("End Conditions")
        parts[f"load_{name}"] = {"nodes": (mesh.group_nodes(name) + 1).tolist(), "conditions": ids}
    # Slave: the body's contact surface, normals out of the body; master: the obstacle's top face.
    slave = mesh.faces[case.contact]
    face_centres = mesh.points[slave].mean(axis=1)
    slave = oriented(slave, mesh.points, face_centres - centroid)
    lines.append(f"Begin Conditions {surface}")
    ids = []
    for row in (slave + 1).tolist():
        lines.append(f"{condition} 1 " + " ".join(map(str, row)))
        ids.append(condition)
        condition += 1
    lines.append("End Conditions")
    parts["contact_slave"] = {"nodes": (mesh.group_nodes(case.contact) + 1).tolist(), "conditions": ids}
    lines.append(f"Begin Conditions {ELEMENTS['hexahedron'][1]}")
    ids = []
    o_centroid = o_points.mean(axis=0)
    master = oriented(o_top, o_points, o_points[o_top].mean(axis=1) - o_centroid)
    for row in (master + n_body + 1).tolist():
        lines.append(f"{condition} 2 " + " ".join(map(str, row)))
        ids.append(condition)
        condition += 1
    lines.append("End Conditions")
    parts["contact_master"] = {"nodes": (np.unique(o_top) + n_body + 1).tolist(), "conditions": ids}
    parts["body"] = {"nodes": list(range(1, n_body + 1)), "elements": list(range(1, len(body_cells) + 1))}
    parts["obstacle"] = {"nodes": o_ids.tolist(),
                         "elements": list(range(first_obstacle_element, first_obstacle_element + len(o_cells)))}
    fixed = mesh.clamped_nodes(case)
    for name in case.clamped:
        parts[f"clamped_{name}"] = {"nodes": (mesh.group_nodes(name) + 1).tolist()}
    for name in case.displacement:
        parts[f"roller_{name}"] = {"nodes": (mesh.roller_nodes(case, name) + 1).tolist()}
    parts["clamped_slave"] = {"nodes": (np.intersect1d(mesh.group_nodes(case.contact), fixed) + 1).tolist()}
    lines += sub_model_parts(parts)
    path.write_text("\n".join(lines) + "\n")
    return {name: np.asarray(part["nodes"]) for name, part in parts.items()}


def analysis_settings(args: argparse.Namespace, materials: pathlib.Path, mdpa: pathlib.Path, n_steps: int,
                      frictional: bool) -> dict:
    """``problem_data`` and ``solver_settings`` of a static contact analysis of ``n_steps`` load steps,
    ``--substeps`` time steps each, with ``--tol`` on every ratio of the contact residual criterion."""
    tol = args.tol
    contact_tolerances = {f"{kind}_{which}_tolerance": tol if which == "relative" else args.atol
                          for kind in ("contact_displacement", "contact_residual",
                                       "frictional_stick_contact_displacement", "frictional_stick_contact_residual",
                                       "frictional_slip_contact_displacement", "frictional_slip_contact_residual")
                          for which in ("relative", "absolute")}
    return {
        "problem_data": {"problem_name": "peer", "parallel_type": "OpenMP", "echo_level": args.echo,
                         "start_time": 0.0, "end_time": n_steps - 0.5 / args.substeps},
        "solver_settings": {
            "solver_type": "Static", "model_part_name": "Structure", "domain_size": 3, "echo_level": args.echo,
            "analysis_type": "non_linear", "time_stepping": {"time_step": 1.0 / args.substeps},
            "model_import_settings": {"input_type": "mdpa", "input_filename": str(mdpa.with_suffix(""))},
            "material_import_settings": {"materials_filename": str(materials)},
            "move_mesh_flag": args.move_mesh,
            "compute_reactions": True,
            "convergence_criterion": "contact_residual_criterion",
            "displacement_relative_tolerance": tol, "displacement_absolute_tolerance": args.atol,
            "residual_relative_tolerance": tol, "residual_absolute_tolerance": args.atol,
            "max_iteration": args.max_iter,
            "linear_solver_settings": {"solver_type": args.linear_solver, **({} if args.linear_tol is None else {
                "tolerance": args.linear_tol, "max_iteration": 1000})},
            "contact_settings": {"mortar_type": "ALMContactFrictional" if frictional else "ALMContactFrictionless",
                                 "use_mixed_ulm_solver": args.mixed_ulm, **contact_tolerances},
        },
    }


def alm_contact_process(pairs: list[tuple[str, str, int, float]], **parameters: typing.Any) -> dict:
    """``ALMContactProcess`` for contact pairs (slave part, master part, property id, friction
    coefficient): ``Frictional`` if any pair has friction, ``Frictionless`` otherwise; ``parameters``
    are merged into its Parameters."""
    return {
        "python_module": "alm_contact_process",
        "kratos_module": "KratosMultiphysics.ContactStructuralMechanicsApplication",
        "process_name": "ALMContactProcess",
        "Parameters": {"model_part_name": "Structure",
                       "contact_model_part": {str(i): [slave, master] for i, (slave, master, _, _) in enumerate(pairs)},
                       "assume_master_slave": {str(i): [slave] for i, (slave, _, _, _) in enumerate(pairs)},
                       "contact_property_ids": {str(i): prop for i, (_, _, prop, _) in enumerate(pairs)},
                       "friction_coefficients": {str(i): mu for i, (_, _, _, mu) in enumerate(pairs)},
                       "contact_type": "Frictional" if any(p[3] > 0 for p in pairs) else "Frictionless",
                       **parameters}}


def project_parameters(case: common.Case, args: argparse.Namespace, materials: pathlib.Path,
                       mdpa: pathlib.Path) -> dict:
    """ProjectParameters of a static contact analysis with one time step per load step."""
    n_steps = len(case.steps)
    frictional = case.friction > 0
    constraints = []

    def fix(part: str, variable: str, constrained: list[bool], value: list, interval=(0.0, "End")):
        constraints.append({"python_module": "assign_vector_variable_process", "kratos_module": "KratosMultiphysics",
                            "Parameters": {"model_part_name": f"Structure.{part}", "variable_name": variable,
                                           "constrained": constrained, "value": value, "interval": list(interval)}})

    for name in case.clamped:
        fix(f"clamped_{name}", "DISPLACEMENT", [True] * 3, [0.0] * 3)
    for name, components in case.displacement.items():
        fix(f"roller_{name}", "DISPLACEMENT", [c in components for c in range(3)],
            [components.get(c) for c in range(3)])
    # The obstacle is rigid: all its nodes prescribed, per step its translation.
    # Case step k spans the time (k, k + 1]: the load and the obstacle's translation go linearly from
    # step k's values to step k + 1's (t in time units; with one Kratos step per case step, the values).
    previous = (0.0, np.zeros(3))
    loads = []
    for k, (load, translation) in enumerate(case.steps):
        interval = [k + 1e-9, k + 1 + 1e-9] if k > 0 else [0.0, k + 1 + 1e-9]
        if k == len(case.steps) - 1:
            interval[1] = "End"

        def ramp(a: float, b: float) -> str:
            return f"({float(a)!r})+(({float(b)!r})-({float(a)!r}))*(t-{k})"

        fix("obstacle", "DISPLACEMENT", [True] * 3,
            [ramp(previous[1][c], translation[c]) for c in range(3)], interval)
        for name, traction in case.traction.items():
            loads.append({"python_module": "assign_vector_variable_to_conditions_process",
                          "kratos_module": "KratosMultiphysics",
                          "Parameters": {"model_part_name": f"Structure.load_{name}", "variable_name": "SURFACE_LOAD",
                                         "value": [ramp(previous[0] * traction[c], load * traction[c])
                                                   for c in range(3)],
                                         "interval": interval}})
        previous = (load, translation)
    return {
        **analysis_settings(args, materials, mdpa, n_steps, frictional),
        "processes": {
            "constraints_process_list": constraints,
            "loads_process_list": loads,
            "contact_process_list": [alm_contact_process([("contact_slave", "contact_master", 3, case.friction)])],
        },
        "output_processes": {},
    }


def command_line(description: str) -> argparse.ArgumentParser:
    """The command line the Kratos drivers share: case, output and Kratos' solver settings."""
    parser = argparse.ArgumentParser(description=description, formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("case")
    parser.add_argument("--output", required=True)
    parser.add_argument("--linear-solver", default="sparse_lu",
                        help="Kratos linear solver: sparse_lu (Eigen), skyline_lu_factorization, amgcl, ...")
    parser.add_argument("--linear-tol", type=float, default=None,
                        help="relative tolerance of an iterative linear solver (AMGCL's default: 1e-6)")
    parser.add_argument("--tol", type=float, default=1e-8, help="relative tolerances of the convergence criteria")
    parser.add_argument("--atol", type=float, default=1e-12, help="absolute tolerances of the convergence criteria")
    parser.add_argument("--max-iter", type=int, default=100)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--mixed-ulm", action="store_true",
                        help="Kratos' MixedULMLinearSolver (condenses the multipliers) instead of the linear "
                             "solver on all unknowns")
    parser.add_argument("--substeps", type=int, default=1,
                        help="Kratos time steps per load step, the load ramped linearly (path-dependent with friction)")
    parser.add_argument("--echo", type=int, default=0)
    return parser


def start_kratos(args: argparse.Namespace) -> tuple[types.ModuleType, types.ModuleType, type]:
    """Import Kratos with ``--threads`` OpenMP threads and its log at ``--echo``: Kratos, its contact
    application (which registers the contact solver) and ``StructuralMechanicsAnalysis``."""
    os.environ["OMP_NUM_THREADS"] = str(args.threads)
    import KratosMultiphysics as KM
    import KratosMultiphysics.ContactStructuralMechanicsApplication as CSMA
    import KratosMultiphysics.LinearSolversApplication  # noqa: F401  (sparse_lu, ...: Eigen's solvers)
    from KratosMultiphysics.StructuralMechanicsApplication.structural_mechanics_analysis import (
        StructuralMechanicsAnalysis)

    KM.ParallelUtilities.SetNumThreads(args.threads)
    if args.echo == 0:
        KM.Logger.GetDefaultOutput().SetSeverity(KM.Logger.Severity.WARNING)
    return KM, CSMA, StructuralMechanicsAnalysis


def main() -> int:
    parser = command_line(__doc__.split("\n")[0])
    parser.add_argument("--move-mesh", action="store_true", help="move_mesh_flag true (Kratos' default)")
    args = parser.parse_args()
    KM, CSMA, StructuralMechanicsAnalysis = start_kratos(args)
    case = common.load_case(args.case)
    mesh = common.read_msh(case.mesh)
    out = pathlib.Path(args.output)
    work = out / "kratos"
    work.mkdir(parents=True, exist_ok=True)
    obstacle = obstacle_mesh(case, mesh)
    mdpa = work / "body.mdpa"
    parts = write_mdpa(mdpa, case, mesh, obstacle)
    materials = work / "materials.json"
    law = {"constitutive_law": {"name": "LinearElastic3DLaw"},
           "Variables": {"YOUNG_MODULUS": case.young, "POISSON_RATIO": case.poisson, "DENSITY": 1.0}}
    materials.write_text(json.dumps({"properties": [
        {"model_part_name": "Structure.body", "properties_id": 1, "Material": law},
        {"model_part_name": "Structure.obstacle", "properties_id": 2, "Material": law}]}, indent=1))
    parameters = project_parameters(case, args, materials, mdpa)
    (work / "ProjectParameters.json").write_text(json.dumps(parameters, indent=1))

    class Analysis(StructuralMechanicsAnalysis):
        """Counts Newton iterations per step and fixes the multipliers of clamped slave nodes."""

        newton_per_step: list[int] = []
        obstacle_forces: list[list[float]] = []

        def InitializeSolutionStep(self):
            super().InitializeSolutionStep()
            clamped = self.model.GetModelPart("Structure.clamped_slave")
            if case.friction > 0:
                variables = [KM.VECTOR_LAGRANGE_MULTIPLIER_X, KM.VECTOR_LAGRANGE_MULTIPLIER_Y,
                             KM.VECTOR_LAGRANGE_MULTIPLIER_Z]
            else:
                variables = [CSMA.LAGRANGE_MULTIPLIER_CONTACT_PRESSURE]
            for node in clamped.Nodes:
                for variable in variables:
                    if node.HasDofFor(variable):
                        node.Fix(variable)
                        node.SetSolutionStepValue(variable, 0.0)

        def FinalizeSolutionStep(self):
            super().FinalizeSolutionStep()
            info = self._GetSolver().GetComputingModelPart().ProcessInfo
            self.newton_per_step.append(int(info[KM.NL_ITERATION_NUMBER]))
            self.obstacle_forces.append(reaction("obstacle").tolist())

    model = KM.Model()

    def reaction(part: str) -> np.ndarray:
        """Sum of REACTION (the supports' force on the nodes) over sub-model part ``part``."""
        return np.sum([[n.GetSolutionStepValue(v) for v in (KM.REACTION_X, KM.REACTION_Y, KM.REACTION_Z)]
                       for n in model.GetModelPart(f"Structure.{part}").Nodes], axis=0)

    analysis = Analysis(model, KM.Parameters(json.dumps(parameters)))
    t0, c0 = time.perf_counter(), time.process_time()
    analysis.Run()
    solve_time, solve_cpu = time.perf_counter() - t0, time.process_time() - c0
    wall_time = common.clock()
    peak = common.peak_memory_mib()
    structure = model.GetModelPart("Structure")
    import KratosMultiphysics.StructuralMechanicsApplication as SMA
    if args.echo > 1:
        for name in case.traction:
            part = structure.GetSubModelPart(f"load_{name}")
            print("load", name, part.NumberOfConditions(), next(iter(part.Conditions)).GetValue(SMA.SURFACE_LOAD))
    u = np.array([[n.GetSolutionStepValue(v) for v in (KM.DISPLACEMENT_X, KM.DISPLACEMENT_Y, KM.DISPLACEMENT_Z)]
                  for n in structure.GetSubModelPart("body").Nodes])
    ids = np.array([n.Id for n in structure.GetSubModelPart("body").Nodes])
    u_nodes = np.empty_like(u)
    u_nodes[ids - 1] = u

    reactions = {name: reaction(f"clamped_{name}").tolist() for name in case.clamped}  # support on body, as ours
    contact_force = reaction("obstacle")  # the obstacle's supports hold the body's push: that is the contact force
    max_iter = args.max_iter
    status = "converged" if len(Analysis.newton_per_step) == len(case.steps) * args.substeps and all(
        k < max_iter for k in Analysis.newton_per_step) else "not converged"
    fixed = mesh.clamped_nodes(case)
    record = {
        "code": "Kratos 10.4.4 (ContactStructuralMechanics, mortar ALM)",
        "case": str(case.path), "status": status,
        "dofs": 3 * len(mesh.points), "free_dofs": 3 * (len(mesh.points) - len(fixed)),
        "contact_nodes": int(len(np.setdiff1d(mesh.group_nodes(case.contact), fixed))),
        "unknowns": None,
        "newton_iterations": int(sum(Analysis.newton_per_step)), "newton_per_step": Analysis.newton_per_step,
        "wall_time": wall_time, "solve_time": solve_time, "solve_cpu_time": solve_cpu, "peak_memory_mib": peak,
        "contact_force": contact_force.tolist(),
        "contact_force_per_step": Analysis.obstacle_forces[args.substeps - 1::args.substeps], "reactions": reactions,
        "settings": {"linear_solver": args.linear_solver, "tol": args.tol, "atol": args.atol,
                     "move_mesh_flag": args.move_mesh, "substeps": args.substeps, "obstacle_nodes": len(obstacle[0])},
        "threads": args.threads,
    }
    common.write_result(out, record, mesh.points, u_nodes)
    print(f"kratos: {status}, {record['newton_iterations']} Newton {Analysis.newton_per_step}, {solve_time:.2f} s, "
          f"contact force {np.array2string(np.asarray(record['contact_force']), precision=6)}")
    return 0 if status == "converged" else 1


if __name__ == "__main__":
    sys.exit(main())
