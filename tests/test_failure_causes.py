"""A step that fails says why, in the log and in ``summary.json`` (issue 46).

* A block pushed past what friction holds (``tests/data/friction_capacity/pushed_block.toml``:
  50 N along the plane, 1 MPa on 1 cm^2 pressing it, friction 0.3) ended in a bare
  ``diverged_line_search`` / ``diverged_max_it``; now ``failure`` names the pair, the load and
  the friction bound.
* A Krylov solve that fails falls back once to a direct solve (MUMPS LU) for that Newton step:
  with no Krylov iteration allowed at all, the patch test takes exactly the Newton steps of
  exact solves, and every Newton step records the fall-back.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import re

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import load_case
from contactqvi.contact.diagnosis import tangential_load
from contactqvi.runner import EXIT_CODES, build_problem, run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
PUSHED = ROOT / "tests" / "data" / "friction_capacity" / "pushed_block.toml"


def test_a_load_beyond_what_friction_holds_is_named(mpi_tmp_path):
    """No equilibrium: the failure names the pair, the 50 N along the plane (the front face's
    0.5 MPa on 1 cm^2; the roller's x component left out) and friction 0.3 times the normal force."""
    summary, code = run_case(load_case(PUSHED), mpi_tmp_path / "out", plot=False)
    assert code == EXIT_CODES["not converged"] and summary["status"] == "diverged_max_it"
    failure = summary["failure"]
    match = re.fullmatch(r"no equilibrium: the tangential load exceeds μ × the normal force on pair bottom/obstacle: "
                         r"the loads on the body that no support takes push along the contact plane with (\S+) N, and "
                         r"friction holds at most (\S+) × (\S+) N = (\S+) N there \((\d+) nodes of 'bottom' slide at "
                         r"their bound, none sticks\); lower the tangential load, raise the friction or hold the body "
                         r"along the plane", failure)
    assert match, failure
    load, mu, normal, bound = (float(match[i]) for i in range(1, 5))
    assert load == pytest.approx(50.0, rel=1e-4) and mu == pytest.approx(0.3, rel=1e-4)
    assert bound == pytest.approx(mu * normal, rel=1e-3) and load > bound and normal > 0.0
    assert summary["steps"][-1]["failure"] == failure
    assert json.loads((mpi_tmp_path / "out" / "summary.json").read_text())["failure"] == failure


def test_the_tangential_load_leaves_out_what_the_supports_take():
    """The resultant of the loads is (0, 50, -100) N; the roller takes x (none here), the plane's
    normal is z: 50 N along the plane, to round-off."""
    case = load_case(PUSHED)
    with build_problem(case, MPI.COMM_WORLD) as problem:  # at load factor 1
        assert tangential_load(problem, 0) == pytest.approx(50.0, rel=1e-12)


def test_friction_that_holds_the_load_converges_without_a_failure(mpi_tmp_path):
    """Friction 0.6 holds the 50 N (60 N at 100 N pressing): converged, no ``failure``."""
    case = load_case(PUSHED)
    held = dataclasses.replace(case, contact=dataclasses.replace(case.contact, law=dataclasses.replace(
        case.contact.law, friction=0.6)))
    summary, code = run_case(held, mpi_tmp_path / "out", plot=False)
    assert code == EXIT_CODES["converged"] and "failure" not in summary
    assert summary["steps"][-1]["pair_forces"]["bottom/obstacle"][1] == pytest.approx(-50.0, rel=1e-9)


def test_a_failed_krylov_solve_falls_back_to_a_direct_one(mpi_tmp_path):
    """``ksp_max_it = 0``: every Krylov solve fails, each Newton step is solved by LU instead and
    says so; the Newton steps and the solution are those of exact solves (pc = "lu")."""
    case = load_case(ROOT / "cases" / "patch_test.toml")
    exact, _ = run_case(dataclasses.replace(case, solver={"pc": "lu"}), mpi_tmp_path / "lu", plot=False)
    summary, code = run_case(dataclasses.replace(case, petsc={"ksp_max_it": 0}), mpi_tmp_path / "krylov", plot=False)
    assert code == EXIT_CODES["converged"]
    step, reference = summary["steps"][-1], exact["steps"][-1]
    assert step["iterations"] == reference["iterations"] > 0
    assert step["displacement_norm"] == pytest.approx(reference["displacement_norm"], rel=1e-12)
    solves = [entry for entry in step["history"] if "ksp_reason" in entry]
    assert len(solves) == step["iterations"]
    assert all(entry["direct_fallback"] == "DIVERGED_MAX_IT" and entry["direct_reason"] == "CONVERGED_ITS"
               for entry in solves)
    assert not any("direct_fallback" in entry for entry in reference["history"])
    records = [record for record in summary["warnings"] if record["key"] == "direct_fallback"]
    assert len(records) == len(solves) and not any(r["key"] == "direct_fallback" for r in exact["warnings"])
    assert records[0]["message"] == ("the Krylov solve of a Newton step failed (DIVERGED_MAX_IT after 0 iterations): "
                                     "solved by lu (MUMPS) instead, CONVERGED_ITS")
    assert np.isfinite(step["equilibrium_error"]) and step["equilibrium_error"] < 1e-10


def test_a_stall_where_friction_holds_is_not_called_no_equilibrium(mpi_tmp_path):
    """Friction 0.6 from rest (``solver.start = "rest"``): nothing holds the block along y or z
    before a node touches, the line search fails at the first Newton step with no node sliding;
    the failure says so and does not claim that friction cannot hold the load."""
    case = load_case(PUSHED)
    rest = dataclasses.replace(case, solver={**case.solver, "start": "rest"},
                               contact=dataclasses.replace(case.contact, law=dataclasses.replace(case.contact.law,
                                                                                                 friction=0.6)))
    summary, code = run_case(rest, mpi_tmp_path / "out", plot=False)
    assert code == EXIT_CODES["not converged"] and summary["status"] == "diverged_line_search"
    assert re.fullmatch(r"the line search accepted no step size \(\|\|y\^\|\| = \S+ N at Newton step 0, 1\.00e\+00 of "
                        r"the start; target \S+ N\)", summary["failure"]), summary["failure"]


@pytest.mark.one_rank(reason="a function of a result's history")
def test_a_cut_step_names_where_its_parts_stopped():
    """A step cut until its cuts ran out: the failure names the last converged part and the nearest
    attempt beyond it (the seal of docs/finite_strain.md Sect. 11 ends so, 3 nm beyond its last
    equilibrium); a step that was never cut adds nothing."""
    from contactqvi.contact.diagnosis import _path_end
    from contactqvi.contact.scd_newton import SCDNewtonResult
    from contactqvi.result import Status

    def part(j: int, z: float, status: str) -> dict:
        return {"k": 0, "substep": j, "substep_load": 1.0, "substep_translation": [0.0, 0.0, z],
                "substep_status": status}

    history = [part(0, -1.35e-3, "diverged_max_it"), part(1, -1.3125e-3, "diverged_max_it"),
               part(2, -1.29375e-3, "converged_atol"), part(3, -1.303125e-3, "diverged_max_it"),
               part(4, -1.2984375e-3, "diverged_max_it")]
    result = SCDNewtonResult(status=Status.DIVERGED_MAX_IT, iterations=0, gamma=1.0, target=1.0, states=np.empty(0),
                             normal_force=np.empty(0), friction_force=np.empty((0, 2)), history=history)
    text = _path_end(result)
    assert "2 attempts failed after the step was cut" in text
    assert "converged up to load factor 1, translation (0, 0, -0.00129375) m" in text
    assert "the nearest attempt beyond, to load factor 1, translation (0, 0, -0.001298437) m, failed" in text
    assert _path_end(dataclasses.replace(result, history=[part(0, -1.35e-3, "diverged_max_it")])) == ""


@pytest.mark.one_rank(reason="a function of a result's history")
def test_a_stalled_solve_says_so():
    """``diverged_stalled`` (``stall_iterations``): the cause names the stall and the last Newton step."""
    from contactqvi.contact.diagnosis import _status_cause
    from contactqvi.contact.scd_newton import SCDNewtonResult
    from contactqvi.result import Status

    history = [{"k": 21, "residual": 3.1e-1, "relative_residual": 3.9e-2}]
    result = SCDNewtonResult(status=Status.DIVERGED_STALLED, iterations=21, gamma=1.0, target=1e-9,
                             states=np.empty(0), normal_force=np.empty(0), friction_force=np.empty((0, 2)),
                             history=history)
    text = _status_cause(result)
    assert text.startswith("stalled: ||y^|| did not halve") and "3.100e-01 N at Newton step 21" in text


@pytest.mark.one_rank(reason="a function of a result's history")
def test_a_relaxation_without_equilibrium_says_so():
    """A step relaxed past a limit point (docs/finite_strain.md Sect. 15) that reached no
    equilibrium: the failure counts its relaxation steps and the plain solves that did not converge
    (not "the configuration did not settle", the message of its last solve's status); a step that
    never relaxed gets none of it."""
    from contactqvi.contact.diagnosis import _relaxation_end
    from contactqvi.contact.scd_newton import SCDNewtonResult
    from contactqvi.result import Status

    def entry(j: int, k: int, viscosity: float) -> dict:
        return {"k": 0, "residual": 1e-13, "substep": j, "relaxation": k, "viscosity": viscosity}

    history = [{"k": 0, "substep": 0}, entry(1, 1, 1e7), entry(2, 2, 5e6), entry(3, 2, 0.0), entry(4, 3, 2e7)]
    result = SCDNewtonResult(status=Status.DIVERGED_MAX_IT, iterations=0, gamma=1.0, target=1.0, states=np.empty(0),
                             normal_force=np.empty(0), friction_force=np.empty((0, 2)), history=history)
    text = _relaxation_end(result)
    assert "relaxed past the limit point for 3 steps" in text and "1 solve without the viscous term from where it slowed down failed" in text
    assert "never slowed down" in _relaxation_end(dataclasses.replace(result, history=history[:3]))
    assert _relaxation_end(dataclasses.replace(result, history=history[:1])) is None
    assert _relaxation_end(dataclasses.replace(result, status=Status.INTERRUPTED)) is None


@pytest.mark.one_rank(reason="a function of the states of one rank's nodes")
def test_each_node_counts_its_changes_of_state():
    """:meth:`SCDNewtonResult.record_states`: a node's changes from one iterate to the next, and the
    state it left last; a new set of contact nodes (a search) starts the count again."""
    from contactqvi.contact.nodal import State
    from contactqvi.contact.scd_newton import SCDNewtonResult
    from contactqvi.result import Status

    result = SCDNewtonResult(status=Status.DIVERGED_MAX_IT, iterations=0, gamma=1.0, target=1.0,
                             states=np.empty(0, np.int8), normal_force=np.empty(0), friction_force=np.empty((0, 2)))
    open_, sliding, sticking = State.NO_CONTACT, State.SLIDING, State.STICKING
    for states in ([open_, sliding, sticking], [sliding, sliding, sticking], [open_, sliding, sliding],
                   [sliding, sliding, sliding]):
        result.record_states(np.array(states, np.int8))
    assert result.switches.tolist() == [3, 0, 1] and result.switched_from.tolist() == [open_, sliding, sticking]
    result.record_states(np.array([open_, sliding], np.int8))
    assert result.switches.tolist() == [0, 0]


def test_a_node_that_cycles_is_named(mpi_tmp_path):
    """A stalled solve whose contact node changed its state 7 times (``CYCLING`` = 5 or more): the
    cause names the node by its reference position and pair, the count and the two states; with
    every node changing less than 5 times nothing is added. Collective: the node may lie on any rank."""
    from contactqvi.contact.diagnosis import CYCLING, _cycling, _point
    from contactqvi.contact.nodal import State
    from contactqvi.contact.scd_newton import SCDNewtonResult
    from contactqvi.result import Status

    with build_problem(load_case(PUSHED), MPI.COMM_WORLD) as problem:
        comm, m = problem.comm, len(problem.contact_blk)
        x = problem.V.tabulate_dof_coordinates()[problem.contact_blk]
        key = x @ np.array([1.0, 10.0, 100.0])  # one node, the same on any number of ranks
        chosen = key == comm.allreduce(float(key.max(initial=-np.inf)), op=MPI.MAX)
        switches = np.where(chosen, 7, CYCLING - 1).astype(np.int32)
        result = SCDNewtonResult(status=Status.DIVERGED_MAX_IT, iterations=40, gamma=1.0, target=1.0,
                                 states=np.full(m, State.SLIDING, np.int8), normal_force=np.zeros(m),
                                 friction_force=np.zeros((m, 2)), history=[{"k": 40}], switches=switches,
                                 switched_from=np.full(m, State.NO_CONTACT, np.int8))
        text = _cycling(problem, result)
        where = comm.allreduce([tuple(point) for point in x[chosen]], op=MPI.SUM)[0]
        assert text == (f"; the contact state cycles: the node at {_point(np.array(where))} m of "
                        "bottom/obstacle changed its state 7 times in its last 40 Newton steps, between no contact and "
                        "sliding")
        assert _cycling(problem, dataclasses.replace(result, switches=np.full(m, CYCLING - 1, np.int32))) == ""
    assert _point(np.array([9.634e-3, 3.66e-4, 1.99e-20])) == "(0.009634, 0.000366, 0)"
