"""A restarted load path is the uninterrupted one (issue 35), after every step.

Each path runs six steps uninterrupted, then once per step k = 1..5 stopped after
step k (``stop_after``: the run ends as if interrupted there, its checkpoint kept)
and continued with ``restart``. The paths cover what a step reads from the step
before (:class:`~contactqvi.contact.path_state.PathState`): a rigid sphere pressed
into a block and dragged along it (the obstacle's position, from which the slip
is measured), with Coulomb friction and with pressure-dependent friction; and a
block slid along another by a moved face (prescribed displacements that move),
its pair searched before every step and until each step's configuration settles.
The Newton steps are solved exactly (``pc = "lu"``) so that nothing but the
path's state can differ. A fifth path twists that block about the vertical through its
top's centre instead (a rotation of the moved face, 1 to 5 degrees): the state also
holds the moved face's rotation. A sixth spins the pressed sphere about a horizontal axis
through its centre (a rotated obstacle, searched every step): the slip is measured from the
displacement of the sphere's material points, which the state's rotation gives.

* On the same number of ranks the restarted run is the uninterrupted one: the
  same Newton and Krylov counts, step forces and final solution to 1e-12.
* Written on 2 ranks and continued on 1 (the 2-rank run), or written on 1 and
  continued on 3 (the 3-rank run): step forces and final solution to 1e-9.

Before the path state held the obstacles' position, a restart moved the sphere
by its whole travel in its first step: the dragged sphere's tangential force
was 5 % off in that step (issue 35).
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import shutil
import tempfile

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.case import ContactCase, Rotation, Step, load_case
from contactqvi.laws import create_law
from contactqvi.runner import EXIT_CODES, run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
STEPS = 6

#: A half model of the Cattaneo-Mindlin block, coarser than the shipped meshes (1 343 dofs).
SPHERE_MESH = f"""DefineConstant[ refinement = 3, extent = 20, symmetry_planes = 1 ];
Include "{ROOT / 'meshes' / 'sphere_indentation.geo'}";
"""
#: The paths: shipped case, the law or search that replaces its own.
PATHS = {
    "sphere_coulomb": ("cattaneo_mindlin.toml", {}),
    "sphere_pressure_coulomb": ("cattaneo_mindlin.toml", {"law": "pressure_coulomb", "friction": 0.3,
                                                          "friction_limit": 0.15, "pressure_scale": 1e9}),
    "blocks_every_step": ("sliding_blocks.toml", {"search": "every_step"}),
    "blocks_until_settled": ("sliding_blocks.toml", {}),
    "blocks_twisted": ("sliding_blocks.toml", {}),
    "sphere_spun": ("cattaneo_mindlin.toml", {"search": "every_step"}),
}
#: The twisted path's steps: pressed 1 mm, then turned about the vertical through the top's centre.
TWISTED = (Step(translation=(0.0, 0.0, -1e-3)),
           *(Step(translation=(0.0, 0.0, -1e-3), rotation=Rotation((0.0, 0.0, 1.0), float(k), (0.5, 0.5, 1.0)))
             for k in range(1, STEPS)))
#: The spun path's steps: the sphere pressed 1 mm, then turned about the y axis through its centre
#: (a rotated obstacle), its surface moving along -x by 0.03 mm per step: the slip reference is the
#: material point's displacement, the geometry the sphere's own; searched every step.
SPUN = (Step(translation=(0.0, 0.0, -1e-3)),
        *(Step(translation=(0.0, 0.0, -1e-3), rotation=Rotation((0.0, 1.0, 0.0), float(np.degrees(3e-5 * k)),
                                                                (0.0, 0.0, 1.0))) for k in range(1, STEPS)))
if MPI.COMM_WORLD.size > 1:  # another law changes only the nodal arithmetic, which the serial run checks;
    del PATHS["sphere_pressure_coulomb"]  # the rotation is JSON in the checkpoint (checked once on 2 ranks: 2 -> 1
    del PATHS["blocks_twisted"]  # and 2 -> 2 agree to 1e-9 and 1e-12), its geometry that of blocks_until_settled
if MPI.COMM_WORLD.size == 3:  # 1 -> 3 ranks (make test's 3-rank run): the searched pairs, whose geometry is parallel
    del PATHS["sphere_coulomb"]


@pytest.fixture(scope="module")
def work() -> pathlib.Path:
    """A directory shared by the ranks, for the whole module."""
    comm = MPI.COMM_WORLD
    path = pathlib.Path(comm.bcast(tempfile.mkdtemp(prefix="contactqvi-paths-") if comm.rank == 0 else None))
    if comm.rank == 0:
        (path / "sphere.geo").write_text(SPHERE_MESH)
    comm.Barrier()
    return path


def _case(name: str, work: pathlib.Path) -> ContactCase:
    """Path ``name`` of :data:`PATHS`: six steps, exact Newton steps."""
    file, law = PATHS[name]
    case = load_case(ROOT / "cases" / file)
    if case.contacts:
        case = dataclasses.replace(case, contacts=tuple(_with(pair, law) for pair in case.contacts))
    else:
        case = dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=work / "sphere.geo"),
                                   contact=_with(case.contact, law))
    steps = {"blocks_twisted": TWISTED, "sphere_spun": SPUN}.get(name, case.steps[:STEPS])
    return dataclasses.replace(case, steps=steps, solver={**case.solver, "pc": "lu"})


def _with(entry, replaced: dict):
    """A ``[contact]`` or ``[[contacts]]`` entry with its law or search replaced."""
    fields = {"search": replaced["search"]} if "search" in replaced else {}
    law = {key: value for key, value in replaced.items() if key != "search"}
    if law:
        fields["law"] = create_law(law, "contact")
    return dataclasses.replace(entry, **fields)


def _solve(case: ContactCase, out: pathlib.Path, comm: MPI.Comm, **options) -> dict:
    summary, code = run_case(case, out, comm, plot=False, **options)
    expected = EXIT_CODES["interrupted" if options.get("stop_after") else "converged"]
    assert code == expected, summary["status"]
    return summary


def _steps(summary: dict) -> list[tuple]:
    return [(s["iterations"], s["inner_iterations"]) for s in summary["steps"]]


def _forces(summary: dict) -> np.ndarray:
    return np.array([[f for force in s["pair_forces"].values() for f in force] for s in summary["steps"]])


def _differences(a: tuple[dict, pathlib.Path], b: tuple[dict, pathlib.Path]) -> tuple[float, float]:
    """Largest relative differences of the step forces and of the final solutions of two runs."""
    (sa, out_a), (sb, out_b) = a, b
    fa, fb = _forces(sa), _forces(sb)
    ua, ub = (np.load(out / "solution.npz")["u"] for out in (out_a, out_b))
    return float(np.abs(fa - fb).max() / np.abs(fa).max()), float(np.abs(ua - ub).max() / np.abs(ua).max())


def _restarts(case: ContactCase, base: pathlib.Path, writer: MPI.Comm | None, reader: MPI.Comm | None):
    """For k = 1..STEPS-1: the output directory of a run stopped after step k on ``writer``
    and the summary of its continuation on ``reader`` (None on ranks outside ``reader``).
    The run stopped after step k is the one stopped after step k - 1, continued (a copy
    of it is continued to the end)."""
    world, chain = MPI.COMM_WORLD, base / "chain"
    for k in range(1, STEPS):
        if writer is not None:
            assert len(_solve(case, chain, writer, stop_after=k, restart=k > 1)["steps"]) == k
        out = base / f"after_{k}"
        if world.rank == 0:
            shutil.copytree(chain, out)
        world.Barrier()
        yield k, out, None if reader is None else _solve(case, out, reader, restart=True)
        world.Barrier()


@pytest.mark.parametrize("name", PATHS)
def test_a_path_restarted_after_any_step_is_the_uninterrupted_path(name, work):
    comm = MPI.COMM_WORLD
    case, base = _case(name, work), work / f"{name}_{comm.size}"
    whole = _solve(case, base / "whole", comm)
    assert len(whole["steps"]) == STEPS
    for k, out, restarted in _restarts(case, base, comm, comm):
        assert restarted["restarts"][-1] == {"after_step": k, "mpi_size": comm.size}
        assert _steps(restarted) == _steps(whole), k
        if comm.rank == 0:
            forces, solution = _differences((whole, base / "whole"), (restarted, out))
            assert forces <= 1e-12 and solution <= 1e-12, (k, forces, solution)


@pytest.mark.skipif(MPI.COMM_WORLD.size not in (2, 3), reason="written on 2 ranks, continued on 1; or 1 -> 3")
@pytest.mark.parametrize("name", PATHS)
def test_a_path_restarted_on_another_number_of_ranks(name, work):
    """2 -> 1 in the 2-rank run (rank 0 continues alone), 1 -> 3 in the 3-rank run."""
    world = MPI.COMM_WORLD
    alone = world.Split(world.rank, 0)  # each rank on its own
    first = alone if world.rank == 0 else None
    writer, reader = (world, first) if world.size == 2 else (first, world)
    case, base = _case(name, work), work / f"{name}_{world.size}_ranks"
    whole = _solve(case, base / "whole", writer) if writer is not None else None  # rank 0 compares
    for k, out, restarted in _restarts(case, base, writer, reader):
        if world.rank == 0:
            forces, solution = _differences((whole, base / "whole"), (restarted, out))
            assert forces <= 1e-9 and solution <= 1e-9, (k, forces, solution)
    alone.Free()


def test_the_checkpoint_holds_the_obstacles_position(work):
    """checkpoint.json names the last step's load factor and translation: what the next
    step measures the obstacle's motion from."""
    comm = MPI.COMM_WORLD
    case, out = _case("sphere_coulomb", work), work / f"marker_{comm.size}"
    _solve(case, out, comm, stop_after=3)
    marker = json.loads((out / "checkpoint" / "checkpoint.json").read_text())
    assert (marker["step"], marker["load"], marker["translation"]) == (3, 1.0, list(case.steps[2].translation))
