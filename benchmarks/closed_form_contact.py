"""Contact solves against closed-form solutions: Hertz (three meshes) and Cattaneo-Mindlin.

Runs the shipped cases ``cases/hertz.toml`` (on ``meshes/hertz_{coarse,medium,fine}.geo``)
and ``cases/cattaneo_mindlin*.toml`` through the case runner and puts the measured
force, contact radius, peak pressure, stick radius and tangential force beside the
formulas of :mod:`contactqvi.problems.hertz`:

    python benchmarks/closed_form_contact.py [--tables hertz mindlin] [--output DIR]

Writes ``hertz.{json,md}`` and ``cattaneo_mindlin.{json,md}`` to ``--output``.
"""

from __future__ import annotations

import argparse
import pathlib
import shutil
import tempfile

import benchlib
import numpy as np

from contactqvi import tables
from contactqvi.case import load_case, parse_case
from contactqvi.problems import hertz
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
MESHES = {"coarse": 8, "medium": 16, "fine": 32}  # h at the contact = a / value


def _run(case_file: pathlib.Path, mesh: str | None, comm) -> tuple[dict, dict]:
    """Summary of a case (optionally on another mesh) and the case as tables."""
    raw = load_case(case_file).to_dict()
    if mesh is not None:
        raw["mesh"] = {"file": str(ROOT / "meshes" / mesh)}
    case = parse_case(raw, case_file.parent)
    tmp = comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0)
    summary, _ = run_case(case, tmp, comm, plot=False)  # a failed step shows as its status in the table
    comm.Barrier()
    if comm.rank == 0:
        shutil.rmtree(tmp)
    return summary, raw


def _symmetry_factor(raw: dict) -> int:
    """4 for the quarter model, 2 for the half model, 1 for the full block."""
    return 2 ** len([name for name in raw["boundary"].get("displacement", {}) if name.startswith("symmetry")])


def hertz_table(comm) -> tuple[dict, str]:
    rows = []
    for level, fraction in MESHES.items():
        summary, raw = _run(ROOT / "cases" / "hertz.toml", f"hertz_{level}.geo", comm)
        last = summary["steps"][-1]
        E, nu, R = raw["material"]["young"], raw["material"]["poisson"], raw["obstacle"]["radius"]
        delta = -raw["steps"][-1]["translation"][2]
        k = _symmetry_factor(raw)
        a = hertz.contact_radius(R, delta)
        row = {"mesh": level, "h": a / fraction, "n": summary["n"], "status": last["status"],
               "newton": [s["iterations"] for s in summary["steps"]], "krylov": [s["inner_iterations"] for s in summary["steps"]],
               "P": k * abs(last["contact_force"][2]), "P_hertz": hertz.contact_force(E, nu, R, delta),
               "a": float(np.sqrt(k * last["contact_area"] / np.pi)), "a_hertz": a,
               "p0": last["max_contact_pressure"], "p0_hertz": hertz.peak_pressure(E, nu, R, delta),
               "equilibrium_error": last["equilibrium_error"]}
        rows.append(row)
    header = ["mesh (h at contact)", "dofs", "Newton per step", "P (MN) / Hertz", "error P", "a (mm) / Hertz",
              "dist(a, a_H) / h", "p0 (GPa) / Hertz", "error p0"]
    body = [[f"{r['mesh']} (a/{MESHES[r['mesh']]})", r["n"], " ".join(map(str, r["newton"])),
             f"{r['P'] / 1e6:.4f} / {r['P_hertz'] / 1e6:.4f}", f"{r['P'] / r['P_hertz'] - 1:+.2%}",
             f"{r['a'] * 1e3:.2f} / {r['a_hertz'] * 1e3:.2f}", f"{abs(r['a'] - r['a_hertz']) / r['h']:.2f}",
             f"{r['p0'] / 1e9:.3f} / {r['p0_hertz'] / 1e9:.3f}", f"{r['p0'] / r['p0_hertz'] - 1:+.2%}"] for r in rows]
    text = ("## Hertz: rigid sphere R = 1 m pressed 1 mm into an elastic block (E = 70 GPa, nu = 0.3)\n\n"
            "Quarter model, four steps of 0.25 mm; P from the total contact force, a from the contact area "
            "(pi a^2), p0 the largest nodal pressure (normal force / lumped area). Formulas: "
            "contactqvi/problems/hertz.py.\n\n" + tables.markdown_table(header, body))
    return {"rows": rows}, text


def mindlin_table(comm) -> tuple[dict, str]:
    rows, text = [], ["## Cattaneo-Mindlin: the Hertz contact (mu = 0.3) moved tangentially\n",
                      "Q, P from the contact force; c from the sticking area (pi c^2); the formulas take the "
                      "measured P and a. Mindlin's Q(s) is for a half-space with the tangential problem "
                      "uncoupled from the normal one (exact for Dundurs beta = 0).\n"]
    for name in ("cattaneo_mindlin", "cattaneo_mindlin_nu045"):
        summary, raw = _run(ROOT / "cases" / f"{name}.toml", None, comm)
        E, nu, mu = raw["material"]["young"], raw["material"]["poisson"], raw["contact"]["friction"]
        k = _symmetry_factor(raw)
        indent = summary["steps"][0]
        P = k * abs(indent["contact_force"][2])
        a = float(np.sqrt(k * indent["contact_area"] / np.pi))
        table = []
        for step in summary["steps"][1:]:
            s = step["translation"][0]
            Q = k * abs(step.get("contact_force", [np.nan])[0])
            c = float(np.sqrt(k * step.get("sticking_area", np.nan) / np.pi))
            c_cm = float(hertz.stick_radius(a, np.array(min(Q, mu * P)), mu, P))
            Q_m = float(hertz.mindlin_force(s, mu, P, hertz.shear_modulus(E, nu), nu, a))
            table.append({"s": s, "status": step["status"], "newton": step["iterations"], "Q": Q, "Q_mindlin": Q_m,
                          "c": c, "c_cattaneo": c_cm})
        rows.append({"case": name, "poisson": nu, "dundurs_beta": hertz.dundurs_beta(nu), "P": P, "a": a, "steps": table})
        text.append(f"### nu = {nu} (Dundurs beta = {hertz.dundurs_beta(nu):.3f}), P = {P / 1e6:.4f} MN, a = {a * 1e3:.2f} mm\n")
        text.append(tables.markdown_table(
            ["s (um)", "status", "Newton", "Q / (mu P)", "Mindlin Q / (mu P)", "c / a", "Cattaneo c / a"],
            [[f"{r['s'] * 1e6:.0f}", r["status"], r["newton"], f"{r['Q'] / (mu * P):.3f}",
              f"{r['Q_mindlin'] / (mu * P):.3f}", f"{r['c'] / a:.3f}", f"{r['c_cattaneo'] / a:.3f}"] for r in table]))
    return {"rows": rows}, "\n".join(text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tables", nargs="+", default=["hertz", "mindlin"], choices=["hertz", "mindlin"])
    parser.add_argument("--output", default=str(pathlib.Path(__file__).parent / "results"))
    args, comm, out = benchlib.parse(parser)
    for name, make in (("hertz", hertz_table), ("mindlin", mindlin_table)):
        if name in args.tables:
            data, markdown = make(comm)
            tables.write_table(comm, out / ("hertz" if name == "hertz" else "cattaneo_mindlin"),
                           {"machine": benchlib.machine(comm), **data}, markdown)


if __name__ == "__main__":
    main()
