"""Standard ParaView views of a contact result (``demos/coulomb3d.py`` or ``python -m contactqvi run``).

Run with ParaView's Python (5.13: ``pvbatch`` or ``pvpython``) under a display or
``xvfb-run``; ``scripts/paraview/run.sh`` sets that up and ``make paraview``
installs ParaView from Debian and runs it on a fresh result::

    xvfb-run -a pvbatch scripts/paraview/pv_views.py RESULT_DIR [--step N] [--out DIR]

Writes three PNGs of one load step (``--step N``: the N-th written step; default the last)
to ``--out`` (default: the result directory): ``paraview_deformed.png``, the body warped
by the displacement coloured by the von Mises stress (or |u|), with the rigid obstacles at
that step if ``summary.json`` describes them, at true scale for a hyperelastic body and
wherever bodies touch (magnified otherwise, the factor stated); ``paraview_contact_traction.png``,
the contact surface seen along its normal from the body's side, coloured by the contact
pressure named as contactqvi names it (Cauchy or nominal), with friction-traction arrows;
``paraview_stick_slip.png``, the contact states of the tributary patches (one cell per
node) with their areas.

Every file and field the script reads is listed in ``SOURCES`` and ``FIELDS``; a
missing file or field stops it with a message that names it. Files are read with
``ADIOS2VTXReader``; the pieces of several ranks are appended onto one grid.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # the views beside this script

from pv_body import deformed_view  # noqa: E402
from pv_common import (  # noqa: E402
    CONTACT_STATES,
    FIELDS,
    SOURCES,
    ResultError,
    field_matches,
    finite_strain,
    pressure_name,
    read_grid,
    surface_frame,
)
from pv_surface import stick_slip_view, traction_view  # noqa: E402

__all__ = ["CONTACT_STATES", "FIELDS", "SOURCES", "field_matches", "main"]

VIEWS = {
    "paraview_deformed.png": deformed_view,
    "paraview_contact_traction.png": traction_view,
    "paraview_stick_slip.png": stick_slip_view,
}


def describe(result_dir, step):
    """From ``summary.json``: a label, the obstacles (if the result has any) and their translation
    at ``step``, whether a body is hyperelastic and the contact pressure's name (:func:`pressure_name`)."""
    try:
        with open(os.path.join(result_dir, "summary.json")) as f:
            summary = json.load(f)
    except (OSError, ValueError):
        summary = {}
    p, case, steps = summary.get("parameters", {}), summary.get("case", {}), summary.get("steps", [])
    label = os.path.basename(os.path.normpath(result_dir))
    if "lev" in p:
        label = f"lev {p['lev']}, {p.get('geometry')}/{p.get('load')}"
    written = [s for s in steps if s.get("converged")]  # the steps in the files
    index = step - 1 if step > 0 else step
    entry = written[index] if step != 0 and -len(written) <= index < len(written) else {}
    if steps:
        label += f", step {entry.get('step', '?')} of {len(steps)}"
    obstacles = [case["obstacle"]] if case.get("obstacle") else []
    obstacles += [pair["obstacle"] for pair in case.get("contacts") or [] if pair.get("obstacle")]
    return {"label": label, "obstacle": case.get("obstacle"), "obstacles": obstacles,
            "translation": entry.get("translation"), "finite_strain": finite_strain(case),
            "pressure": pressure_name(case)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("result_dir", help="output directory of demos/coulomb3d.py or python -m contactqvi run")
    parser.add_argument("--step", type=int, default=-1, help="the N-th written load step (1, 2, ...; -1: the last)")
    parser.add_argument("--out", help="directory for the PNGs (default: result_dir)")
    args = parser.parse_args(argv)
    out = args.out or args.result_dir
    os.makedirs(out, exist_ok=True)
    from paraview import simple

    simple.LoadPalette("WhiteBackground")
    try:
        result = {role: read_grid(os.path.join(args.result_dir, name), args.step) for role, name in SOURCES.items()}
        b = result["volume"].GetBounds()
        result["frame"] = surface_frame(result["surface"], [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2])
        result["case"] = describe(args.result_dir, args.step)
        for name, view in VIEWS.items():
            view(result, os.path.join(out, name))
    except ResultError as error:
        print(f"pv_views: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
