"""Standard ParaView views of a contact result (``demos/coulomb3d.py`` or ``python -m contactqvi run``).

Run with ParaView's Python (5.13: ``pvbatch`` or ``pvpython``) under a display or
``xvfb-run``; ``scripts/paraview/run.sh`` sets that up and ``make paraview``
installs ParaView from Debian and runs it on a fresh result (``make paraview-dynamics``: on a
fresh drop test)::

    xvfb-run -a pvbatch scripts/paraview/pv_views.py RESULT_DIR [--step N] [--out DIR] [--time]

Writes three PNGs of one load step (``--step N``: the N-th written step; default the last)
to ``--out`` (default: the result directory): ``paraview_deformed.png``, the body warped
by the displacement coloured by the von Mises stress (or |u|), with the rigid obstacles at
that step if ``summary.json`` describes them, at true scale for a hyperelastic body and
wherever bodies touch (magnified otherwise, the factor stated); ``paraview_contact_traction.png``,
the contact surface seen along its normal from the body's side, coloured by the contact
pressure named as contactqvi names it (Cauchy or nominal), with friction-traction arrows;
``paraview_stick_slip.png``, the contact states of the tributary patches (one cell per
node) with their areas.

A dynamic result (a case with ``[dynamics]``: ``summary.json`` has a ``scheme`` and timed
steps, or ``--time``) gets views over time instead (``pv_time.py``): ``paraview_time_NN.png``,
the body coloured by its velocity at a few chosen times (before contact, first contact, peak
contact force, separation, end), and ``RESULT_DIR/paraview_time.pvsm`` for ParaView's GUI
(``paraview --state=RESULT_DIR/paraview_time.pvsm``, then Play).

Every file and field the script reads is listed in ``SOURCES``, ``SUMMARY`` and ``FIELDS``
(a dynamic result's steps: ``STEP_KEYS``); a missing file or field stops it with a message
that names it. Files are read with ``ADIOS2VTXReader``; the pieces of several ranks are
appended onto one grid.
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # the views beside this script

from pv_body import deformed_view  # noqa: E402
from pv_common import (  # noqa: E402
    CONTACT_STATES,
    FIELDS,
    SOURCES,
    SUMMARY,
    ResultError,
    field_matches,
    finite_strain,
    obstacles_of,
    pressure_name,
    read_grid,
    read_summary,
    surface_frame,
)
from pv_surface import stick_slip_view, traction_view  # noqa: E402
from pv_time import STEP_KEYS, chosen_frames, is_dynamic, time_views  # noqa: E402

__all__ = ["CONTACT_STATES", "FIELDS", "SOURCES", "STEP_KEYS", "SUMMARY", "chosen_frames", "field_matches",
           "is_dynamic", "main"]

VIEWS = {
    "paraview_deformed.png": deformed_view,
    "paraview_contact_traction.png": traction_view,
    "paraview_stick_slip.png": stick_slip_view,
}


def describe(result_dir, step):
    """From ``summary.json``: a label, the obstacles (if the result has any), the entry of ``step``
    (where the obstacles are then, :func:`pv_body.obstacle_transform`), whether a body is hyperelastic
    and the contact pressure's name (:func:`pressure_name`)."""
    summary = read_summary(result_dir)
    p, case, steps = summary.get("parameters", {}), summary.get("case", {}), summary.get("steps", [])
    label = os.path.basename(os.path.normpath(result_dir))
    if "lev" in p:
        label = f"lev {p['lev']}, {p.get('geometry')}/{p.get('load')}"
    written = [s for s in steps if s.get("converged")]  # the steps in the files
    index = step - 1 if step > 0 else step
    entry = written[index] if step != 0 and -len(written) <= index < len(written) else {}
    if steps:
        label += f", step {entry.get('step', '?')} of {len(steps)}"
    return {"label": label, "obstacle": case.get("obstacle"), "obstacles": obstacles_of(case),
            "step": entry, "finite_strain": finite_strain(case),
            "pressure": pressure_name(case)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("result_dir", help="output directory of demos/coulomb3d.py or python -m contactqvi run")
    parser.add_argument("--step", type=int, default=-1, help="the N-th written load step (1, 2, ...; -1: the last)")
    parser.add_argument("--out", help="directory for the PNGs (default: result_dir)")
    parser.add_argument("--time", action="store_true",
                        help="views over time of a dynamic result (default: when summary.json has a scheme and times)")
    args = parser.parse_args(argv)
    out = args.out or args.result_dir
    os.makedirs(out, exist_ok=True)
    from paraview import simple

    simple.LoadPalette("WhiteBackground")
    try:
        summary = read_summary(args.result_dir, required=args.time)
        if args.time or is_dynamic(summary):
            time_views(args.result_dir, out, summary)
            return 0
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
