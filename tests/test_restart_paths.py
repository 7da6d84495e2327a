"""A restarted load path is the uninterrupted one (issue 35), after every step.

Each path runs six steps uninterrupted, and again as a chain of runs each stopped after
one more step (``stop_after``: the run ends as if interrupted there, its checkpoint kept)
and continued with ``restart``: every step k + 1 of the chain starts from the checkpoint
of step k. State that a step reads from any earlier step and that the checkpoint lacks
is then missing in the chain at the first step that reads it. The paths cover what a
step reads from the steps before (:class:`~contactqvi.contact.path_state.PathState`): a
rigid sphere pressed into a block and dragged along it (the obstacle's position, from
which the slip is measured), with Coulomb friction and with pressure-dependent friction;
and a block slid along another by a moved face (prescribed displacements that move),
its pair searched before every step and until each step's configuration settles. The
Newton steps are solved exactly (``pc = "lu"``) so that nothing but the path's state can
differ. A fifth path twists that block about the vertical through its top's centre
instead (a rotation of the moved face, 1 to 5 degrees): the state also holds the moved
face's rotation. A sixth spins the pressed sphere about a horizontal axis through its
centre (a rotated obstacle, searched every step): the slip is measured from the
displacement of the sphere's material points, which the state's rotation gives. A seventh
squeezes the O-ring of ``benchmarks/data/oring`` at nu = 0.4999 with the nodal pressure: the
mixed Newton method starts each step's nodal volume ratios from the last step's displacement.

* On the same number of ranks the chain is the uninterrupted run: the same Newton and
  Krylov counts in every step, every step's forces and the final solution to 1e-12.
* Written on 2 ranks and continued on 1 (the 2-rank run), or written on 1 and continued
  on 3 (the 3-rank run): from the checkpoint of every step k, step k + 1 on the other
  number of ranks gives the writer's forces and solution of step k + 1 to 1e-9.

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
import typing

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
CASES = {
    "sphere_coulomb": ("cattaneo_mindlin.toml", {}),
    "sphere_pressure_coulomb": ("cattaneo_mindlin.toml", {"law": "pressure_coulomb", "friction": 0.3,
                                                          "friction_limit": 0.15, "pressure_scale": 1e9}),
    "blocks_every_step": ("sliding_blocks.toml", {"search": "every_step"}),
    "blocks_until_settled": ("sliding_blocks.toml", {}),
    "blocks_twisted": ("sliding_blocks.toml", {}),
    "sphere_spun": ("cattaneo_mindlin.toml", {"search": "every_step"}),
    "oring_mixed": ("../benchmarks/data/oring/oring.toml", {}),
}
#: The paths the restart tests run on this number of ranks.
PATHS = dict(CASES)
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
    del PATHS["blocks_twisted"]  # and 2 -> 2 agree to 1e-9 and 1e-12), its geometry that of blocks_until_settled;
    del PATHS["sphere_spun"]  # the obstacle's motion is nodal arithmetic (2 -> 2: 3e-13, 2 -> 1 within 1e-9)
    del PATHS["oring_mixed"]  # the volume ratios' start is the state's displacement, which the others check
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
    """Path ``name`` of :data:`CASES`: six steps, exact Newton steps."""
    file, law = CASES[name]
    case = load_case(ROOT / "cases" / file)
    if name == "oring_mixed":
        case = dataclasses.replace(case, material=dataclasses.replace(case.material, poisson=0.4999,
                                                                      formulation="nodal_pressure"))
    elif case.contacts:
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
    stopped = options.get("stop_after", STEPS) < STEPS
    assert code == EXIT_CODES["interrupted" if stopped else "converged"], summary["status"]
    return summary


def _steps(summary: dict) -> list[tuple]:
    return [(s["iterations"], s["inner_iterations"]) for s in summary["steps"]]


def _forces(summary: dict) -> np.ndarray:
    return np.array([[f for force in s["pair_forces"].values() for f in force] for s in summary["steps"]])


def _difference(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(a).max())


def _solution(out: pathlib.Path) -> np.ndarray:
    return np.load(out / "solution.npz")["u"]


def _chain(case: ContactCase, out: pathlib.Path, comm: MPI.Comm) -> typing.Iterator[tuple[int, dict]]:
    """Steps k = 1..STEPS run one at a time in ``out``, each stopped after step k and the
    next continued from its checkpoint: k and the summary after step k."""
    for k in range(1, STEPS + 1):
        summary = _solve(case, out, comm, stop_after=k, restart=k > 1)
        assert len(summary["steps"]) == k
        yield k, summary


#: The paths written on 2 ranks and continued on 1 in the 2-rank run, whose chain there is also
#: the same-rank restart after every step (one chain for both checks).
WRITTEN_ON_TWO = ("sphere_coulomb", "blocks_every_step", "blocks_until_settled")


def _same_ranks(name: str):
    """Parameter ``name`` of the same-rank test; on 2 ranks its twin is the 2 -> 1 test's."""
    if name not in WRITTEN_ON_TWO:
        return name
    twin = pytest.mark.parallel_twin(f"test_a_path_restarted_on_another_number_of_ranks[{name}]",
                                     reason="on 2 ranks the writer's chain is this test's chain, checked there")
    return pytest.param(name, marks=twin)


