"""The views over time of a dynamic result (``python -m contactqvi run`` on a case with ``[dynamics]``).

``pv_views.py`` comes here when the result's ``summary.json`` describes a time integration
(:func:`is_dynamic`), or with ``--time``. From ``body.bp`` (a time series: the simulated times,
s) and ``summary.json`` it writes

* ``paraview_time_NN.png`` (NN = 01, 02, ...) to ``--out``: the body warped by the displacement
  (true scale where bodies touch or at finite strain, magnified otherwise, the factor stated, as
  in the deformed view: :func:`pv_body.drawing_scale`), coloured by the velocity magnitude, one
  range in every frame so that frames compare (from 0 to the run's largest speed, or to a
  robust top when a few nodes ring far faster, :func:`speed_top`; those red), with velocity
  arrows and the rigid obstacles where the step of the frame has them; at the times
  :func:`chosen_frames` picks from the steps' contact force (before contact, first contact,
  peak contact force, separation, end), each with its time in the title;
* ``RESULT_DIR/paraview_time.pvsm``: the same pipeline on ``body.bp`` with the time shown, for
  ParaView's GUI: ``paraview --state=RESULT_DIR/paraview_time.pvsm``, then Play. A Python
  animation cue in it (:func:`obstacle_cue_script`) moves the obstacles with the time.

The pure-Python parts (the choice of frames, the time unit, the obstacles' cue) load
without ParaView (``tests/test_paraview_script.py``).
"""

from __future__ import annotations

import glob
import os

import numpy as np

from pv_body import (
    OBSTACLE_NAME,
    drawing_scale,
    move_obstacles,
    oblique_camera,
    obstacle_transform,
    show_body,
    show_obstacles,
)
from pv_common import (
    FIELDS,
    SOURCES,
    SUMMARY,
    ResultError,
    add_title,
    clear,
    colour_bar,
    field,
    finite_strain,
    grid_at,
    new_view,
    obstacles_of,
    open_vtx,
    points_of,
    robust_top,
    screenshot,
    show_text,
)

#: The keys of each converged step of ``summary.json`` that the frames are chosen from.
STEP_KEYS = ("time", "contact_force")
#: A step touches when its contact force exceeds this fraction of the run's largest (round-off
#: of a step without contact stays below it).
TOUCHING = 1e-6
#: Frames at the least (when the events fall on fewer steps): the middles of the longest gaps.
MIN_FRAMES = 4
FRAME_NAME = "paraview_time_{:02d}.png"
STATE = "paraview_time.pvsm"
#: Units of the time in the titles, (name, factor from s); the first that shows the end time >= 1.
TIME_UNITS = (("s", 1.0), ("ms", 1e3), ("\u00b5s", 1e6))
#: The colour of speeds above the colour range (a few nodes ringing where bodies touched).
ABOVE_RANGE = (0.85, 0.1, 0.1)
#: Speeds beyond this factor on their robust top are shown above the colour range (:func:`speed_top`).
OUTLIERS = 1.25
#: Velocity arrows: about this many, the top of the colour range this fraction of the body's size.
ARROWS, ARROW = 50, 0.15


def is_dynamic(summary):
    """Whether ``summary`` (``summary.json``) is a time integration's: a ``scheme`` and timed steps."""
    return "scheme" in summary and any("time" in step for step in summary.get("steps") or [])


def written_steps(summary, where):
    """The steps in ``body.bp``: the converged steps of ``summary``, each with the :data:`STEP_KEYS`;
    a ResultError naming ``where`` (the summary's path) and the missing key otherwise."""
    steps = [step for step in summary.get("steps") or [] if step.get("converged")]
    if not steps:
        raise ResultError(f"{where}: no converged time step")
    for step in steps:
        missing = [key for key in STEP_KEYS if key not in step]
        if missing:
            raise ResultError(f"{where}: step {step.get('step', '?')} has no '{missing[0]}' (STEP_KEYS in pv_time.py)")
    return steps


def contact_forces(steps):
    """|contact force| (N) of each step."""
    return np.array([np.linalg.norm(np.asarray(step["contact_force"], dtype=float)) for step in steps])


