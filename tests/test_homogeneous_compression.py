"""Homogeneous compression of two stacked neo-Hookean blocks (issue 45, first Done-when item).

The closed form (docs/finite_strain.md, Sect. 12; :mod:`contactqvi.problems.uniaxial`): each
block in uniaxial stress F_k = diag(a_k, a_k, s_k), zero lateral stress (12.1), one axial
nominal stress P33 in both (12.3), the stretches adding up to the shortening (12.4); the
blocks expand alike (12.5) only with Poisson's ratios chosen for one shortening. Checked here
against its own equations evaluated directly, against the single block of Sect. 6, and the
30 % case of ``benchmarks/data/homogeneous_compression`` solved with the reference coupling
(``search = "once"``), whose solution it is at every load.
"""

from __future__ import annotations

import pathlib
import tomllib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import parse_case
from contactqvi.contact.scd_newton import HYPERELASTIC_TOL
from contactqvi.elasticity import lame_parameters
from contactqvi.paraview import read_vtx
from contactqvi.problems.uniaxial import matching_poisson, stacked_compression, uniaxial_stress
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
DATA = ROOT / "benchmarks" / "data" / "homogeneous_compression"
HEIGHTS = (1.0, 1.0)  # m, the blocks of meshes/patch_blocks.geo
LOWER = (10e6, 0.3)  # Pa, the lower block of the cases
UPPER_YOUNG = 5e6  # Pa
#: The closed form's tests: serial arithmetic that every rank would repeat.
CLOSED_FORM = pytest.mark.one_rank(reason="closed forms: scalar roots, the same on every rank")


def _blocks(name: str) -> tuple[list[tuple[float, float]], float]:
    """(Young's modulus, Poisson's ratio) of each block of the case ``name`` (bottom first) and its top's travel (m)."""
    data = tomllib.loads((DATA / name).read_text())
    return ([(b["material"]["young"], b["material"]["poisson"]) for b in data["bodies"]],
            -data["bodies"][1]["boundary"]["displacement"]["top"]["z"])


@CLOSED_FORM
@pytest.mark.parametrize("blocks, heights, shortening", [
    ([LOWER, (UPPER_YOUNG, 0.3)], HEIGHTS, 0.6),
    ([LOWER, (UPPER_YOUNG, 0.45)], (1.0, 0.5), 0.9),
    ([(2e6, 0.45), (1e9, 0.2)], (0.3, 2.0), 0.05),
])
def test_the_stack_solves_its_equations(blocks, heights, shortening):
    """(12.1) and (12.2) evaluated directly in each block, one P33 in both (12.3), the shortening (12.4),
    and the displacement: zero at the bottom, continuous across the interface, the travel at the top."""
    stack = stacked_compression(blocks, heights, shortening)
    a, s = stack.lateral_stretches, stack.axial_stretches
    mu, lmbda = np.transpose([lame_parameters(*b) for b in blocks])
    assert np.abs(mu * (a**2 - 1.0) + lmbda * np.log(a**2 * s)).max() <= 1e-12 * mu.max()
    axial = mu * (s - 1.0 / s) + lmbda * np.log(a**2 * s) / s
    assert np.abs(axial - stack.nominal_stress).max() <= 1e-12 * abs(stack.nominal_stress)
    assert abs(np.dot(heights, s) - (sum(heights) - shortening)) <= 1e-14 * sum(heights)
    assert abs(stack.travel - shortening) <= 1e-14 * sum(heights)
    interface = [0.3, 0.2, heights[0]]
    u = stack.displacement(np.array([[0.5, 0.5, 0.0], interface, interface, [0.5, 0.5, sum(heights)]]),
                           np.array([0, 0, 1, 1]))
    assert u[0, 2] == 0.0 and abs(u[1, 2] - u[2, 2]) <= 1e-15 and abs(u[3, 2] + shortening) <= 1e-14
    assert np.allclose(u[1:3, 0] / interface[0] + 1.0, a, rtol=0.0, atol=1e-15)
    assert np.allclose(stack.cauchy_stress, stack.nominal_stress / a**2, rtol=1e-15)


@CLOSED_FORM
def test_equal_blocks_are_the_single_block_of_sect_6():
    """Both blocks alike: s = 1 - shortening / height in both, a and P33 of uniaxial stress (Sect. 6)."""
    stack = stacked_compression([LOWER, LOWER], HEIGHTS, 0.6)
    a, P33 = uniaxial_stress(0.7, *LOWER)
    assert np.abs(stack.axial_stretches - 0.7).max() <= 1e-14
    assert np.abs(stack.lateral_stretches - a).max() <= 1e-14
    assert abs(stack.nominal_stress / P33 - 1.0) <= 1e-13