def _assert_chain_is_whole(whole: tuple[dict, pathlib.Path], chained: tuple[dict, pathlib.Path],
                           comm: MPI.Comm) -> None:
    """The chain restarted after every step is the uninterrupted run on the same ranks: restarts
    recorded, Newton and Krylov counts, every step's forces and the final solution to 1e-12."""
    (summary, out), (chain, chain_out) = whole, chained
    assert chain["restarts"] == [{"after_step": k, "mpi_size": comm.size} for k in range(1, STEPS)]
    assert len(summary["steps"]) == STEPS and _steps(chain) == _steps(summary)
    if comm.rank == 0:
        forces = np.abs(_forces(summary) - _forces(chain)).max(axis=1) / np.abs(_forces(summary)).max()
        assert forces.max() <= 1e-12, forces  # every step's
        solution = _difference(_solution(out), _solution(chain_out))
        assert solution <= 1e-12, solution


@pytest.mark.parametrize("name", [_same_ranks(name) for name in PATHS])
def test_a_path_restarted_after_every_step_is_the_uninterrupted_path(name, work):
    comm = MPI.COMM_WORLD
    case, base = _case(name, work), work / f"{name}_{comm.size}"
    whole = _solve(case, base / "whole", comm)
    *_, (_, chained) = _chain(case, base / "chain", comm)
    _assert_chain_is_whole((whole, base / "whole"), (chained, base / "chain"), comm)


@pytest.mark.ranks(2, 3)  # written on 2 ranks, continued on 1; or 1 -> 3
@pytest.mark.parametrize("name", PATHS)
def test_a_path_restarted_on_another_number_of_ranks(name, work):
    """2 -> 1 in the 2-rank run (rank 0 continues alone), 1 -> 3 in the 3-rank run: the
    writer's chain keeps its output after every step k, and step k + 1 continued from it
    on the reader's ranks is compared with the chain's step k + 1. On 2 ranks the chain is
    also compared with the uninterrupted run (the same-rank test's check)."""
    world = MPI.COMM_WORLD
    alone = world.Split(world.rank, 0)  # each rank on its own
    first = alone if world.rank == 0 else None
    writer, reader = (world, first) if world.size == 2 else (first, world)
    base = work / f"{name}_{world.size}_ranks"
    case, written = _case(name, work), base / "chain"
    whole = _solve(case, base / "whole", world) if world.size == 2 else None
    chain = _chain(case, written, writer) if writer is not None else ((k, None) for k in range(1, STEPS + 1))
    for k, summary in chain:
        if k > 1 and reader is not None:
            continued = _solve(case, base / f"after_{k - 1}", reader, stop_after=k, restart=True)
            assert continued["restarts"][-1] == {"after_step": k - 1, "mpi_size": reader.size}
        if world.rank == 0 and k > 1:
            forces = _difference(_forces(summary)[-1], _forces(continued)[-1])
            solution = _difference(_solution(written), _solution(base / f"after_{k - 1}"))
            assert forces <= 1e-9 and solution <= 1e-9, (k, forces, solution)
        if world.rank == 0 and k < STEPS:
            shutil.copytree(written, base / f"after_{k}")
        world.Barrier()
    if whole is not None:
        _assert_chain_is_whole((whole, base / "whole"), (summary, written), world)
    alone.Free()


def test_the_checkpoint_holds_the_obstacles_position(work):
    """checkpoint.json names the last step's load factor and translation: what the next
    step measures the obstacle's motion from."""
    comm = MPI.COMM_WORLD
    case, out = _case("sphere_coulomb", work), work / f"marker_{comm.size}"
    _solve(case, out, comm, stop_after=3)
    marker = json.loads((out / "checkpoint" / "checkpoint.json").read_text())
    assert (marker["step"], marker["load"], marker["translation"]) == (3, 1.0, list(case.steps[2].translation))
