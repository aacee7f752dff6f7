#!/usr/bin/python3
"""Tables of the accuracy study's sweep files (bench/accuracy/*.yaml, docs/accuracy-vs-time.md).

Usage: accuracy_sweep_tables.py --results DIR [--label cpu-sweeps] [--doc docs/accuracy-vs-time.md]

DIR holds one results folder per sweep (convergence/, nu_sweep/, forehead_resolution/, knobs/, as
scripts/accuracy-sweeps writes them), each with its sweep_table.json. Replaces the text between
    <!-- BEGIN accuracy tables <label> -->  and  <!-- END accuracy tables <label> -->
in the document (appended when absent). Errors are against references inside the sweeps: the
cantilever's finest run (n = 8) and beam theory, the forehead's finest voxel size (1/3 mm), and
for the knobs the baseline run; the skin measure is the largest displacement difference over the
six skin probes of bench/accuracy/forehead_patch.yaml, relative to the largest displacement there.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_plots import g, pct, table, update_doc  # noqa: E402

# The cantilever of bench/accuracy/cantilever.yaml.
MU, T, L, RHO, G = 1.5e5, 2e-3, 10e-3, 1000.0, 9.81


def beam_theory_tip(nu):
    """Euler-Bernoulli plus Timoshenko shear for a uniform load (Cowper 1966, square section), as
    bench/accuracy_study.cpp's beam_theory_tip."""
    e = 2 * MU * (1 + nu)
    q, area, inertia = RHO * G * T * T, T * T, T**4 / 12
    ks = 10 * (1 + nu) / (12 + 11 * nu)
    return q * L**4 / (8 * e * inertia) + q * L**2 / (2 * ks * MU * area)


def load(results, name):
    path = os.path.join(results, name, "sweep_table.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)["runs"]


def fig(run, name):
    v = run["figures"].get(name)
    return math.nan if v is None else v


def steps(run):
    return int(fig(run, "steps_done")) if math.isfinite(fig(run, "steps_done")) else "–"


def run_seconds(runs):
    return sum(fig(r, "wall_time_s") for r in runs if math.isfinite(fig(r, "wall_time_s")))


def model_name(run):
    return os.path.basename(str(run["values"].get("model", ""))).removesuffix(".h5")


SWEEPS = ["convergence", "nu_sweep", "forehead_resolution", "knobs"]

SKIN = ["brow_left_uy", "brow_left_uz", "brow_centre_uz", "brow_right_uz", "mid_left_uy",
        "mid_left_uz", "middle_uz", "upper_left_uz"]


def skin_change(run, ref):
    """max |u - u_ref| / max |u_ref| over the skin probe columns."""
    if run["status"] != "completed" or ref is None:
        return math.nan
    diff = max(abs(fig(run, c) - fig(ref, c)) for c in SKIN)
    return diff / max(abs(fig(ref, c)) for c in SKIN)


def convergence_tables(runs):
    out = []
    for nu in ("0.3", "0.49"):
        rs = [r for r in runs if model_name(r).endswith("_nu" + nu)]
        if not rs:
            continue
        finest = max(rs, key=lambda r: int(model_name(r).split("_n")[1].split("_")[0]))
        ref = -fig(finest, "tip_uz")
        beam = beam_theory_tip(float(nu))
        body = []
        for r in rs:
            n = model_name(r).split("_n")[1].split("_")[0]
            tip = -fig(r, "tip_uz")
            body.append([n, steps(r), g(fig(r, "wall_time_s")), g(tip * 1e3, 5),
                         pct(abs(tip - ref) / ref) if r is not finest else "reference",
                         pct(tip / beam - 1), r["status"]])
        out.append(f"Cantilever, ν = {nu} (tip = −u_z of the end face's centre node at 0.05 s):\n\n" +
                   table(["n", "steps", "wall s", "tip mm", "vs n = 8", "vs beam theory", "status"],
                         body))
    return out


def nu_table(runs):
    body = []
    for r in runs:
        nu = float(model_name(r).split("_nu")[1])
        tip = -fig(r, "tip_uz")
        body.append([g(nu, 5), r["values"].get("hourglass.modulus"), steps(r),
                     g(fig(r, "wall_time_s")), g(tip * 1e3, 5), pct(tip / beam_theory_tip(nu) - 1),
                     r["status"]])
    return ("Near-incompressible bending, n = 2, κ = 0.075 (negative: stiffer than beam theory, "
            "locking):\n\n" + table(["ν", "modulus", "steps", "wall s", "tip mm", "vs beam theory",
                                     "status"], body))


def forehead_table(runs):
    ref = runs[-1]
    body = [[g(int(model_name(r).split("_")[-1].removesuffix("um")) / 1000) + " mm", steps(r),
             g(fig(r, "wall_time_s")), g(fig(r, "brow_centre_uz") * 1e3, 4),
             g(fig(r, "mid_left_uy") * 1e3, 4),
             pct(skin_change(r, ref)) if r is not ref else "reference", r["status"]]
            for r in runs]
    return ("Forehead patch, voxel size (skin at the six probes at 40 ms against the finest, 1/3 mm):"
            "\n\n" + table(["h", "steps", "wall s", "brow centre u_z mm", "mid left u_y mm",
                            "skin vs 1/3 mm", "status"], body)), ref


def knobs_table(runs, reference):
    base = runs[0]
    body = []
    for r in runs:
        values = ", ".join(f"{k} = {v}" for k, v in r["values"].items() if k != "title")
        name = r["values"].get("title") or values
        if r["values"].get("title") and values:
            name += f" ({values})"
        body.append([name.replace("[", "\\[").replace("]", "\\]"), steps(r),
                     g(fig(r, "wall_time_s")),
                     pct(skin_change(r, base)) if r is not base else "–",
                     pct(skin_change(r, reference)), r["status"]])
    return ("Knobs one at a time, h = 2/3 mm (skin at the six probes at the end of each run: 40 ms, the static row "
            "0.15 s):\n\n" +
            table(["run", "steps", "wall s", "vs baseline", "vs 1/3 mm", "status"], body))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", required=True)
    ap.add_argument("--label", default="cpu-sweeps")
    ap.add_argument("--doc", default="docs/accuracy-vs-time.md")
    ap.add_argument("--note", default="")
    a = ap.parse_args()
    parts = [a.note] if a.note else []
    seconds = {n: run_seconds(r) for n in SWEEPS if (r := load(a.results, n))}
    parts.append("Wall time of the runs (their `wall_time_s`, summed): " +
                 ", ".join(f"{n} {s:.0f} s" for n, s in seconds.items()) + ".")
    if runs := load(a.results, "convergence"):
        parts += convergence_tables(runs)
    if runs := load(a.results, "nu_sweep"):
        parts.append(nu_table(runs))
    reference = None
    if runs := load(a.results, "forehead_resolution"):
        text, reference = forehead_table(runs)
        parts.append(text)
    if runs := load(a.results, "knobs"):
        parts.append(knobs_table(runs, reference))
    update_doc(a.doc, a.label, "\n\n".join(parts))


if __name__ == "__main__":
    main()
