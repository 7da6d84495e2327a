"""Command-line plumbing shared by the demos and ``python -m contactqvi``.

Every demo accepts ``--help``, ``--output DIR`` and ``--log-level``; any unknown
option starting with ``-`` (e.g. ``-coulomb_ksp_type gmres``) goes to PETSc.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
import traceback
import typing

from mpi4py import MPI
from petsc4py import PETSc

from contactqvi.lifetime import abort_alone

__all__ = ["abort_on_error", "make_parser", "parse_args", "pass_to_petsc", "print_error", "setup_logging"]


class _Parser(argparse.ArgumentParser):
    """argparse's parser whose errors (an unknown option, a value outside the choices) print
    on rank 0 only, as :func:`print_error` does; every rank exits with argparse's code 2."""

    def error(self, message: str) -> typing.NoReturn:
        if MPI.COMM_WORLD.rank == 0:
            self.print_usage(sys.stderr)
        self.exit(2, f"{self.prog}: error: {message}\n" if MPI.COMM_WORLD.rank == 0 else None)


def make_parser(description: str, default_output: str, petsc_example: str | None = None) -> argparse.ArgumentParser:
    """Argument parser with the options every demo has.

    ``petsc_example`` is a PETSc option under the program's own prefix, shown in
    ``--help`` (e.g. ``-coulomb_ksp_monitor``).
    """
    example = f" (e.g. {petsc_example}; -log_view prints PETSc's profile at exit)" if petsc_example else ""
    parser = _Parser(
        description=description,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        epilog=f"Unknown options starting with '-' are passed to PETSc{example}.",
        allow_abbrev=False,
    )
    parser.add_argument("--output", default=default_output, help="directory for results")
    parser.add_argument(
        "--log-level", default="INFO", type=str.upper, choices=["DEBUG", "INFO", "WARNING", "ERROR"],
        help="progress output (any case)"
    )
    return parser


def parse_args(parser: argparse.ArgumentParser, argv: list[str] | None = None) -> argparse.Namespace:
    """Parse ``argv``; hand unknown ``-options`` to the PETSc options database."""
    args, unknown = parser.parse_known_args(sys.argv[1:] if argv is None else argv)
    if unknown and not unknown[0].startswith("-"):
        parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    if unknown:
        pass_to_petsc(unknown)
    setup_logging(args.log_level)
    return args


def pass_to_petsc(options: list[str]) -> None:
    """Insert command-line ``options`` into the PETSc options database.

    PETSc reads a few options only in ``PetscInitialize`` (which ran when petsc4py
    was imported); of those, ``-log_view`` and its variants need the default log
    handler started, which is done here, so the profile prints at exit.
    """
    opts = PETSc.Options()
    opts.insertString(" ".join(options))
    if any(opts.hasName(name) for name in ("log_view", "log_summary", "log_all")):
        PETSc.Log.begin()


def setup_logging(level: str = "INFO") -> None:
    """Log progress on rank 0 only; other ranks log warnings and errors."""
    rank = MPI.COMM_WORLD.rank
    logging.basicConfig(
        level=getattr(logging, level) if rank == 0 else logging.WARNING,
        format="%(message)s" if rank == 0 else f"[rank {rank}] %(levelname)s %(message)s",
        stream=sys.stdout,
        force=True,
    )


def print_error(error: Exception | str, comm: MPI.Comm | None = None) -> None:
    """``error: <error>`` on standard error, once for the job: on rank 0 only.

    For errors raised on every rank alike (bad input, failed output), after which every
    rank returns its exit code; under ``mpirun -n N`` the line would otherwise print N times.
    """
    if (MPI.COMM_WORLD if comm is None else comm).rank == 0:
        print(f"error: {error}", file=sys.stderr)


def abort_on_error(function: typing.Callable[[], int], comm: MPI.Comm | None = None) -> int:
    """``function()``; an exception it raises on one rank of several ends the whole job.

    Errors of bad input are raised on every rank and become exit codes (the case
    runner and the demos check their input first); anything else may be raised on one
    rank only while the others wait in a collective call, which would hold a cluster
    allocation until its time limit. So under ``mpirun`` the traceback is printed and
    ``MPI_Abort`` ends every rank (exit code 1); on one rank the exception propagates
    as usual. An exception raised on one rank alone ends the job already at the first collective
    clean-up it meets (a ``with`` block's ``destroy()``, the runner's output files), which would
    otherwise wait for the other ranks for ever (:func:`contactqvi.lifetime.abort_alone`).
    """
    comm = MPI.COMM_WORLD if comm is None else comm
    try:
        with abort_alone(comm) if comm.size > 1 else contextlib.nullcontext():
            return function()
    except Exception:
        if comm.size == 1:
            raise
        traceback.print_exc()
        sys.stderr.flush()
        comm.Abort(1)
        raise
