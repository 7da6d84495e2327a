"""A failed benchmark run is a row of its table, written and read back without a crash (issue 46, item 5).

``benchmarks/peers_real.py`` stopped with ``KeyError: 'dofs'`` writing its table after the
reference run of a case timed out, and every later run stopped reading that JSON. The
table writer and the reader are checked here on such rows; no benchmark is run.
"""

from __future__ import annotations

import json
import pathlib
import re
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
import peers_real  # noqa: E402
import rows  # noqa: E402

pytestmark = pytest.mark.one_rank(reason="tables of rows in files of a per-rank tmp_path, no MPI")

TIMEOUT = "failed: timeout after 900 s"


def _converged(problem: str, size: str, dofs: int) -> dict:
    """A converged reference row with the fields the table reads."""
    return {"problem": problem, "size": size, "dofs": dofs, "code": "reference", "status": "converged",
            "newton_iterations": 6, "solve_time": 1.5, "solve_cpu_time": 1.4, "process_cpu_seconds": 3.0,
            "process_seconds": 3.2, "wall_time": 1.5, "peak_memory_mib": 250.0, "contact_force": [0.0, 0.0, -10.0],
            "force_error": 0.0, "displacement_error": 0.0, "load_average": 0.5, "closed_form_error": 0.01}


def _data(table_rows: list[dict]) -> dict:
    return {"machine": {"cpu": "test", "cores": 2, "memory_gib": 1.0}, "ours_commit": "0" * 40, "accuracy": 1e-6,
            "tolerances": peers_real.TOLERANCES, "getfem_options": [], "getfem_settings_trials": [],
            "rows": table_rows, "load_average_end": [0.5, 0.5, 0.5]}


def test_a_failed_row_holds_its_key_status_and_time():
    assert rows.failed_row(TIMEOUT, 900.4, problem="hertz_bodies", size="fine", code="reference") == {
        "problem": "hertz_bodies", "size": "fine", "code": "reference", "status": TIMEOUT, "seconds": 900.4,
        "failed": True}
    assert rows.failed(rows.failed_row("diverged_max_it", 1.0)) and not rows.failed(_converged("hertz", "c", 9))
    table = [{"dofs": 30}, {"dofs": None}, {}, {"dofs": 10}]
    assert [r.get("dofs") for r in sorted(table, key=rows.order("dofs"))] == [10, 30, None, None]
    assert rows.cell({"a": 0.123456}, "a") == "0.123" and rows.cell({}, "a") == "\u2013"


def test_peers_real_writes_and_reads_back_a_table_with_failed_references(tmp_path):
    """The reference of one case timed out (a row without dofs, as :func:`rows.failed_row` makes
    it), another failed as runs before issue 46 wrote it (its record's status, no flag): the
    table says so with the time used, the limits leave them out, and the file written reads back
    into the same table; the next run's rows merge with it."""
    failed = rows.failed_row(TIMEOUT, 900.4, problem="hertz_bodies", size="fine", code="reference",
                             case="hertz_bodies_fine.toml", output="runs/x")
    old_style = {"problem": "hertz", "size": "medium", "code": "reference", "status": "failed: exit 1",
                 "process_seconds": 12.0}
    data = _data([_converged("hertz", "coarse", 3000), failed, old_style])
    text = peers_real.markdown(data)
    assert f"| hertz_bodies | fine | \u2013 | reference | **failed after 900 s: {TIMEOUT}** |" in text
    assert "| hertz | medium | \u2013 | reference | **failed after 12 s: failed: exit 1** |" in text
    assert "| hertz | coarse | 3000 | reference |" in text
    written = peers_real.save(tmp_path, "0" * 40, 1e-6, [], [], data["rows"], {})
    again = rows.read_table(tmp_path / "peers_real.json")
    assert peers_real.markdown(again) == written == (tmp_path / "peers_real.md").read_text()
    assert again["limits"] == []  # only reference rows: no code timed
    merged = rows.merge_rows(tmp_path / "peers_real.json", [_converged("hertz_bodies", "fine", 9000)],
                             ("problem", "size", "code"))
    assert [(r["problem"], r["size"], r.get("dofs")) for r in merged] == [
        ("hertz", "coarse", 3000), ("hertz", "medium", None), ("hertz_bodies", "fine", 9000)]


