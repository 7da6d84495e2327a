"""``python -m contactqvi <problem> [options]``: run one of the demos.

``python -m contactqvi --help`` lists the problems; ``python -m contactqvi
<problem> --help`` shows that problem's options. The demos live in ``demos/``
of the source tree (this package is installed in editable mode).
"""

from __future__ import annotations

import pathlib
import runpy
import sys

DEMOS = pathlib.Path(__file__).resolve().parent.parent / "demos"

PROBLEMS = {
    "coulomb3d": "3D contact with Coulomb friction, SCD semismooth* Newton (seed 000)",
    "simplified_friction": "Stadler's simplified (scalar Tresca) friction: PDAS, SS, ALM, Uzawa (seed 002)",
    "thermoforming": "obstacle problems and the thermoforming QVI, semismooth Newton (seed 003)",
    "elasticity": "plain linear elasticity on the contact body (no contact)",
}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: python -m contactqvi <problem> [options]   (mpirun -n N python -m contactqvi ...)\n")
        print("problems:")
        for name, text in PROBLEMS.items():
            available = "" if (DEMOS / f"{name}.py").is_file() else "  [not available]"
            print(f"  {name:<20} {text}{available}")
        print("\n'python -m contactqvi <problem> --help' lists a problem's options.")
        return 0
    name = argv[0]
    script = DEMOS / f"{name}.py"
    if name not in PROBLEMS or not script.is_file():
        print(f"problem: unknown problem {name!r}; known: {', '.join(PROBLEMS)}", file=sys.stderr)
        return 2
    sys.argv = [str(script), *argv[1:]]
    runpy.run_path(str(script), run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main())
