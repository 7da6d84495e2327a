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

__all__ = ["MPIENV", "on_rank_0", "run_program"]

#: OpenMPI 5 as root, more ranks than cores, no TCP pairing warning.
MPIENV = {"OMPI_MCA_rmaps_base_oversubscribe": "1", "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",
          "OMPI_MCA_btl": "self,sm", "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}


def run_program(case: pathlib.Path, output: pathlib.Path, ranks: int = 1,
                timeout: float = 180.0) -> subprocess.CompletedProcess:
    """Run ``case`` with ``--output output --no-plot`` on ``ranks`` ranks (mpirun beyond one), in a
    session directory of its own (one left by a killed run made mpirun fail)."""
    command = [sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(output), "--no-plot"]
    session = tempfile.mkdtemp(prefix="prte-")
    try:
        return subprocess.run(["mpirun", "-n", str(ranks), *command] if ranks > 1 else command,
                              capture_output=True, text=True, timeout=timeout,
                              env=os.environ | MPIENV | {"TMPDIR": session})
    finally:
        shutil.rmtree(session, ignore_errors=True)


def on_rank_0(comm: MPI.Comm, work: typing.Callable[[], None]) -> None:
    """Run ``work`` on rank 0 alone; the other ranks wait without spinning (oversubscribed cores)."""
    if comm.rank == 0:
        work()
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(0.01)
