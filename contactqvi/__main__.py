"""``python -m contactqvi``: run a contact case file or one of the demos.

    python -m contactqvi run CASE.toml --output DIR     your own contact problem (see contactqvi.case);
                                                        --restart continues a killed run
    python -m contactqvi <demo> [options]               a paper's demo (coulomb3d, simplified_friction, thermoforming)

Both work under ``mpirun -n N``. The demos are the scripts of the source tree's
``demos/``; an installed package carries them in ``<prefix>/share/contactqvi/demos``.
Unknown options starting with ``-`` go to PETSc.
"""

from __future__ import annotations

import pathlib
import runpy
import sys

__all__ = ["DEMOS", "entry", "main"]

#: Demos by name, with what they solve.
DEMOS = {
    "coulomb3d": "3D contact with Coulomb friction, SCD semismooth* Newton (seed 000)",
    "simplified_friction": "Stadler's simplified (scalar Tresca) friction: PDAS, SS, ALM, Uzawa (seed 002)",
    "thermoforming": "obstacle problems and the thermoforming QVI, semismooth Newton (seed 003)",
}


def demo_directory() -> pathlib.Path | None:
    """``demos/`` of the source tree, else the installed copy, else None."""
    for path in (pathlib.Path(__file__).resolve().parent.parent / "demos",
                 pathlib.Path(sys.prefix) / "share" / "contactqvi" / "demos"):
        if path.is_dir():
            return path
    return None


def run(argv: list[str]) -> int:
    """``run CASE.toml --output DIR [--restart] [--stop-after K] [--no-plot] [--log-level L] [-petsc_options]``."""
    from mpi4py import MPI

    from contactqvi import cli
    from contactqvi.case import load_case
    from contactqvi.parameters import ParameterError
    from contactqvi.dynamic_runner import run_dynamics
    from contactqvi.runner import EXIT_CODES, PREFIX, OutputError, run_case

    parser = cli.make_parser("Solve a contact case file (TOML) along its load path.", "results/case",
                             f"-{PREFIX}ksp_monitor")
    parser.prog = "python -m contactqvi run"
    parser.add_argument("case", help="the case file (.toml)")
    parser.add_argument("--no-plot", action="store_true", help="skip the PNG of the contact states")
    parser.add_argument("--restart", action="store_true",
                        help="continue after the last complete checkpoint in --output (any number of ranks; "
                             "from step 1 when there is none)")
    parser.add_argument("--stop-after", type=int, metavar="K",
                        help="stop after step K with its checkpoint, as if interrupted (exit 3); continue with "
                             "--restart")
    try:
        args = cli.parse_args(parser, argv)
        case = load_case(args.case)
        run = run_case if case.dynamics is None else run_dynamics  # [dynamics]: a time integration
        _, code = run(case, args.output, MPI.COMM_WORLD, plot=not args.no_plot, restart=args.restart,
                      stop_after=args.stop_after)
    except ParameterError as exc:
        cli.print_error(exc)
        return EXIT_CODES["bad input"]
    except OutputError as exc:
        cli.print_error(exc)
        return EXIT_CODES["output failed"]
    return code


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    demos = demo_directory()
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        for name, text in DEMOS.items():
            print(f"  {name:<20} {text}{'' if demos else '  [demos not installed]'}")
        return 0
    name = argv[0]
    if name == "run":
        return run(argv[1:])
    if name not in DEMOS:
        print(f"contactqvi: unknown command {name!r}; known: run, {', '.join(DEMOS)}", file=sys.stderr)
        return 2
    if demos is None:
        print(f"contactqvi: the demos are not installed (neither ../demos nor <prefix>/share/contactqvi/demos)",
              file=sys.stderr)
        return 2
    script = demos / f"{name}.py"
    sys.argv = [str(script), *argv[1:]]
    runpy.run_path(str(script), run_name="__main__")
    return 0


def entry() -> int:
    """The ``contactqvi`` command and ``python -m contactqvi``: :func:`main` under
    :func:`contactqvi.cli.abort_on_error`."""
    from contactqvi.cli import abort_on_error

    return abort_on_error(main)


if __name__ == "__main__":
    sys.exit(entry())