@CLOSED_FORM
def test_blocks_of_equal_poisson_ratio_and_different_moduli_do_not_expand_alike():
    """(12.1) fixes a from s and lambda/mu, but the softer block is compressed more (12.3): at 30 %,
    E = 10 and 5 MPa, nu = 0.3, a = 1.0775 and 1.1418, a step of 6.4 % of the width at the interface."""
    stack = stacked_compression([LOWER, (UPPER_YOUNG, LOWER[1])], HEIGHTS, 0.6)
    assert np.allclose(stack.lateral_stretches, [1.0775359, 1.1418092], rtol=0.0, atol=1e-7)


@CLOSED_FORM
@pytest.mark.parametrize("name", ["stacked_30.toml", "stacked_50.toml"])
def test_the_cases_poisson_ratio_makes_the_blocks_expand_alike(name):
    """The upper block's nu in the case file is :func:`matching_poisson` at its travel (to the 15 digits
    written), the blocks then expand alike to round-off; at small strain nu_1 / E_1 = nu_0 / E_0."""
    blocks, travel = _blocks(name)
    assert abs(matching_poisson(blocks[0], blocks[1][0], HEIGHTS, travel) - blocks[1][1]) <= 1e-14
    assert abs(np.diff(stacked_compression(blocks, HEIGHTS, travel).lateral_stretches)[0]) <= 1e-14
    small = matching_poisson(LOWER, UPPER_YOUNG, HEIGHTS, 1e-6)
    assert abs(small / (LOWER[1] * UPPER_YOUNG / LOWER[0]) - 1.0) <= 1e-5


@pytest.mark.parametrize("name, steps", [("stacked_30.toml", 6), ("stacked_50.toml", 10)])
def test_the_compressions_searched_once_are_the_closed_form(mpi_tmp_path, name, steps):
    """stacked_30.toml (6 steps) and stacked_50.toml (10 steps) with the reference coupling (``search =
    "once"``): at every step the displacement equals the closed form to 1e-8 of the top's travel (measured
    1.1e-13 at most), the pair force's tangential part is at most 1e-10 of its normal part (measured 1e-16)
    and the normal part is P33 times the reference area to 1e-10; no step is cut and none takes more than 8
    Newton steps (measured 5 in every step of both).
    Before a step whose predictor inverts elements started from the elastic response
    (load_path._add_elastic_change), every step was cut and the last one of 30 % ended at another
    equilibrium of the frozen coupling (0.76 of the travel from the closed form, force 11 % low); before
    that response was the tangent's at the last solution (load_path._tangent_change), the 50 % path's
    steps 7-10 were cut (19, 14, 48, 24 Newton steps; docs/finite_strain.md Sects. 12, 17)."""
    comm = MPI.COMM_WORLD
    data = tomllib.loads((DATA / name).read_text())
    data["contacts"][0]["search"] = "once"
    summary, code = run_case(parse_case(data, DATA), mpi_tmp_path, comm, plot=False)
    assert code == 0, summary["status"]
    assert not [step["step"] for step in summary["steps"] if any("substep" in e for e in step["history"])]
    assert max(step["iterations"] for step in summary["steps"]) <= 8, [s["iterations"] for s in summary["steps"]]
    blocks, travel = _blocks(name)
    errors = []
    for k, step in enumerate(summary["steps"]):
        stack = stacked_compression(blocks, HEIGHTS, step["load"] * travel)
        if comm.rank == 0:
            dataset = read_vtx(mpi_tmp_path / "body.bp", k)
            body = dataset.cell_data_at_points("body [1]").astype(np.int64)
            exact = stack.displacement(dataset.points, body)
            errors.append(float(np.abs(dataset.point_data["displacement [m]"] - exact).max()) / stack.travel)
        (force,) = step["pair_forces"].values()
        assert np.hypot(force[0], force[1]) <= 1e-10 * abs(force[2]), (step["step"], force)
        assert abs(force[2] + stack.nominal_stress * 1.0) <= 1e-10 * abs(stack.nominal_stress), (step["step"], force)
    errors = comm.bcast(errors, root=0)
    assert len(errors) == steps and max(errors) <= 1e-8, errors


