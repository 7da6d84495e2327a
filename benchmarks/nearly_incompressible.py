"""Newton-step Krylov counts against Poisson's ratio, plain P1 and nodal pressure (issue 43, item 3).

This benchmark illustrates how to:

* build the tetrahedral block of the uniaxial closed form (docs/finite_strain.md, Sect. 6)
  with either formulation (``formulation`` of :func:`~contactqvi.contact.build_contact_problem`);
* solve its compression with the default Newton-step solver (GAMG, the hyperelastic
  Krylov tolerance) and count Newton steps and Krylov iterations per load step.

The O-ring and seal runs behind ``benchmarks/results/nearly_incompressible.md`` are case
files run by ``python -m contactqvi run`` (docs/nearly_incompressible.md lists them).

::

    python benchmarks/nearly_incompressible.py --lev 2 --poisson 0.45 0.49 0.499
    python benchmarks/nearly_incompressible.py --lev 1 --degree 2 --formulations nodal_pressure \
        --pc pressure_schur --poisson 0.45 0.499 0.4999
    python benchmarks/nearly_incompressible.py --lev 1 --degree 2 --formulations nodal_pressure \
        --pc pressure_schur --wavy --linear --steps 1 --compression 0.01 --poisson 0.45 0.4999
    python benchmarks/nearly_incompressible.py --lev 1 --pc lu --formulations nodal_pressure --condensed \
        --poisson 0.45 0.49 0.499 0.4999
"""

from __future__ import annotations

import argparse

from mpi4py import MPI

import numpy as np

from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.laws import Frictionless
from contactqvi.materials import NeoHookean
from contactqvi.meshes import create_contact_body


def krylov_counts(lev: int, poisson: float, formulation: str, steps: int, compression: float,
                  pc: str = "gamg", degree: int = 1, wavy: bool = False,
                  linear: bool = False, mixed: bool = True) -> list[tuple[int, int]]:
    """(Newton steps, Krylov iterations) of each load step of the block's compression, on a flat or
    ``wavy`` foundation (that of tests/test_nearly_incompressible.py), neo-Hookean or ``linear``,
    by the ``mixed`` Newton method of the nodal pressure or the condensed one
    (docs/nearly_incompressible.md Sect. 7)."""
    def gap(x, y):
        return 0.02 * (1.0 - np.cos(np.pi * x)) * (1.0 - np.cos(np.pi * y)) if wavy else np.zeros_like(x)

    msh, tags = create_contact_body(MPI.COMM_WORLD, lev, gap, length=1.0, width=1.0, height=1.0,
                                    cell_type="tetrahedron")
    problem = build_contact_problem(msh, tags, 10e6, poisson, {}, Frictionless(), clamped=(), contact="contact",
                                    displacements={"dirichlet": {0: 0.0}, "front": {1: 0.0},
                                                   "top": {2: -compression}},
                                    material=None if linear else NeoHookean(), formulation=formulation,
                                    degree=degree)
    with problem:
        u = problem.A.createVecRight()
        results = solve_load_path(problem, [LoadStep((k + 1) / steps) for k in range(steps)], u,
                                  {"pc": pc, "mixed": mixed}, from_rest=True)
        u.destroy()
    return [(r.iterations, r.inner_iterations) for r in results]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--lev", type=int, default=2, help="block level (create_contact_body)")
    parser.add_argument("--poisson", type=float, nargs="+", default=[0.45, 0.49, 0.499], help="Poisson's ratios")
    parser.add_argument("--steps", type=int, default=3, help="load steps")
    parser.add_argument("--compression", type=float, default=0.1, help="of the height")
    parser.add_argument("--pc", default="gamg", help="Newton-step solver (SCD parameter pc)")
    parser.add_argument("--degree", type=int, default=1, help="displacement degree (mesh.order)")
    parser.add_argument("--wavy", action="store_true", help="the wavy foundation instead of the flat one")
    parser.add_argument("--linear", action="store_true", help="linear elasticity instead of neo-Hookean")
    parser.add_argument("--formulations", nargs="+", default=["displacement", "nodal_pressure"],
                        help="formulations compared")
    parser.add_argument("--condensed", action="store_true",
                        help="the nodal pressure by the condensed Newton method ([solver] mixed = false)")
    args = parser.parse_args()
    rows = [f"| nu | formulation | Newton steps per step | Krylov per step ({args.pc}) | Krylov per Newton step |",
            "|---|---|---|---|---|"]
    for poisson in args.poisson:
        for formulation in args.formulations:
            counts = krylov_counts(args.lev, poisson, formulation, args.steps, args.compression, args.pc,
                                   args.degree, args.wavy, args.linear, not args.condensed)
            newton, krylov = (sum(c[i] for c in counts) for i in (0, 1))
            rows.append(f"| {poisson} | {formulation} | {' '.join(str(c[0]) for c in counts)} | "
                        f"{' '.join(str(c[1]) for c in counts)} | {krylov / max(newton, 1):.1f} |")
    if MPI.COMM_WORLD.rank == 0:
        print("\n".join(rows))


if __name__ == "__main__":
    main()
