"""The SCD semismooth* Newton method for a nonlinear f (issue 36, the core): 0 in f(u) + Q(u)
with f the residual of a hyperelastic body (:mod:`contactqvi.contact.hyperelastic`).

A block on a frictionless rigid plane, rollers on two lateral faces, its top face pushed
down by 30 % of its height in ten load steps, the other faces free: the deformation is
homogeneous uniaxial stress, F = diag(a, a, s) with s = 0.7 and the lateral stretch a
from zero lateral stress, which trilinear hexahedra represent exactly. Closed forms
(docs/finite_strain.md):

* neo-Hookean, P = mu (F - F^-T) + lambda ln J F^-T: mu (a^2 - 1) + lambda ln(a^2 s) = 0,
  P33 = mu (s - 1/s) + lambda ln(a^2 s) / s;
* Saint Venant-Kirchhoff, S = lambda tr E I + 2 mu E: E11 = -lambda E33 / (2 (lambda + mu)),
  P33 = s (lambda (2 E11 + E33) + 2 mu E33).

The displacement must equal u = ((a - 1) x, (a - 1) y, (s - 1) z) to 1e-8 of its size and
the contact pressure must be uniform and equal to -P33 to 1e-8, in every step.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
import scipy.optimize


from contactqvi.contact import LoadStep, build_contact_problem, solve_load_path
from contactqvi.elasticity import lame_parameters
from contactqvi.laws import Frictionless
from contactqvi.materials import NeoHookean, SaintVenantKirchhoff
from contactqvi.meshes import create_contact_body

YOUNG, POISSON = 10e6, 0.3  # Pa, a compressible rubber-like solid
COMPRESSION = 0.3  # of the height 1 m
STEPS = 10
MU, LMBDA = lame_parameters(YOUNG, POISSON)


def neo_hookean(s: float) -> tuple[float, float]:
    """Lateral stretch a and axial nominal stress P33 (Pa) of uniaxial stress at axial stretch s."""
    a = scipy.optimize.brentq(lambda a: MU * (a * a - 1.0) + LMBDA * np.log(a * a * s), 0.5, 2.0, xtol=1e-15)
    return a, MU * (s - 1.0 / s) + LMBDA * np.log(a * a * s) / s


def saint_venant_kirchhoff(s: float) -> tuple[float, float]:
    e3 = (s * s - 1.0) / 2.0
    e1 = -LMBDA * e3 / (2.0 * (LMBDA + MU))
    return np.sqrt(1.0 + 2.0 * e1), s * (LMBDA * (2.0 * e1 + e3) + 2.0 * MU * e3)


CLOSED_FORMS = {"neo_hookean": (NeoHookean(), neo_hookean), "saint_venant_kirchhoff": (SaintVenantKirchhoff(),
                                                                                       saint_venant_kirchhoff)}


def _compressed_block(material, compression: float, steps: int, lev: int = 1) -> list[dict]:
    """Solve the compression in ``steps`` equal load steps; per step the displacement, the
    contact nodes' coordinates, pressures and the Newton count."""
    comm = MPI.COMM_WORLD
    msh, tags = create_contact_body(comm, lev, lambda x, y: np.zeros_like(x), length=1.0, width=1.0, height=1.0)
    problem = build_contact_problem(msh, tags, YOUNG, POISSON, {}, Frictionless(), clamped=(), contact="contact",
                                    displacements={"dirichlet": {0: 0.0}, "front": {1: 0.0},
                                                   "top": {2: -compression}}, material=material)
    rows = []

    def record(index, step, u, result, state):
        assert result.converged, result.status
        x = problem.V.tabulate_dof_coordinates()[: problem.V.dofmap.index_map.size_local]
        rows.append({"load": step.load, "x": x, "u": state.displacement.x.array.reshape(-1, 3)[: len(x)].copy(),
                     "pressure": result.normal_force / problem.contact_area, "iterations": result.iterations})

    with problem:
        u = problem.A.createVecRight()
        solve_load_path(problem, [LoadStep((k + 1) / steps) for k in range(steps)], u, {"pc": "lu"},
                        on_step=record, from_rest=True)
        u.destroy()
    return rows


@pytest.mark.parametrize("name", CLOSED_FORMS)
def test_uniaxial_compression_on_a_rigid_plane_is_the_closed_form(name):
    material, closed_form = CLOSED_FORMS[name]
    comm = MPI.COMM_WORLD
    for row in _compressed_block(material, COMPRESSION, STEPS):
        s = 1.0 - COMPRESSION * row["load"]
        a, P33 = closed_form(s)
        exact = row["x"] * np.array([a - 1.0, a - 1.0, s - 1.0])
        error = comm.allreduce(float(np.abs(row["u"] - exact).max(initial=0.0)), op=MPI.MAX)
        assert error <= 1e-8 * (1.0 - s), (row["load"], error)
        p = row["pressure"]
        spread = comm.allreduce(float(np.abs(p + P33).max(initial=0.0)), op=MPI.MAX)
        assert spread <= 1e-8 * abs(P33), (row["load"], spread, P33)
        assert row["iterations"] <= 8, row


def test_a_hyperelastic_body_at_small_strain_is_the_linear_one():
    """At 1e-4 compression the neo-Hookean and the linear solution agree to O(strain)."""
    comm = MPI.COMM_WORLD
    (neo,), (linear,) = (_compressed_block(m, 1e-4, 1) for m in (NeoHookean(), None))
    size = comm.allreduce(float(np.abs(linear["u"]).max(initial=0.0)), op=MPI.MAX)
    difference = comm.allreduce(float(np.abs(neo["u"] - linear["u"]).max(initial=0.0)), op=MPI.MAX)
    assert difference <= 1e-3 * size, difference / size
