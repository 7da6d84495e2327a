"""Contact between hyperelastic bodies (issue 36): the SCD semismooth* Newton method on
f(u) = T^T r_K(u~), the mortar coupling searched in the deformed configuration.

The finite-strain contact patch test: the two stacked unit blocks of the linear patch
test (``meshes/patch_blocks.geo``, non-matching tetrahedral meshes), one neo-Hookean
material, rollers on the symmetry planes and under the lower block, the top of the upper
block moved down by 30 % of the height (0.6 m) in load steps, the outer lateral faces
free. The deformation is homogeneous uniaxial stress with F = diag(a, a, s) in both
blocks (docs/finite_strain.md, Sect. 6): u = ((a - 1) x, (a - 1) y, (s - 1) z), which P1
tetrahedra represent exactly, and the contact traction is uniform: -P33 per unit
reference area, the Cauchy stress -P33 / a^2 per unit deformed area.

* searched once (the reference configuration): a homogeneous deformation maps the
  projection along the normal onto itself, so the reference mortar coupling is the exact
  one; the pressure is nominal (force per reference area D_ii);
* ``search = "until_settled"``: D, M and the normals on the deformed surfaces, searched
  again until the configuration settles; the pressure is the Cauchy traction (force per
  deformed area).
"""

from __future__ import annotations

import pathlib

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import parse_case
from contactqvi.contact import LoadStep, solve_load_path
from contactqvi.contact.interface import BodyPair
from contactqvi.contact.problem import assemble_contact_problem
from contactqvi.elasticity import body_materials
from contactqvi.laws import Coulomb, Frictionless
from contactqvi.materials import NeoHookean
from contactqvi.meshes import read_gmsh, split_by_body
from contactqvi.parameters import ParameterError

from test_finite_strain import POISSON, YOUNG, neo_hookean

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESH = ROOT / "meshes" / "patch_blocks.geo"
HEIGHT = 2.0  # m, the two unit blocks
COMPRESSION = 0.3  # of the height
SUPPORTS = {"lower.bottom": {2: 0.0}, "lower.symmetry_x": {0: 0.0}, "lower.symmetry_y": {1: 0.0},
            "upper.symmetry_x": {0: 0.0}, "upper.symmetry_y": {1: 0.0},
            "upper.top": {2: -COMPRESSION * HEIGHT}}


def _compressed_blocks(friction: float, search: str, steps: int) -> list[dict]:
    """The patch blocks compressed in ``steps`` equal load steps; per step the errors of the
    displacement (relative to the top's motion) and of the pressure (relative to the exact
    one: nominal when searched once, Cauchy otherwise), the Newton count and the result."""
    comm = MPI.COMM_WORLD
    msh, facet_tags, cell_tags = read_gmsh(MESH, comm)
    young, poisson = body_materials(msh, cell_tags, {"lower": (YOUNG, POISSON), "upper": (YOUNG, POISSON)})
    law = Coulomb(friction) if friction > 0.0 else Frictionless()
    pair = BodyPair("upper.interface", "lower.interface", law, search=search)
    problem = assemble_contact_problem(msh, split_by_body(msh, facet_tags, cell_tags), young, poisson, {}, [pair],
                                       displacements=SUPPORTS, cell_tags=cell_tags, material=NeoHookean())
    rows = []

    def record(index, step, u, result, state):
        s = 1.0 - COMPRESSION * step.load
        a, P33 = neo_hookean(s)
        x = problem.V.tabulate_dof_coordinates()[: problem.V.dofmap.index_map.size_local]
        error = np.abs(state.displacement.x.array.reshape(-1, 3)[: len(x)] - x * [a - 1.0, a - 1.0, s - 1.0])
        exact = -P33 if search == "once" else -P33 / a**2
        pressure = result.normal_force / problem.contact_area
        rows.append({"load": step.load, "result": result, "contact_nodes": comm.allreduce(len(pressure)),
                     "u": comm.allreduce(float(error.max(initial=0.0)), op=MPI.MAX) / (HEIGHT * (1.0 - s)),
                     "p": comm.allreduce(float(np.abs(pressure - exact).max(initial=0.0)), op=MPI.MAX) / exact})

    with problem:
        u = problem.A.createVecRight()
        solve_load_path(problem, [LoadStep((k + 1) / steps) for k in range(steps)], u, {"pc": "lu"},
                        on_step=record, from_rest=True)
        u.destroy()
    return rows


@pytest.mark.parametrize("friction, search, steps", [
    pytest.param(0.0, "once", 20, marks=pytest.mark.parallel_twin(
        "0.3-until_settled-5", reason="the first search and the hyperelastic assembly, which the twin runs "
        "too; the frictionless nodal law")),
    (0.3, "until_settled", 5)])
