"""Command-line plumbing shared by the demos.

Every demo accepts ``--help``, ``--output DIR`` and ``--log-level``; any unknown
option starting with ``-`` (e.g. ``-coulomb_ksp_type gmres``) goes to PETSc.
"""

from __future__ import annotations

import argparse
import logging
import sys

from mpi4py import MPI
from petsc4py import PETSc

__all__ = ["make_parser", "parse_args", "setup_logging"]


def make_parser(description: str, default_output: str) -> argparse.ArgumentParser:
    """Argument parser with the options every demo has."""
    parser = argparse.ArgumentParser(
        description=description,
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        epilog="Unknown options starting with '-' are passed to PETSc (e.g. -coulomb_ksp_monitor).",
        allow_abbrev=False,
    )
    parser.add_argument("--output", default=default_output, help="directory for results")
    parser.add_argument(
        "--log-level", default="INFO", choices=["DEBUG", "INFO", "WARNING", "ERROR"], help="progress output"
    )
    return parser


def parse_args(parser: argparse.ArgumentParser, argv: list[str] | None = None) -> argparse.Namespace:
    """Parse ``argv``; hand unknown ``-options`` to the PETSc options database."""
    args, unknown = parser.parse_known_args(sys.argv[1:] if argv is None else argv)
    if unknown and not unknown[0].startswith("-"):
        parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    if unknown:
        PETSc.Options().insertString(" ".join(unknown))
    setup_logging(args.log_level)
    return args


def setup_logging(level: str = "INFO") -> None:
    """Log progress on rank 0 only; other ranks log warnings and errors."""
    rank = MPI.COMM_WORLD.rank
    logging.basicConfig(
        level=getattr(logging, level) if rank == 0 else logging.WARNING,
        format="%(message)s" if rank == 0 else f"[rank {rank}] %(levelname)s %(message)s",
        stream=sys.stdout,
        force=True,
    )
