"""Kratos Multiphysics 10.4 on the shallow-ironing benchmark, with Kratos' own input files.

    build/kratos-venv/bin/python benchmarks/peers/kratos_ironing.py --output DIR \\
        [--friction 0.3] [--mdpa build/kratos-ironing/shallow_ironing3D.mdpa] [--vertical-steps 16] \\
        [--sliding-steps 500] [--end-time 2.0] [--threads 1] [--max-iteration 20] \\
        [--linear-solver amgcl --linear-tol 1e-8]

Runs ``build/kratos-ironing/source/ProjectParameters_literature.json`` (KratosMultiphysics/Examples,
``contact_structural_mechanics/validation/shallow_ironing_3D``, commit 9eacc7b: neo-Hookean
``TotalLagrangianElement3D8N`` bodies, ``HyperElastic3DLaw``, dual mortar ALM contact with the
die ``Parts_Auto1`` as slave, ``contact_residual_criterion`` 1e-4, at most 20 Newton iterations)
as given, except: the time steps (``--vertical-steps`` in [0.2, 1], ``--sliding-steps`` in
[1, end]; the file's are 0.05 and 0.002, 16 and 500 steps), no GiD/VTK output, no ``mesh_id``
(a key Kratos 10.4 rejects), and with
``--friction`` the frictional contact process of ``ProjectParameters_frictional.json``
(``ALMContactFrictional``, mu, its tangent factor, search and stiffness settings) on the
literature path (that file itself moves the die by 1.0 down and then by (t - 1) along x up
to t = 12, the README's "custom" setup). ``--mdpa`` replaces the mesh (e.g. the tetrahedra of
``meshes/shallow_ironing.msh`` written by ``ironing_mesh.py --mdpa``).

Per step (``DIR/kratos_ironing.json``): time, converged, Newton iterations, wall seconds, and the
sums of Kratos' ``REACTION`` over ``Displacement_Auto2`` (the die's top) and ``Displacement_Auto1``
(the block's bottom). REACTION is the support's force on the body, as our reactions ``R``
(measured: t = 0.3 on ``meshes/shallow_ironing_coarse.msh``, Kratos (3.23e5, -2.331e7) N, ours
(4.66e5, -2.334e7) N); Kratos' figures plot F_y = -REACTION_y and F_x = REACTION_x of the die's top.

With ``--mdpa`` of the tetrahedra and ``--linear-solver sparse_lu`` the coarse mesh (17 136 dofs)
takes 4-8 Newton iterations and about 5 s per press step of 0.05 (``--vertical-steps 16``, the
file's); with steps of 0.1 it stopped at t = 0.6 ("CONTACT LOST", Newton iteration 5). On the
reference hexahedra (47 628 dofs) Kratos' default linear solver did not finish its first Newton
iteration in 3 minutes, and ``amgcl`` is rejected by the contact solver's own settings
(``"block_size": "auto"`` against amgcl's integer default, Kratos 10.4.4).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCE = ROOT / "build" / "kratos-ironing" / "source"


def parameters(args: argparse.Namespace, work: pathlib.Path) -> dict:
    """The literature setup with the requested time steps, friction and mesh."""
    p = json.loads((SOURCE / "ProjectParameters_literature.json").read_text())
    mdpa = pathlib.Path(args.mdpa).resolve()
    p["problem_data"]["end_time"] = args.end_time
    p["problem_data"]["echo_level"] = 0
    p["solver_settings"]["echo_level"] = args.echo
    p["solver_settings"]["max_iteration"] = args.max_iteration
    p["solver_settings"]["model_import_settings"]["input_filename"] = str(mdpa.with_suffix(""))
    p["solver_settings"]["material_import_settings"]["materials_filename"] = str(work / "StructuralMaterials.json")
    p["solver_settings"]["time_stepping"] = {"time_step_intervals": {
        "first": {"interval": [0.0, 1.0], "time_step": 0.8 / args.vertical_steps},
        "second": {"interval": [1.0, "End"], "time_step": (args.end_time - 1.0) / args.sliding_steps}}}
    if args.linear_solver:
        p["solver_settings"]["linear_solver_settings"] = {"solver_type": args.linear_solver, **(
            {} if args.linear_tol is None else {"tolerance": args.linear_tol, "max_iteration": 1000})}
    if args.friction > 0:
        frictional = json.loads((SOURCE / "ProjectParameters_frictional.json").read_text())
        p["solver_settings"]["contact_settings"] = frictional["solver_settings"]["contact_settings"]
        contact = frictional["processes"]["contact_process_list"][0]
        contact["Parameters"]["friction_coefficients"] = {"0": args.friction}
        p["processes"]["contact_process_list"] = [contact]
    for process in p["processes"]["constraints_process_list"]:
        process["Parameters"].pop("mesh_id", None)  # a key of older Kratos, rejected by 10.4
    p["output_processes"] = {}
    return p


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--output", required=True)
    parser.add_argument("--friction", type=float, default=0.0)
    parser.add_argument("--mdpa", default=str(ROOT / "build" / "kratos-ironing" / "shallow_ironing3D.mdpa"))
    parser.add_argument("--vertical-steps", type=int, default=16, help="steps of the press, t in [0.2, 1]")
    parser.add_argument("--sliding-steps", type=int, default=500, help="steps of the slide, t in [1, end]")
    parser.add_argument("--end-time", type=float, default=2.0)
    parser.add_argument("--max-iteration", type=int, default=20)
    parser.add_argument("--linear-solver", default=None, help="e.g. sparse_lu (default: the file's, Kratos' default)")
    parser.add_argument("--linear-tol", type=float, default=None, help="of an iterative linear solver (amgcl)")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--echo", type=int, default=1)
    args = parser.parse_args()
    os.environ["OMP_NUM_THREADS"] = str(args.threads)
    import KratosMultiphysics as KM
    import KratosMultiphysics.ConstitutiveLawsApplication  # noqa: F401  (HyperElastic3DLaw: neo-Hookean)
    import KratosMultiphysics.ContactStructuralMechanicsApplication  # noqa: F401
    import KratosMultiphysics.LinearSolversApplication  # noqa: F401
    from KratosMultiphysics.StructuralMechanicsApplication.structural_mechanics_analysis import (
        StructuralMechanicsAnalysis)
    KM.ParallelUtilities.SetNumThreads(args.threads)

    out = pathlib.Path(args.output)
    work = out / "kratos"
    work.mkdir(parents=True, exist_ok=True)
    (work / "StructuralMaterials.json").write_text((SOURCE / "StructuralMaterials.json").read_text())
    p = parameters(args, work)
    (work / "ProjectParameters.json").write_text(json.dumps(p, indent=1))
    record = {"code": "Kratos 10.4.4 (ContactStructuralMechanics, mortar ALM, TotalLagrangian, HyperElastic3DLaw)",
              "mdpa": str(args.mdpa), "friction": args.friction, "steps": []}
    result_path = out / "kratos_ironing.json"

    class Analysis(StructuralMechanicsAnalysis):
        """Records per step: convergence, Newton iterations, summed REACTION of the supports."""

        def SolveSolutionStep(self):
            self._started = time.perf_counter()
            self._converged = bool(super().SolveSolutionStep())
            return self._converged

        def FinalizeSolutionStep(self):
            super().FinalizeSolutionStep()
            structure = self.model.GetModelPart("Structure")
            info = structure.ProcessInfo

            def reaction(part: str) -> list[float]:
                nodes = structure.GetSubModelPart(part).Nodes
                return np.sum([[n.GetSolutionStepValue(v) for v in (KM.REACTION_X, KM.REACTION_Y, KM.REACTION_Z)]
                               for n in nodes], axis=0).tolist()

            step = {"time": info[KM.TIME], "converged": self._converged,
                    "newton": int(info[KM.NL_ITERATION_NUMBER]),
                    "seconds": time.perf_counter() - self._started,
                    "reaction_die_top": reaction("DISPLACEMENT_Displacement_Auto2"),
                    "reaction_block_bottom": reaction("DISPLACEMENT_Displacement_Auto1")}
            record["steps"].append(step)
            print(f"kratos_ironing: t = {step['time']:.4f} converged {step['converged']} newton {step['newton']} "
                  f"die top REACTION {np.array2string(np.asarray(step['reaction_die_top']), precision=4)}",
                  flush=True)
            result_path.write_text(json.dumps(record, indent=1))

    model = KM.Model()
    analysis = Analysis(model, KM.Parameters(json.dumps(p)))
    t0 = time.perf_counter()
    try:
        analysis.Run()
    except Exception as exc:  # Kratos raises on a failed solve in some versions: keep what converged
        record["error"] = repr(exc)
    record["wall_time"] = time.perf_counter() - t0
    record["status"] = ("converged" if record["steps"] and all(s["converged"] for s in record["steps"])
                        and "error" not in record else "not converged")
    result_path.write_text(json.dumps(record, indent=1))
    print(f"kratos_ironing: {record['status']}, {len(record['steps'])} steps, {record['wall_time']:.1f} s")
    return 0 if record["status"] == "converged" else 1


if __name__ == "__main__":
    raise SystemExit(main())
