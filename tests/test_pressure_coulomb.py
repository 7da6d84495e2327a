"""Coulomb friction with a pressure-dependent coefficient (contactqvi.laws.pressure_coulomb), solved.

The nodal algebra of the law (resolvent, states, SCD bases against finite
differences) is tested with every other law in ``tests/test_contact_nodal.py``;
here the law solves the paper's body (seed 000, Sect. 7) at lev 3: the SCD Newton
method converges, every contact node meets the law, the classical fixed point of
Tresca problems reaches the same solution, and a case file and the demo take it.
"""

from __future__ import annotations

import copy
import json
import pathlib
import tomllib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi import meshes
from contactqvi.case import parse_case
from contactqvi.contact import SCDNewtonSolver, State, build_contact_problem
from contactqvi.contact.fixed_point import solve_tresca_fixed_point
from contactqvi.laws import PressureDependentCoulomb
from contactqvi.problems import coulomb as data
from contactqvi.runner import run_case
from law_checks import assert_contact_law_holds

ROOT = pathlib.Path(__file__).resolve().parent.parent

#: Contact pressures on the paper's body at lev 3 run from 2e7 to 3e9 Pa, so p0 = 1 GPa puts the
#: coefficient half-way in the middle of the contact zone: rising 0.1 -> 0.4 (metals), falling 0.4 -> 0.1.
RISING, FALLING = PressureDependentCoulomb(0.1, 0.4, 1e9), PressureDependentCoulomb(0.4, 0.1, 1e9)


def _problem(law: PressureDependentCoulomb, geometry: str, load: str):
    msh, tags = meshes.create_contact_body(MPI.COMM_WORLD, 3, data.gap_function(geometry))
    return build_contact_problem(msh, tags, data.YOUNG, data.POISSON, data.tractions(load), law)


def _solve(problem, prefix: str, **parameters):
    u = problem.A.createVecRight()
    with SCDNewtonSolver(problem, parameters, prefix=prefix) as solver:
        result = solver.solve(u)
    return u, result


@pytest.mark.parametrize("law", [RISING, FALLING], ids=["rising", "falling"])
@pytest.mark.parametrize("geometry, load", [("d1", "L1"), ("d3", "L2")])
def test_paper_body_meets_the_law_at_every_contact_node(law, geometry, load):
    """Exact inner solves: converged to 1e-12 in as many Newton steps as Coulomb (8 at F = 0.23), the
    conditions of the law at every node, and at the sliding nodes friction force / normal force equal
    to F(p) of the node's pressure, over a range of coefficients (the law is really pressure-dependent)."""
    problem = _problem(law, geometry, load)
    u, result = _solve(problem, f"pressure_{geometry}_", pc="lu")
    assert result.converged and result.iterations <= 12
    lam = assert_contact_law_holds(problem, u, result)
    slide = (result.states == State.SLIDING) & (lam > 0.0)
    ratio = np.linalg.norm(result.friction_force[slide], axis=1) / result.normal_force[slide]
    expected = law.coefficient(result.normal_force[slide] / problem.contact_area[slide])
    np.testing.assert_allclose(ratio, expected, rtol=1e-8)
    comm = problem.comm
    spread = comm.allreduce(float(expected.max(initial=-np.inf)), op=MPI.MAX) - comm.allreduce(
        float(expected.min(initial=np.inf)), op=MPI.MIN)
    assert spread > 0.1
    counts = result.history[-1]["states"]
    assert counts["sliding"] > 0 and counts["sticking"] > 0


def test_fixed_point_of_tresca_problems_reaches_the_same_solution():
    """An independent route: Tresca problems with the bound b(lambda) of the previous iterate,
    s <- lambda F(lambda / area), converge to the SCD Newton solution (1e-8)."""
    problem = _problem(RISING, "d3", "L2")
    u_newton, result = _solve(problem, "pressure_reference_", pc="lu")
    u = problem.A.createVecRight()
    fixed_point = solve_tresca_fixed_point(problem, u, {"pc": "lu"})
    assert result.converged and fixed_point.converged and fixed_point.iterations >= 2
    u.axpy(-1.0, u_newton)
    assert u.norm() <= 1e-8 * u_newton.norm()
    for vec in (u, u_newton):
        vec.destroy()


def test_case_file_with_the_law(mpi_tmp_path):
    """``law = "pressure_coulomb"`` in a case file: read, written back in the same keys, solved."""
    with open(ROOT / "cases" / "paper_d3_L2.toml", "rb") as f:
        data_ = tomllib.load(f)
    data_ = copy.deepcopy(data_)
    data_["mesh"]["box"]["lev"] = 3
    data_["contact"] = {"surface": "contact", "law": "pressure_coulomb", "friction": 0.1, "friction_limit": 0.4,
                        "pressure_scale": 1e9}
    case = parse_case(data_, ROOT / "cases")
    assert case.contact.law == RISING and case.to_dict()["contact"] == data_["contact"]
    summary, code = run_case(case, mpi_tmp_path / "pressure_case", MPI.COMM_WORLD, plot=False)
    assert code == 0 and summary["steps"][0]["converged"]
    assert summary["case"]["contact"]["law"] == "pressure_coulomb"


@pytest.mark.parametrize("args, name", [
    (["--law", "pressure_coulomb", "--pressure-scale", "1e9"], "friction-limit"),
    (["--law", "pressure_coulomb", "--friction-limit", "0.4", "--pressure-scale", "0"], "pressure-scale"),
    (["--friction-limit", "0.4"], "friction-limit"),
])
def test_demo_names_the_option_of_a_bad_parameter(args, name, capsys, load_demo):
    assert load_demo("coulomb3d").main(["--no-plot", *args]) == 2
    assert capsys.readouterr().err.count(f"error: {name}:") == (MPI.COMM_WORLD.rank == 0)


def test_demo_solves_with_the_law(mpi_tmp_path, load_demo):
    """``--law pressure_coulomb``: solved, the law in summary.json, no paper numbers beside it."""
    out = mpi_tmp_path / "demo"
    argv = ["--lev", "2", "--law", "pressure_coulomb", "--friction-limit", "0.4", "--pressure-scale", "1e9",
            "--output", str(out), "--no-plot"]
    assert load_demo("coulomb3d").main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] and summary["paper"] is None
    assert summary["law"] == {"law": "pressure_coulomb", "friction": data.FRICTION, "friction_limit": 0.4,
                              "pressure_scale": 1e9}  # --friction: the paper's F by default
