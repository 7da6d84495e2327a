"""The shipped cases as ``make test`` runs them, each once per test session.

Every case file of ``cases/`` runs through :func:`contactqvi.case.load_case` and
:func:`contactqvi.runner.run_case` (a case with ``[dynamics]``:
:func:`contactqvi.dynamic_runner.run_dynamics`) as shipped, or as its variant where it names a larger
mesh or a long path (:data:`COARSE`). The runs are shared by the tests of several modules
(the fixture ``shipped_runs`` of conftest.py): tests/test_shipped_cases.py checks every
case, others read one case's output files. Tests of one case share an xdist group
(:func:`of_case`), so that each case runs on one pytest-xdist worker of the serial run
and the workers share out the cases.
"""

from __future__ import annotations

import dataclasses
import pathlib
import typing

from mpi4py import MPI

import pytest

from contactqvi.case import ContactCase, PaperBody, load_case
from contactqvi.dynamic_runner import run_dynamics
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent


@dataclasses.dataclass(frozen=True)
class Variant:
    """What ``make test`` runs instead of a large case: another mesh file or paper level,
    and optionally a part of a long load path (``steps``: its first steps, or every other one)."""

    mesh: str | PaperBody | None = None
    steps: slice | None = None

    def of(self, case: ContactCase) -> ContactCase:
        if isinstance(self.mesh, PaperBody):
            case = dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, box=self.mesh))
        elif self.mesh is not None:
            case = dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / self.mesh))
        return case if self.steps is None else dataclasses.replace(case, steps=case.steps[self.steps])


#: The variant of each case whose file names a larger mesh (the coarsest mesh it lists).
#: Two bodies on the coarse Mindlin meshes take 45 s for three steps under load: the
#: indentation and two tangential steps of the path run. The Mindlin paths run every other
#: step (the indentation, then 0.06 ... 0.42 mm): the tangential load only grows, so the
#: larger steps reach the same states (Mindlin's curve within 0.05 mu P either way).
COARSE = {
    "hertz": Variant("hertz_coarse.geo"),
    "hertz_bodies": Variant("hertz_bodies_coarse.geo"),
    "cattaneo_mindlin": Variant("mindlin_coarse.geo", steps=slice(None, None, 2)),
    "cattaneo_mindlin_nu045": Variant("mindlin_coarse.geo", steps=slice(None, None, 2)),
    "cattaneo_mindlin_bodies": Variant("mindlin_bodies_coarse.geo", steps=slice(3)),
    "paper_d3_L2": Variant(PaperBody(lev=3, geometry="d3")),
    "rubber_pad": Variant("rubber_pad_coarse.geo"),
    # the ironing paths take 36 min each (docs/ironing.md): their first press step here
    "shallow_ironing": Variant(steps=slice(1)),
    "shallow_ironing_frictional": Variant(steps=slice(1)),
}


def shipped_case(name: str) -> ContactCase:
    """``cases/NAME.toml`` as make test runs it (its :data:`COARSE` variant, if any)."""
    return COARSE.get(name, Variant()).of(load_case(ROOT / "cases" / f"{name}.toml"))


class ShippedRuns(dict):
    """Run of each case by name, made on first access (collective): its ``summary``, exit
    ``code`` and ``output`` directory, or the ``error`` it raised (so that only that case's
    tests fail)."""

    def __init__(self, base: pathlib.Path, comm: MPI.Comm):
        super().__init__()
        self.base, self.comm = base, comm

    def __missing__(self, name: str) -> dict[str, typing.Any]:
        output = self.base / name
        try:
            case = shipped_case(name)
            run = run_case if case.dynamics is None else run_dynamics
            summary, code = run(case, output, self.comm, plot=case.dynamics is not None)
            self[name] = {"summary": summary, "code": code, "output": output}
        except Exception as exc:  # reported by that case's tests; the others still run
            self[name] = {"error": f"{type(exc).__name__}: {exc}"}
        self.comm.Barrier()
        return self[name]

    def steps(self, name: str) -> list[dict]:
        """The step summaries of case ``name``, which must have run without error (exit code 0)."""
        run = self[name]
        if "error" in run:
            pytest.fail(f"{name} raised {run['error']}")
        assert run["code"] == 0, [step["status"] for step in run["summary"]["steps"]]
        return run["summary"]["steps"]


#: Cases that run on one rank only, and the case whose parallel code each repeats
#: (``parallel_twin``, tests/conftest.py): twin and reason.
TWINS = {
    "cattaneo_mindlin_nu045": ("cattaneo_mindlin", "cattaneo_mindlin's mesh, sphere and path; another Poisson ratio"),
    "cattaneo_mindlin_bodies": ("sliding_blocks", "two bodies, a frictional mortar pair, searched every step; on "
                                "2 ranks also in tests/test_restart.py, killed and restarted"),
    "shallow_ironing_frictional": ("shallow_ironing", "shallow_ironing's mesh and press step; Coulomb's nodal law, "
                                   "at finite strain on 2 ranks in rubber_pad"),
    "twisted_fit": ("shrink_fit", "shrink_fit's pair and interference on a full model; tests/test_rotation.py "
                    "twists the same case on 2 ranks"),
}


def of_case(*names: str) -> list:
    """Parameters ``names``, each test of a case in the case's xdist group (:func:`group`),
    those of :data:`TWINS` marked ``parallel_twin``."""
    return [pytest.param(name, marks=[group(name), *_twin(name)]) for name in names]


def _twin(name: str) -> list[pytest.MarkDecorator]:
    if name not in TWINS:
        return []
    twin, reason = TWINS[name]
    return [pytest.mark.parallel_twin(twin, reason=reason)]


def group(name: str) -> pytest.MarkDecorator:
    """The xdist group of the tests that read the run of case ``name``."""
    return pytest.mark.xdist_group(f"shipped_{name}")