def chosen_frames(steps):
    """(index in ``steps``, what happens) of the frames, by time: the first step; before contact (the
    step before the first that touches, :data:`TOUCHING`), first contact, the peak contact force,
    separation (the first step after the peak that does not touch); the end. Events on one step
    share its frame; fewer than :data:`MIN_FRAMES` are filled with the middles of the longest gaps."""
    force = contact_forces(steps)
    touching = force > TOUCHING * force.max()
    events = [(0, "first step")]
    if touching.any():
        first, peak = int(np.argmax(touching)), int(np.argmax(force))
        events += [(first - 1, "before contact")] if first > 0 else []
        events += [(first, "first contact"), (peak, "peak contact force")]
        after = np.flatnonzero(~touching[peak:])
        events += [(peak + int(after[0]), "separation")] if len(after) else []
    events.append((len(steps) - 1, "end"))
    frames = {}
    for index, what in events:
        frames[index] = f"{frames[index]}, {what}" if index in frames else what
    while len(frames) < min(MIN_FRAMES, len(steps)):
        kept = sorted(frames)
        start, stop = max(zip(kept[:-1], kept[1:]), key=lambda gap: gap[1] - gap[0])
        frames[(start + stop) // 2] = ""
    return sorted(frames.items())


def time_unit(end):
    """(name, factor from s) of the unit of :data:`TIME_UNITS` that shows ``end`` (s) as at least 1."""
    return next(((name, factor) for name, factor in TIME_UNITS if end * factor >= 1.0), TIME_UNITS[-1])


def obstacle_cue_script(steps, times, scale, count):
    """The script of the state file's Python animation cue that moves the ``count`` obstacles'
    Transform filters (:data:`pv_body.OBSTACLE_NAME`) with the animation's time: at time t, where
    the written step of ``steps`` at the last of ``times`` (s) not after t has them
    (:func:`pv_body.obstacle_transform`, the motion magnified by ``scale``)."""
    transforms = [obstacle_transform(step, scale) for step in steps]
    names = [OBSTACLE_NAME.format(k) for k in range(1, count + 1)]
    return f"""import bisect
from paraview import simple
TIMES = {[float(t) for t in times]!r}
TRANSFORMS = {transforms!r}
NAMES = {names!r}
def start_cue(self):
    tick(self)
def tick(self):
    index = max(bisect.bisect_right(TIMES, simple.GetAnimationScene().AnimationTime) - 1, 0)
    for name in NAMES:
        transform = simple.FindSource(name).Transform
        transform.Translate, transform.Rotate = TRANSFORMS[index]
def end_cue(self):
    pass
"""


def speed_top(speeds):
    """The top of the colours of ``speeds`` (the nodes' at every time of the run): their largest, or,
    when a few nodes (ringing where bodies touched) go faster than :data:`OUTLIERS` times the
    robust top of the rest (:func:`pv_common.robust_top`), that robust top."""
    largest, robust = float(np.max(speeds)), robust_top(speeds)
    return robust if largest > OUTLIERS * robust else largest


def _run(reader, times, path, steps, case):
    """What the frames share: the displacement's and velocity's names in ``reader`` (the file
    ``path``), the speeds of the nodes at each time (a node the pieces of several ranks share
    once), the colours' top (:func:`speed_top`) and the largest speed, the drawing scale and
    its words (:func:`pv_body.drawing_scale`)."""
    u_max, speeds = 0.0, []
    for time in times:
        grid = grid_at(reader, time, f"{path} at t = {time:g} s")
        _, u, u_name = field(grid, "displacement", path)
        _, v, v_name = field(grid, "velocity", path, required=True)
        u_max = max(u_max, float(np.linalg.norm(u.reshape(len(u), -1), axis=1).max()))
        nodes = np.unique(points_of(grid), axis=0, return_index=True)[1]
        speeds.append(np.linalg.norm(v.reshape(len(v), -1)[nodes], axis=1))
    b = reader.GetDataInformation().GetBounds()
    scale, drawn = drawing_scale(u_max, max(b[1] - b[0], b[3] - b[2], b[5] - b[4]), finite_strain(case),
                                 bool(contact_forces(steps).max() > 0.0))  # fmt: skip
    top = speed_top(np.concatenate(speeds))
    largest = float(max(speed.max() for speed in speeds))
    colours = (f"its 99th percentile over the nodes and times of the run (red above it, up to {largest:.3g} m/s)"
               if top < largest else "its largest over the run")  # fmt: skip
    return {"u": u_name, "v": v_name, "speeds": speeds, "top": top, "scale": scale,
            "captions": [f"{drawn}, largest displacement of the run {u_max * 1e3:.3g} mm; grey box: undeformed",
                         f"colour: velocity magnitude, one range in every frame: {colours}",
                         f"arrows: velocity, the colour range's top {ARROW:.0%} of the body long"]}  # fmt: skip


def _bounds(source, times):
    """The bounds of ``source`` over ``times``."""
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for time in times:
        source.UpdatePipeline(time)
        b = np.asarray(source.GetDataInformation().GetBounds()).reshape(3, 2)
        low, high = np.minimum(low, b[:, 0]), np.maximum(high, b[:, 1])
    return np.column_stack([low, high]).ravel()


def _scene(view, reader, run, frame_times, case):
    """The body warped by the displacement and coloured by the speed, velocity arrows, the
    obstacles, seen so that the body at ``frame_times`` is in the picture: the Transforms that move
    the obstacles and the caption's lines."""
    from paraview import simple

    display = show_body(view, reader, run["u"], run["scale"])
    display.Representation = "Surface"  # the colours of the small cells where bodies touch, not their edges
    bounds = _bounds(display.Input, frame_times)
    centre, extent = list((bounds[0::2] + bounds[1::2]) / 2), float(max(bounds[1::2] - bounds[0::2]))
    simple.ColorBy(display, ("POINTS", run["v"], "Magnitude"))
    lut = simple.GetColorTransferFunction(run["v"])
    lut.ApplyPreset("Viridis (matplotlib)", True)
    lut.AutomaticRescaleRangeMode = "Never"  # one range in every frame
    lut.RescaleTransferFunction(0.0, run["top"] or 1.0)
    lut.UseAboveRangeColor, lut.AboveRangeColor = 1, list(ABOVE_RANGE)
    label, _, unit = FIELDS["velocity"][2:5]
    colour_bar(view, lut, f"{label} magnitude ({unit})", run["top"], position=(0.85, 0.2))
    arrows = simple.Show(simple.Glyph(Input=display.Input, GlyphType="Arrow", OrientationArray=["POINTS", run["v"]],
                                      ScaleArray=["POINTS", run["v"]], ScaleFactor=ARROW * extent / (run["top"] or 1.0),
                                      GlyphMode="Uniform Spatial Distribution (Surface Sampling)",
                                      MaximumNumberOfSamplePoints=ARROWS), view)  # fmt: skip
    simple.ColorBy(arrows, None)
    arrows.DiffuseColor = arrows.AmbientColor = [0.15, 0.15, 0.15]
    moved, captions = show_obstacles(view, obstacles_of(case), centre, extent, "at that time")
    oblique_camera(view, centre, extent, bounds)
    return moved, run["captions"] + captions


def time_views(result_dir, out, summary):
    """The frames (:func:`chosen_frames`) of the dynamic result in ``result_dir`` to ``out``, and its
    ParaView state (:data:`STATE`) beside its ``body.bp``."""
    from paraview import simple

    steps, case = written_steps(summary, os.path.join(result_dir, SUMMARY)), summary.get("case") or {}
    path = os.path.join(result_dir, SOURCES["volume"])
    reader, times = open_vtx(path)
    if len(times) != len(steps):
        raise ResultError(f"{path}: {len(times)} times, {SUMMARY}: {len(steps)} converged steps")
    run, frames = _run(reader, times, path, steps, case), chosen_frames(steps)
    view = new_view()
    moved, captions = _scene(view, reader, run, [times[index] for index, _ in frames], case)
    name = os.path.basename(os.path.normpath(result_dir))
    title, caption = add_title(view, name, "\n".join(captions))
    scene = simple.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    time_name, factor = time_unit(times[-1])

    def show_time(index):
        scene.AnimationTime = times[index]
        move_obstacles(moved, steps[index], run["scale"])

    for stale in glob.glob(os.path.join(out, FRAME_NAME.replace("{:02d}", "[0-9][0-9]"))):
        os.remove(stale)  # the frames of an earlier run
    for number, (index, what) in enumerate(frames, 1):
        show_time(index)
        title.Text = f"{name}: {what + ', ' if what else ''}t = {times[index] * factor:.4g} {time_name}"
        faster = run["speeds"][index] > run["top"]
        caption.Text = "\n".join(captions + [f"red: {faster.sum()} nodes faster, up to "
                                             f"{run['speeds'][index].max():.3g} m/s"] * bool(faster.any()))  # fmt: skip
        screenshot(view, os.path.join(out, FRAME_NAME.format(number)))
    show_time(0)
    title.Text, caption.Text = name, "\n".join(captions)
    clock = simple.AnnotateTimeFilter(Input=reader, Format=f"t = {{time:.4g}} {time_name}", Scale=factor)
    show_text(view, clock, "Upper Left Corner")
    if moved:
        cue = simple.PythonAnimationCue()
        cue.Script = obstacle_cue_script(steps, times, run["scale"], len(moved))
        scene.Cues.append(cue)
    state = os.path.join(result_dir, STATE)
    simple.SaveState(state)
    print(f"pv_views: wrote {state} (paraview --state={state}, then Play)")
    clear(view)