def test_an_unreadable_table_is_an_empty_one(tmp_path, capsys):
    """A truncated JSON file (a run stopped while writing, before writes were atomic) reads as no
    rows, said on stderr; a missing one silently."""
    path = tmp_path / "peers_real.json"
    assert rows.read_table(path) == {}
    path.write_text(json.dumps(_data([_converged("hertz", "coarse", 3000)]))[:-20])
    assert rows.read_table(path) == {}
    assert "peers_real.json: not read" in capsys.readouterr().err
    rows.write_text(path, "{\"rows\": []}\n")
    assert rows.read_table(path) == {"rows": []} and sorted(p.name for p in tmp_path.iterdir()) == [path.name]


def test_weak_scaling_shows_a_failed_run_with_its_status_and_time():
    """benchmarks/weak_scaling.py: a run that exited non-zero is a row with its status and wall
    time in the table, and the projection, which needs the 1-rank run, is left out instead of
    stopping the script."""
    import weak_scaling

    failed = rows.failed_row("failed: exit 137", 1234.5, case="d1/L1", ranks=1, lev=6, exit_code=137,
                             wall_s=1234.5, commit="abc")
    text = weak_scaling.markdown({"machine": {"cores": 2}, "rows": [failed]})
    assert "| 1 | 6 | failed: exit 137 after 1234 s |" in text
    assert weak_scaling.projection([failed]) == {}


def test_homogeneous_compression_counts_and_tables():
    """``benchmarks/homogeneous_compression.py``: the attempts and searches of a cut step from its history
    (a mode searched each step searches before every solve, ``once`` before the first step only, and a
    mode that records ``searches`` is taken at its word); a run with a mode the case reader does not know
    (a new search mode before it exists) is a failed row of both tables, which still compare the others
    with the reference."""
    import homogeneous_compression as hc

    history = [{"k": 0, "substep": 0}, *({"k": k, "substep": 1, "search": 0} for k in range(3)),
               {"k": 0, "substep": 1, "search": 1}, {"k": 0, "substep": 2, "search": 0}]
    step = {"step": 2, "history": history}
    assert hc.attempts(step) == 3
    assert (hc.searches(step, "until_settled"), hc.searches(step, "once"), hc.searches({**step, "step": 1}, "once"),
            hc.searches({**step, "searches": 7}, "current")) == (4, 0, 1, 7)
    failed = rows.failed_row("failed: ParameterError: contacts[0].search", 0.1, search="current", friction=0.3,
                             case="bulging")
    assert "| 30 % | current | \u2013 | failed: ParameterError" in hc.homogeneous_markdown([{**failed, "case": "30 %"}])
    measured = [failed, *({"friction": 0.3, "search": mode, "step": 1, "status": "converged_rtol", "newton": 6,
                           "force": [0.0, 0.0, fz]} for mode, fz in (("reference", 2.0), ("once", 2.2)))]
    hc.against_reference(measured)
    assert measured[2]["force_difference"] == pytest.approx(0.1) and "force_difference" not in measured[0]
    assert "| 0.3 | once | 1 | converged_rtol | 6 | \u2013 | \u2013 | 2.200000e+00 | \u2013 | 1.00e-01 |" in \
        hc.bulging_markdown(measured)