@pytest.mark.parametrize("foundation", ["rollers", "plane"])
def test_the_30_percent_compression_searched_newton_is_the_closed_form(mpi_tmp_path, foundation):
    """stacked_30.toml as shipped (6 steps) with the geometry in the current configuration
    (``search = "newton"``, issue 45): at 30 % the displacement equals the closed form to 1e-8 of the
    top's travel (measured 9e-14), the flat frictionless interface carries no tangential force
    (at most 1e-10 of the normal; measured 5e-16) and the normal force is P33 times the reference
    area to 1e-10; no step is cut and none takes more than 8 Newton steps (measured 3-6), the
    elastic predictor starting every step (only turns are extrapolated). A solve that goes on after
    a search inside the Newton iteration keeps the Krylov tolerance where the last one left it
    (:class:`~contactqvi.contact.scd_newton.Forcing`; starting again at ``tol``: 3-8 Newton steps).
    ``plane``: the lower block stands on a frictionless rigid plane searched once instead of on
    rollers (the same closed form), beside the pair searched ``"newton"``: its nodes' rows of the
    Newton matrix were zero (J singular at the first Newton step) until they took identity rows
    of (dv/du~) T (current_geometry.geometric_rows).
    (The intermediate steps have no closed form: the blocks expand differently there.)"""
    comm = MPI.COMM_WORLD
    data = tomllib.loads((DATA / "stacked_30.toml").read_text())
    data["contacts"][0]["search"] = "newton"
    if foundation == "plane":
        del data["bodies"][0]["boundary"]["displacement"]["bottom"]
        data["contacts"].append({"slave": "lower.bottom", "law": "frictionless", "search": "once",
                                 "obstacle": {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]}})
    summary, code = run_case(parse_case(data, DATA), mpi_tmp_path, comm, plot=False)
    assert code == 0, summary["status"]
    newton = [step["iterations"] for step in summary["steps"]]
    cut = [step["step"] for step in summary["steps"] if any("substep" in e for e in step["history"])]
    assert max(newton) <= 8 and not cut, (newton, cut)
    resumed = [entry["tol"] for step in summary["steps"] for entry in step["history"]
               if entry.get("search", 0) > 0 and entry["k"] == 0 and "tol" in entry]
    assert resumed and min(resumed) < HYPERELASTIC_TOL, resumed
    _check_the_end(summary, mpi_tmp_path, "stacked_30.toml")


def test_the_50_percent_compression_with_the_wider_face_as_slave_searched_newton(mpi_tmp_path):
    """stacked_50.toml as shipped (10 steps), searched ``"newton"``: before the end the upper block is
    the wider one, so its face, the slave, reaches past the lower block's edge (by 4-16 mm; facets
    0.14 m wide), and the facets there are covered in part. With the dual basis of the whole facet
    their nodes' weights D_ii fell through zero and the path failed at its ninth step
    (docs/finite_strain.md Sect. 22); with that of the covered part no step is cut and every step takes
    at most 8 Newton steps (the issue's bound), and the last one is the closed form to 1e-8 of the
    travel with no tangential force (1e-10 of the normal). The last step ends where the faces' edges
    coincide, a kink of D and M: it took 7, 14, 10 Newton steps on 1, 2, 3 ranks with the symmetry
    edges' side picked by round-off, 9, 7, 9 with the clipping band (segments.CLIP_BAND), and takes
    7, 8, 8 (steps before it 3-5) with the covered part's basis for every facet short of whole cover
    (before, a facet covered to within 1e-9 of its area took the whole facet's basis: a jump of D and M
    that the tail's iterates crossed)."""
    comm = MPI.COMM_WORLD
    data = tomllib.loads((DATA / "stacked_50.toml").read_text())
    data["contacts"][0]["search"] = "newton"
    summary, code = run_case(parse_case(data, DATA), mpi_tmp_path, comm, plot=False)
    assert code == 0, summary["status"]
    newton = [step["iterations"] for step in summary["steps"]]
    cut = [step["step"] for step in summary["steps"] if any("substep" in e for e in step["history"])]
    assert max(newton) <= 8 and not cut, (newton, cut)
    _check_the_end(summary, mpi_tmp_path, "stacked_50.toml")


def _check_the_end(summary: dict, output: pathlib.Path, name: str) -> None:
    """The last step of the run of case ``name`` written to ``output``: the displacement the closed
    form to 1e-8 of the top's travel, no tangential pair force (1e-10 of the normal) and the normal
    force P33 times the reference area (1 m^2) to 1e-10."""
    comm = MPI.COMM_WORLD
    blocks, travel = _blocks(name)
    stack = stacked_compression(blocks, HEIGHTS, travel)
    error = None
    if comm.rank == 0:
        dataset = read_vtx(output / "body.bp", len(summary["steps"]) - 1)
        body = dataset.cell_data_at_points("body [1]").astype(np.int64)
        exact = stack.displacement(dataset.points, body)
        error = float(np.abs(dataset.point_data["displacement [m]"] - exact).max()) / stack.travel
    error = comm.bcast(error, root=0)
    force = summary["steps"][-1]["pair_forces"]["upper.interface/lower.interface"]
    assert np.hypot(force[0], force[1]) <= 1e-10 * abs(force[2]), force
    assert abs(force[2] + stack.nominal_stress * 1.0) <= 1e-10 * abs(stack.nominal_stress), force
    assert error <= 1e-8, error
