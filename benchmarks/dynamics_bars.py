"""Two equal bars meeting head-on (issue 44): the contact-stabilised time schemes against 1D wave theory.

This benchmark illustrates how to run a dynamic case from Python (``run_dynamics``) and
checks it against the closed form: two bars of length L, one hexahedron across (lateral
rollers: uniaxial strain, so the wave speed is c = sqrt(E (1 - nu) / ((1 + nu)(1 - 2 nu) rho)),
the constrained modulus), ``--elements`` hexahedra along each, meet at +-v. The contact lasts
2L/c, the bars then leave with the velocities exchanged and, for an exact scheme, the energy
they had. Per mesh and time step (tau = (2L/c) / (k n) for k of ``--courant-steps``, n the
elements along a bar: k = 2 is Courant number 1): the contact duration, the mean velocities
after separation, the energy after separation and the balance error (docs/dynamics.md, Sect. 4:
the solver's error for Newmark's rule; for HHT-α and generalized-α also the scheme's own
numerical dissipation, which the energy after separation then holds as well). ``--schemes``
takes ``newmark``, ``hht:ALPHA`` and ``generalized_alpha:RHO_INFINITY``.

Issue 44's bounds: duration 1 %, velocities 2 %, energy 1 %. Writes
``benchmarks/results/<--table>.{json,md}`` (default ``dynamics``).
"""

from __future__ import annotations

import argparse
import math
import pathlib
import tempfile
import time

from mpi4py import MPI

from contactqvi import tables
from contactqvi.case import Body, Boundary, ContactCase, ContactPair, Displacement, Dynamics, Material, MeshSource
from contactqvi.dynamic_runner import run_dynamics
from contactqvi.laws import Frictionless

ROOT = pathlib.Path(__file__).resolve().parent.parent
E, NU, RHO, V0, L = 210e9, 0.3, 7800.0, 1.0, 1.0
C = math.sqrt(E * (1 - NU) / ((1 + NU) * (1 - 2 * NU)) / RHO)
DURATION = 2 * L / C

GEO = """SetFactory("OpenCASCADE");
n = {n}; a = {a};
Box(1) = {{0, 0, 0, {L}, a, a}};
Box(2) = {{{L}, 0, 0, {L}, a, a}};
eps = 1e-6;
Transfinite Curve{{:}} = 2;
For iy In {{0:1}}
  For iz In {{0:1}}
    Transfinite Curve{{Curve In BoundingBox{{-eps, iy * a - eps, iz * a - eps, 2 * {L} + eps, iy * a + eps,
                                            iz * a + eps}}}} = n + 1;
  EndFor
EndFor
Transfinite Surface{{:}};
Recombine Surface{{:}};
Transfinite Volume{{:}};
Physical Volume("left") = {{1}};
Physical Volume("right") = {{2}};
Physical Surface("interface") = Surface In BoundingBox{{{L} - eps, -eps, -eps, {L} + eps, a + eps, a + eps}};
sy[] = Surface In BoundingBox{{-eps, -eps, -eps, 2 * {L} + eps, eps, a + eps}};
sy[] += Surface In BoundingBox{{-eps, a - eps, -eps, 2 * {L} + eps, a + eps, a + eps}};
Physical Surface("sides_y") = sy[];
sz[] = Surface In BoundingBox{{-eps, -eps, -eps, 2 * {L} + eps, a + eps, eps}};
sz[] += Surface In BoundingBox{{-eps, -eps, a - eps, 2 * {L} + eps, a + eps, a + eps}};
Physical Surface("sides_z") = sz[];
"""


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--elements", type=int, nargs="+", default=[20, 40, 80, 160], help="hexahedra along a bar")
    parser.add_argument("--courant-steps", type=int, nargs="+", default=[2, 4],
                        help="k: time steps per element crossing time h/c times 1/2 (tau = (2L/c) / (k n))")
    parser.add_argument("--schemes", nargs="+", default=["newmark"],
                        help="newmark, hht:ALPHA, generalized_alpha:RHO_INFINITY")
    parser.add_argument("--output", default=str(ROOT / "benchmarks" / "results"))
    parser.add_argument("--table", default="dynamics", help="the results' file name, without suffix")
    return parser.parse_args()


