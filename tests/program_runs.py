"""``python -m contactqvi run`` in a subprocess, serially or under ``mpirun``, as a user runs it;
a run on rank 0 alone beside a parallel one (:func:`on_rank_0`)."""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time
import typing

from mpi4py import MPI

__all__ = ["MPIENV", "RankZeroFailed", "on_rank_0", "run_program", "run_ranks"]

#: OpenMPI 5 as root, more ranks than cores, no TCP pairing warning.
MPIENV = {"OMPI_MCA_rmaps_base_oversubscribe": "1", "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",
          "OMPI_MCA_btl": "self,sm", "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}


def run_program(case: pathlib.Path, output: pathlib.Path, ranks: int = 1,
                timeout: float = 180.0) -> subprocess.CompletedProcess:
    """Run ``case`` with ``--output output --no-plot`` on ``ranks`` ranks (mpirun beyond one), in a
    session directory of its own (one left by a killed run made mpirun fail)."""
    command = [sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(output), "--no-plot"]
    return run_ranks(command, ranks, timeout)


def run_ranks(command: list[str], ranks: int = 1, timeout: float = 180.0,
              env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """Run ``command`` on ``ranks`` ranks (mpirun beyond one), with ``env`` added to the environment,
    in a session directory of its own (one left by a killed run made mpirun fail)."""
    session = tempfile.mkdtemp(prefix="prte-")
    try:
        return subprocess.run(["mpirun", "-n", str(ranks), *command] if ranks > 1 else command,
                              capture_output=True, text=True, timeout=timeout,
                              env=os.environ | MPIENV | (env or {}) | {"TMPDIR": session})
    finally:
        shutil.rmtree(session, ignore_errors=True)


def on_rank_0(comm: MPI.Comm, work: typing.Callable[[], None]) -> None:
    """Run ``work`` on rank 0 alone; the other ranks wait without spinning (oversubscribed cores).

    An exception of ``work`` (a failed assertion) is raised on rank 0 and, as a
    :class:`RankZeroFailed` naming it, on every other rank: else pytest would record the failure
    on rank 0 and go on to the next test while the other ranks waited here for ever."""
    failure = None
    if comm.rank == 0:
        try:
            work()
        except Exception as exc:  # raised again below, once every rank knows
            failure = exc
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(0.01)
    text = comm.bcast(None if failure is None else f"{type(failure).__name__}: {failure}", root=0)
    if failure is not None:
        raise failure
    if text is not None:
        raise RankZeroFailed(f"on rank 0: {text}")


class RankZeroFailed(AssertionError):
    """What the other ranks raise when the work of :func:`on_rank_0` failed on rank 0."""