def test_quadratic_elements_compares_each_oring_with_its_own_nu_045_row():
    """``benchmarks/quadratic_elements.py``: an O-ring row's force change and Krylov ratio are taken
    against the row of nu = 0.45 with the same mesh, order, formulation and friction (the frictional
    Taylor-Hood rows against each other, not against the frictionless ones), and a failed run is a
    row of the table with its status."""
    import quadratic_elements as qe

    key = {"case": "oring", "order": 2, "mesh": "h0.25", "formulation": "nodal_pressure"}

    def converged(poisson: float, friction: float, force: float, krylov: float) -> dict:
        return {**key, "poisson": poisson, "friction": friction, "status": "converged_rtol", "dofs": 8766,
                "newton_per_step": 4.0, "newton": 80, "krylov_per_newton": krylov, "direct_fallbacks": 0,
                "seconds": 70.0, "failed": False, "force": force, "area": 1.7e-6}

    measured = [converged(0.45, 0.0, 2.0, 10.0), converged(0.45, 0.4, 4.0, 8.0), converged(0.4999, 0.4, 5.0, 12.0),
                rows.failed_row("diverged_max_it", 3.0, **key, poisson=0.4999, friction=0.0)]
    table = qe.markdown(measured)
    assert ("| h0.25 | 0.4999 | 2 | nodal_pressure | 0.4 | 8766 | 5.00000 | +25.0% | 1.700 | 4.0 (80) "
            "| 12.0 | 1.50× | 0 |") in table
    assert "| h0.25 | 0.45 | 2 | nodal_pressure | 0 | 8766 | 2.00000 | +0.0% |" in table
    assert "| h0.25 | 0.4999 | 2 | nodal_pressure | 0 | \u2013 | diverged_max_it | \u2013 | \u2013 |" in table


@pytest.mark.serial  # launches mpirun
def test_restart_shows_a_run_without_summary_as_failed_rows(tmp_path):
    """``benchmarks/restart.py``: the uninterrupted run of a case that stops at its input check
    (exit 2, no summary.json) is a failed row for each restart, and the table shows it beside a
    measured row, instead of the script stopping on the missing summary."""
    import argparse

    import restart

    case = ROOT / "tests" / "data" / "mistakes" / "m08_normal_flipped.toml"
    found = restart.compare("m08", case, tmp_path, argparse.Namespace(ranks=1, other_ranks=2), "abc")
    assert [(r["case"], r["ranks"], r["restart_ranks"], r["status"], rows.failed(r)) for r in found] == [
        ("m08", 1, 1, "failed: exit 2 (uninterrupted run)", True),
        ("m08", 1, 2, "failed: exit 2 (uninterrupted run)", True)]
    measured = {"case": "d3_L2 lev 8", "ranks": 2, "restart_ranks": 1, "steps": 4, "killed_in_step": 3,
                "counts_equal": True, "d_newton": 0, "rel_diff": 2e-13, "wall_whole": 60.5, "wall_killed": 40.1,
                "wall_restart": 30.2, "status": "converged_rtol", "commit": "abc"}
    text = restart.markdown([measured, *found], "abc")
    assert ("| d3_L2 lev 8 | 2 | 1 | 4 | 3 | converged_rtol | yes | 0 | 2e-13 | 1e-9 | 60.5 | 40.1 + 30.2 | abc |"
            in text)
    assert (f"| m08 | 1 | 2 | \u2013 | \u2013 | failed: exit 2 (uninterrupted run) | \u2013 | \u2013 | \u2013 | 1e-9 "
            f"| \u2013 | failed after {found[1]['seconds']:.0f} | abc |") in text


def test_weak_scaling_tables_only_rewrites_the_stored_tables(tmp_path, monkeypatch, capsys):
    """``benchmarks/weak_scaling.py --tables-only`` rewrites the markdown from the stored JSON
    (the same as the stored one); where there is no JSON it says so and exits, instead of a
    KeyError on the empty table."""
    import weak_scaling

    stored = ROOT / "benchmarks" / "results"
    (tmp_path / "weak_scaling.json").write_text((stored / "weak_scaling.json").read_text())
    monkeypatch.setattr(sys, "argv", ["weak_scaling.py", "--tables-only", "--output", str(tmp_path)])
    weak_scaling.main()
    assert (tmp_path / "weak_scaling.md").read_text() == (stored / "weak_scaling.md").read_text()
    empty = tmp_path / "none"
    monkeypatch.setattr(sys, "argv", ["weak_scaling.py", "--tables-only", "--output", str(empty)])
    with pytest.raises(SystemExit, match=re.escape(f"error: --tables-only: no rows in {empty / 'weak_scaling.json'}")):
        weak_scaling.main()
    assert not empty.exists()