def dynamics(tau: float, scheme: str) -> Dynamics:
    """[dynamics] to 1.25 (2L/c) with the time step ``tau`` and ``scheme`` (``name[:parameter]``)."""
    name, _, value = scheme.partition(":")
    key = {"hht": "alpha", "generalized_alpha": "rho_infinity"}.get(name)
    parameters = {key: float(value)} if key and value else {}
    return Dynamics(tau, 1.25 * DURATION, scheme=name, **parameters)


def run(n: int, k: int, scheme: str, directory: pathlib.Path) -> list:
    """One mesh, time step and scheme: the row of the table."""
    mesh = directory / f"bars_{n}.geo"
    if MPI.COMM_WORLD.rank == 0:
        mesh.write_text(GEO.format(n=n, a=L / n, L=L))
    MPI.COMM_WORLD.Barrier()
    material = Material(E, NU, density=RHO)
    rollers = Boundary(displacement={"sides_y": Displacement(y=0.0), "sides_z": Displacement(z=0.0)})
    tau = DURATION / (k * n)
    case = ContactCase(mesh=MeshSource(file=mesh), bodies=(Body("left", material, rollers, (V0, 0.0, 0.0)),
                                                           Body("right", material, rollers, (-V0, 0.0, 0.0))),
                       contacts=(ContactPair("right.interface", "left.interface", law=Frictionless(), search="once"),),
                       dynamics=dynamics(tau, scheme), solver={"pc": "lu"})
    start = time.perf_counter()
    summary, _ = run_dynamics(case, directory / f"run_{n}_{k}_{scheme}", plot=False)
    seconds = time.perf_counter() - start
    steps = summary["steps"]
    touching = [s["time"] for s in steps if s["contact_area"] > 0.0]
    duration = (touching[-1] - touching[0] + tau) / DURATION
    last = steps[-1]
    before = RHO * 2 * L * (L / n) ** 2 * V0**2 / 2
    after = (last["energy"]["kinetic"] + last["energy"]["elastic"]) / before
    velocities = last["body_velocity"]["left"][0], last["body_velocity"]["right"][0]
    balance = max(abs(s["energy"]["balance_error"]) for s in steps) / before
    return [scheme, n, f"(2L/c)/{k * n}", duration, velocities[0], velocities[1], after, balance, round(seconds, 1)]


def main() -> None:
    args = parse()
    comm = MPI.COMM_WORLD
    directory = pathlib.Path(comm.bcast(tempfile.mkdtemp(prefix="bars-") if comm.rank == 0 else None, root=0))
    rows = [run(n, k, scheme, directory) for scheme in args.schemes for n in args.elements for k in args.courant_steps]
    header = ["scheme", "elements along a bar", "tau", "duration / (2L/c)", "v left after (m/s)", "v right after (m/s)",
              "energy after / before", "largest balance error / energy", "seconds"]
    text = (f"# Two bars head-on (benchmarks/dynamics_bars.py, {comm.size} rank(s))\n\n"
            f"L = {L} m, one hexahedron across (lateral rollers), E = {E:g} Pa, nu = {NU}, rho = {RHO} kg/m^3, "
            f"v = +-{V0} m/s; c = {C:.1f} m/s (constrained modulus), 2L/c = {DURATION * 1e6:.2f} us; exact: "
            "duration 1, velocities -1 and +1 m/s, energy 1. Contact-stabilised schemes (docs/dynamics.md).\n\n"
            + tables.markdown_table(header, rows))
    tables.write_table(comm, pathlib.Path(args.output) / args.table, {"header": header, "rows": rows}, text)


if __name__ == "__main__":
    main()