def test_finite_strain_contact_patch_test(friction, search, steps):
    """Every step: the homogeneous displacement to 1e-8 and a uniform contact pressure equal
    to the closed form to 1e-8, every slave node in contact (sticking with friction).

    Steps of 6 % of the height invert elements in the first Newton iterate: each is cut once
    (the path searched until settled). Searched once, the path takes 20 steps: from 0.9 to 1
    (10 steps, or 5 with their cuts) Newton finds another equilibrium of the frozen reference
    coupling, its slave nodes at the interface's outer edge slid by 0.1 m (homogeneous
    elsewhere; the 6, 7 and 20-step paths stay on the homogeneous one)."""
    rows = _compressed_blocks(friction, search, steps)
    assert len(rows) == steps
    for row in rows:
        assert row["result"].converged, (row["load"], row["result"].status)
        assert row["u"] <= 1e-8, row
        assert row["p"] <= 1e-8, row
        states = np.bincount(row["result"].states, minlength=4)
        assert states[0] == 0 and states.sum() == len(row["result"].states), states


def test_bodies_of_a_case_file_take_one_model():
    """A hyperelastic model on several bodies is accepted; two different models are a named error."""
    def case(models):
        return {
            "mesh": {"file": str(MESH)},
            "bodies": [{"name": name, "material": {"young": YOUNG, "poisson": POISSON, "model": model},
                        "boundary": {"displacement": {"symmetry_x": {"x": 0.0}}}}
                       for name, model in zip(("lower", "upper"), models)],
            "contacts": [{"slave": "upper.interface", "master": "lower.interface", "law": "frictionless"}],
        }

    assert parse_case(case(["neo_hookean", "neo_hookean"])).bodies[1].material.model == "neo_hookean"
    with pytest.raises(ParameterError, match=r"bodies\[1\]\.material\.model.*same model"):
        parse_case(case(["neo_hookean", "saint_venant_kirchhoff"]))
    with pytest.raises(ParameterError, match=r"bodies\[1\]\.material\.model"):
        parse_case(case(["neo_hookean", None]))


def test_two_body_hertz_at_a_small_load_is_the_linear_solution(mpi_tmp_path):
    """cases/hertz_bodies.toml on its coarse mesh at 1e-3 of its indentation (1 um): both bodies
    neo-Hookean give the linear solution's force P to 1e-3 (strains of 1e-3 at most; measured
    2.2e-5 on 1 and 2 ranks), its largest pressure likewise, both solves converged and in
    balance: the linear one to 1e-8 (measured 3.5e-10 on 1 rank, 1.5e-9 on 2: the forces are
    140 N, the stopping floor is relative to the load of the shifted variables), the
    neo-Hookean one to 1e-4 (measured 6.3e-6 on 1 rank, 8.2e-6 on 2): its residual cannot be
    resolved below eps times stress terms of size mu |F| (``ContactProblem.force_scale``), and
    the solver stops at its ``floor``, 45 eps of that."""
    import tomllib

    from contactqvi.runner import run_case

    data = tomllib.loads((ROOT / "cases" / "hertz_bodies.toml").read_text())
    data["mesh"]["file"] = str(ROOT / "meshes" / "hertz_bodies_coarse.geo")
    data["steps"] = [{"load": 1e-3}]
    results = {}
    for model in (None, "neo_hookean"):
        for body in data["bodies"]:
            body["material"]["model"] = model
        case = parse_case({**data, "bodies": [{**b, "material": {k: v for k, v in b["material"].items()
                                                                 if v is not None}} for b in data["bodies"]]},
                          ROOT / "cases")
        summary, code = run_case(case, mpi_tmp_path / str(model), plot=False)
        assert code == 0, summary["status"]
        results[model] = summary["steps"][-1]
        assert max(results[model]["body_equilibrium_errors"].values()) <= (1e-8 if model is None else 1e-4)
    linear, neo = results[None], results["neo_hookean"]
    assert abs(neo["contact_force"][2] / linear["contact_force"][2] - 1.0) <= 1e-3
    assert abs(neo["max_contact_pressure"] / linear["max_contact_pressure"] - 1.0) <= 1e-3
    # the pressure named for what it is (issue 46): per deformed area where the pair is searched on the
    # deformed surfaces at finite strain; its area there differs from the reference one by the strains
    assert (linear["contact_pressure_measure"], neo["contact_pressure_measure"]) == ("nominal", "cauchy")
    assert "deformed_contact_area" not in linear
    assert abs(neo["deformed_contact_area"] / neo["contact_area"] - 1.0) <= 1e-2
