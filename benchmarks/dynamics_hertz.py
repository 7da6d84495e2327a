"""An elastic sphere dropped on a rigid plane (issue 44): impact duration and peak force against Hertz.

This benchmark illustrates how to run a dynamic case with a rigid obstacle from Python: a
quarter of a steel sphere (radius R, symmetry planes x = 0 and y = 0 on rollers) touches the
plane z = -R at time 0 with speed v. Hertz's quasi-static impact theory (valid while the
contact lasts much longer than a wave's transit, 2R/c) gives, with the full sphere's mass m
and E* = E / (1 - nu^2) against a rigid plane,

    t_c = 2.87 (m^2 / (R E*^2 v))^(1/5),
    F_max = 4/3 E* sqrt(R) delta_max^(3/2),  delta_max = (15 m v^2 / (16 E* sqrt(R)))^(2/5).

Per contact mesh size h (``--sizes``, m, graded to ``--far`` away from the contact) and time
step tau = t_c / k (``--steps``): the contact duration (first to last step with a contact
force, plus one step) and the largest step-mean contact force (four times the quarter's),
against t_c and F_max; and the energy after the impact. Contact-stabilised Newmark
(docs/dynamics.md). Issue 44's bound: 3 % on the finest mesh. Writes
``benchmarks/results/dynamics_hertz.{json,md}``. Run with ``nice`` on a shared machine.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import tempfile
import time

from mpi4py import MPI

from contactqvi import tables
from contactqvi.case import Boundary, Contact, ContactCase, Displacement, Dynamics, Material, MeshSource, ObstacleShape
from contactqvi.dynamic_runner import run_dynamics
from contactqvi.laws import Frictionless

ROOT = pathlib.Path(__file__).resolve().parent.parent
E, NU, RHO, V0, R = 210e9, 0.3, 7800.0, 1.0, 0.1
E_STAR = E / (1 - NU**2)
MASS = RHO * 4.0 / 3.0 * math.pi * R**3
T_C = 2.87 * (MASS**2 / (R * E_STAR**2 * V0)) ** 0.2
DELTA = (15 * MASS * V0**2 / (16 * E_STAR * math.sqrt(R))) ** 0.4
F_MAX = 4.0 / 3.0 * E_STAR * math.sqrt(R) * DELTA**1.5

#: A mesh of meshes/drop_ball.geo with the contact size h and the far size (m).
GEO = """R = {R}; h = {h}; far = {far}; near = {near};
Include "{ball}";
"""


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--sizes", type=float, nargs="+", default=[2e-3, 1.4e-3, 1e-3],
                        help="element size at the contact (m)")
    parser.add_argument("--far", type=float, default=0.02, help="element size away from the contact (m)")
    parser.add_argument("--steps", type=int, nargs="+", default=[20, 40, 80], help="time steps per t_c")
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    return parser.parse_args()


def run(h: float, far: float, k: int, directory: pathlib.Path) -> list:
    """One mesh and time step: the row of the table."""
    mesh = directory / f"ball_{h:g}.geo"
    if MPI.COMM_WORLD.rank == 0:
        mesh.write_text(GEO.format(R=R, h=h, far=far, near=3 * math.sqrt(R * DELTA),
                                   ball=ROOT / "meshes" / "drop_ball.geo"))
    MPI.COMM_WORLD.Barrier()
    case = ContactCase(mesh=MeshSource(file=mesh), material=Material(E, NU, density=RHO),
                       boundary=Boundary(displacement={"symmetry_x": Displacement(x=0.0),
                                                       "symmetry_y": Displacement(y=0.0)}),
                       contact=Contact("surface", Frictionless()),
                       obstacle=ObstacleShape("plane", point=(0.0, 0.0, -R), normal=(0.0, 0.0, 1.0)),
                       dynamics=Dynamics(T_C / k, 1.3 * T_C, initial_velocity=(0.0, 0.0, -V0)),
                       solver={"pc": "lu"})
    start = time.perf_counter()
    summary, _ = run_dynamics(case, directory / f"run_{h:g}_{k}", plot=False)
    seconds = time.perf_counter() - start
    steps = summary["steps"]
    touching = [s["time"] for s in steps if s["contact_force"][2] > 0.0]
    duration = touching[-1] - touching[0] + T_C / k
    force = 4 * max(s["contact_force"][2] for s in steps)
    energy = steps[-1]["energy"]
    after = (energy["kinetic"] + energy["elastic"]) / (MASS / 4 * V0**2 / 2)
    return [f"{h * 1e3:g}", f"t_c/{k}", summary["n"], duration / T_C, force / F_MAX, after, round(seconds, 1)]


def main() -> None:
    args = parse()
    comm = MPI.COMM_WORLD
    directory = pathlib.Path(comm.bcast(tempfile.mkdtemp(prefix="hertz-drop-") if comm.rank == 0 else None, root=0))
    header = ["h at contact (mm)", "tau", "free dofs", "duration / t_c", "peak force / F_max", "energy after / before",
              "seconds"]
    rows = []
    for h in args.sizes:
        for k in args.steps:  # the table is written after every run: a long grid keeps what it finished
            rows.append(run(h, args.far, k, directory))
            text = (f"# Hertz drop of a sphere on a rigid plane (benchmarks/dynamics_hertz.py, {comm.size} rank(s))\n\n"
                    f"R = {R} m, E = {E:g} Pa, nu = {NU}, rho = {RHO} kg/m^3, v = {V0} m/s (a quarter sphere, rollers "
                    f"on the symmetry planes): t_c = {T_C * 1e6:.1f} us, F_max = {F_MAX / 1e3:.2f} kN, delta_max = "
                    f"{DELTA * 1e6:.1f} um. Step-mean contact force (docs/dynamics.md, Sect. 3).\n\n"
                    + tables.markdown_table(header, rows))
            tables.write_table(comm, pathlib.Path(args.output) / "dynamics_hertz", {"header": header, "rows": rows},
                               text, echo=False)


if __name__ == "__main__":
    main()
