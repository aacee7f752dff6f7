#!/usr/bin/python3
"""Plots and tables of an accuracy-study CSV (bench/accuracy_study.cpp, docs/accuracy-vs-time.md).

Usage: accuracy_plots.py --csv docs/data/accuracy_cpu-quick.csv --label cpu-quick
                         [--doc docs/accuracy-vs-time.md] [--images docs/images/accuracy]

Writes <images>/<label>_{convergence,nu_sweep,forehead,knobs,effects}.png and replaces the text
between the markers
    <!-- BEGIN accuracy tables <label> -->  and  <!-- END accuracy tables <label> -->
in the document with the tables of this run (appended at the end when the markers are absent), so
the document's prose is kept. Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import csv
import math
import os
import re
import sys

# matplotlib is imported by main() only, so that scripts/accuracy_sweep_tables.py can use the
# table helpers here without it.
plt = None


def import_pyplot():
    global plt
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot

    plt = matplotlib.pyplot


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def read(path):
    header, rows = [], []
    lines = []
    with open(path, newline="") as f:
        for line in f:
            if line.startswith("#"):
                header.append(line[1:].strip())
            else:
                lines.append(line)
    for r in csv.DictReader(lines):
        for k in ("h_mm", "per_edge", "elements", "nodes", "nu", "dt_s", "safety_factor",
                  "mass_scaling", "time_scaling", "kappa", "steps", "sim_time_s", "wall_s",
                  "wall_per_step_us", "wall_per_sim_s", "error", "error_rms", "measured",
                  "hourglass_ratio"):
            r[k] = num(r.get(k))
        rows.append(r)
    return header, rows


def pareto(points):
    """Indices of the points (cost, error) that no other point beats in both (lower is better)."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        c, e = points[i]
        if math.isfinite(c) and math.isfinite(e) and e < best:
            front.append(i)
            best = e
    return front


def sel(rows, problem, knob=None, **eq):
    out = []
    for r in rows:
        if r["problem"] != problem or (knob is not None and r["knob"] != knob):
            continue
        if all(r.get(k) == v for k, v in eq.items()):
            out.append(r)
    return out


def g(v, digits=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return f"{v:.{digits}g}"


def pct(v):
    if not math.isfinite(v):
        return "–"
    return f"{100 * v:.3g} %"


def table(head, body):
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    # A "|" inside a cell would end it: escape it.
    out += ["| " + " | ".join(str(c).replace("|", "\\|") for c in row) + " |" for row in body]
    return "\n".join(out)


# ---- plots -------------------------------------------------------------------------------------
def decorate(ax, xlabel, ylabel, title, **legend):
    """Labels, title, legend (keyword arguments go to ax.legend) and a grid on both tick levels."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(**legend)
    ax.grid(True, which="both", alpha=0.3)


def save(fig, path):
    """Writes the figure to path (PNG, 110 dpi) and closes it."""
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_convergence(rows, path):
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for nu, mark, color in (("0.3", "o", "C0"), ("0.49", "s", "C1")):
        rs = [r for r in sel(rows, "convergence", "per_edge") if g(r["nu"]) == nu and r["status"] == "ok"]
        if not rs:
            continue
        h = [r["h_mm"] for r in rs]
        e = [r["error"] for r in rs]
        a.loglog(h, e, mark + "-", color=color, label=f"ν = {nu}")
        b.loglog([r["wall_s"] for r in rs], e, mark, color=color, label=f"ν = {nu}")
        # Pareto front of this ν (the two ν are different problems).
        pts = [(r["wall_s"], r["error"]) for r in rs]
        front = pareto(pts)
        b.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "-", color=color, lw=1)
        for i in front:
            b.annotate(f"n={int(rs[i]['per_edge'])}", pts[i], textcoords="offset points",
                       xytext=(4, 4), fontsize=7, color=color)
    hs = [r["h_mm"] for r in sel(rows, "convergence", "per_edge")]
    es = [r["error"] for r in sel(rows, "convergence", "per_edge") if r["error"] > 0]
    if hs and es:
        h0, h1 = min(hs), max(hs)
        e1 = max(es)
        a.loglog([h0, h1], [e1 * (h0 / h1) ** 2, e1], "k--", lw=1, label="slope h²")
    decorate(a, "voxel side h (mm)", "tip deflection error (vs Richardson)",
             "cantilever under its own weight: error vs h")
    decorate(b, "wall time to static answer (s)", "tip deflection error",
             "error vs wall time (lines: Pareto front per ν)")
    save(fig, path)


def plot_nu(rows, path):
    rs = sel(rows, "nu_sweep", "nu")
    if not rs:
        return False
    fig, ax = plt.subplots(figsize=(8, 4.5))
    groups = {}
    for r in rs:
        groups.setdefault((r["hourglass_modulus"], r["kappa"], int(r["per_edge"])), []).append(r)
    for (mod, kappa, n), grp in sorted(groups.items()):
        grp = [r for r in grp if r["status"] == "ok"]
        grp.sort(key=lambda r: r["nu"])
        x = [0.5 - r["nu"] for r in grp]
        y = [1 + r["error"] for r in grp]
        style = "-" if mod == "shear" else "--"
        ax.semilogx(x, y, style + "o", ms=4, label=f"{mod}, κ={g(kappa)}, n={n}")
    ax.axhline(1, color="k", lw=0.8)
    ax.invert_xaxis()
    decorate(ax, "0.5 − ν (log; right = nearly incompressible)", "tip deflection / beam theory",
             "near-incompressible bending: hourglass modulus M* = 2μ (shear) vs λ+2μ (p_wave)",
             fontsize=7, ncol=2)
    save(fig, path)
    return True


def plot_forehead(rows, path):
    rs = [r for r in sel(rows, "forehead", "h") if r["status"] == "ok"]
    if not rs:
        return False
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for prec, mark in (("double", "o"), ("float", "^")):
        grp = sorted([r for r in rs if r["precision"] == prec], key=lambda r: r["h_mm"])
        if not grp:
            continue
        a.loglog([r["h_mm"] for r in grp], [r["error"] for r in grp], mark + "-", label=f"{prec}, max")
        a.loglog([r["h_mm"] for r in grp], [r["error_rms"] for r in grp], mark + ":",
                 label=f"{prec}, rms")
    hs = [r["h_mm"] for r in rs]
    e1 = max(r["error"] for r in rs)
    a.loglog([min(hs), max(hs)], [e1 * (min(hs) / max(hs)) ** 2, e1], "k--", lw=1, label="slope h²")
    decorate(a, "voxel side h (mm)", "skin displacement error (relative)",
             "forehead patch, brow raise: error vs h", fontsize=8)
    # Error vs cost, with every forehead and knob point at default time scaling.
    pts, labels = [], []
    for r in rs + [r for r in sel(rows, "knobs") if r["error_measure"].startswith("skin_max_vs_ref")
                   and r["status"] == "ok"]:
        pts.append((r["wall_per_sim_s"], r["error"]))
        labels.append(f"h={g(r['h_mm'])}" if r["problem"] == "forehead" else f"{r['knob']}={r['value']}")
    b.loglog([p[0] for p in pts], [p[1] for p in pts], "o", ms=4, alpha=0.6, label="runs")
    front = pareto(pts)
    b.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "k-", lw=1.2, label="Pareto front")
    for i in front:
        b.annotate(labels[i], pts[i], textcoords="offset points", xytext=(4, 3), fontsize=7)
    decorate(b, "wall time per simulated second (s)", "skin displacement error (max, relative)",
             "error vs cost (Pareto front)", fontsize=8)
    save(fig, path)
    return True


def plot_knobs(rows, path):
    fig, axes = plt.subplots(2, 3, figsize=(14, 7.5))
    any_ = False

    def knob_xy(knob):
        ok = sorted([r for r in sel(rows, "knobs", knob) if r["status"] == "ok"],
                    key=lambda r: num(r["value"]))
        bad = [r for r in sel(rows, "knobs", knob) if r["status"] != "ok"]
        return ok, bad

    def mark_bad(ax, bad):
        for r in bad:
            ax.axvline(num(r["value"]), color="r", ls=":", lw=1)
            ax.text(num(r["value"]), 0.5, r["status"], color="r", rotation=90, fontsize=7,
                    transform=ax.get_xaxis_transform())

    def wall_axis(ax, rs, xs):
        ax2 = ax.twinx()
        ax2.plot(xs, [r["wall_s"] for r in rs], "x:", color="gray")
        ax2.set_ylabel("wall time (s), gray ×", color="gray")

    # 1. safety factor: the time-discretisation error alone (vs 0.3) and the wall time.
    ax = axes[0, 0]
    rs, bad = knob_xy("safety_factor_vs_0.3")
    if rs or bad:
        any_ = True
        xs = [num(r["value"]) for r in rs]
        ax.semilogy(xs, [r["error"] for r in rs], "o-", label="skin error vs safety 0.3")
        mark_bad(ax, bad)
        wall_axis(ax, rs, xs)
        ax.set_xlabel("safety factor (× h/c estimate)")
        ax.set_title("time-step safety factor", fontsize=9)
        ax.legend(fontsize=7, loc="upper left")
    # 2. mass scaling vs the unscaled run.
    ax = axes[0, 1]
    rs, bad = knob_xy("mass_scaling")
    if rs:
        any_ = True
        xs = [num(r["value"]) for r in rs]
        ax.loglog(xs, [r["error"] for r in rs], "o-", label="skin error vs unscaled")
        wall_axis(ax, rs, xs)
        ax.set_xlabel("mass scaling")
        ax.set_title("mass scaling (speed-up = √scaling in steps)", fontsize=9)
        ax.legend(fontsize=7, loc="upper left")
    # 3. quasi-static error against wall time: time scaling and mass scaling.
    ax = axes[0, 2]
    for knob, mark, name in (("time_scaling_vs_static", "o-", "time scaling"),
                             ("mass_scaling_vs_static", "s-", "mass scaling")):
        rs, _ = knob_xy(knob)
        if not rs:
            continue
        any_ = True
        ax.loglog([r["wall_s"] for r in rs], [r["error"] for r in rs], mark, label=name)
        for r in rs:
            ax.annotate(r["value"], (r["wall_s"], r["error"]), textcoords="offset points",
                        xytext=(3, 3), fontsize=7)
    ax.set_xlabel("wall time (s)")
    ax.set_title("distance from the quasi-static answer", fontsize=9)
    ax.legend(fontsize=7)
    # 4. κ on the forehead.
    ax = axes[1, 0]
    rs, _ = knob_xy("kappa")
    rd, _ = knob_xy("kappa_vs_default")
    if rs:
        any_ = True
        ax.semilogy([num(r["value"]) for r in rs], [r["error"] for r in rs], "o-",
                    label="skin error vs reference")
        ax.semilogy([num(r["value"]) for r in rd], [r["error"] for r in rd], "^-",
                    label="change vs κ = 0.075")
        ax.semilogy([num(r["value"]) for r in rs], [r["hourglass_ratio"] for r in rs], "s--",
                    label="hourglass / |strain| energy")
        ax.set_xlabel("hourglass κ")
        ax.set_title(f"hourglass κ (forehead, h = {g(rs[0]['h_mm'])} mm)", fontsize=9)
        ax.legend(fontsize=7)
    # 5. κ on the cantilever.
    ax = axes[1, 1]
    rs, bad = knob_xy("kappa_beam")
    if rs or bad:
        any_ = True
        ax.semilogy([num(r["value"]) for r in rs], [abs(r["error"]) for r in rs], "o-",
                    label="|tip / reference − 1|")
        ax.semilogy([num(r["value"]) for r in rs], [r["hourglass_ratio"] for r in rs], "s--",
                    label="hourglass / |strain| energy")
        mark_bad(ax, bad)
        ax.set_xlabel("hourglass κ")
        ax.set_title("hourglass κ (cantilever n = 2, ν = 0.49)", fontsize=9)
        ax.legend(fontsize=7)
    # 6. single switches against the reference.
    ax = axes[1, 2]
    picks = [("baseline", "default"), ("precision", "float"), ("kappa", "0"),
             ("hourglass_modulus", "p_wave"), ("sliding", "off(base_rigid)")]
    names, vals = [], []
    for knob, value in picks:
        m = [r for r in sel(rows, "knobs", knob) if r["value"] == value and r["status"] == "ok"]
        if m:
            names.append(f"{knob}\n{value}")
            vals.append(m[0]["error"])
    if names:
        any_ = True
        ax.bar(range(len(names)), vals)
        ax.set_xticks(range(len(names)))
        ax.set_xticklabels(names, fontsize=7)
        ax.set_yscale("log")
        ax.set_ylabel("skin error vs reference (max)")
        ax.set_title("switches (forehead)", fontsize=9)
    for ax in axes.flat:
        ax.grid(True, which="both", alpha=0.3)
    save(fig, path)
    return any_


def plot_effects(rows, path):
    rs = sel(rows, "effects", "effects")
    if not rs:
        return False
    fig, ax = plt.subplots(figsize=(8, 4))
    names = list(dict.fromkeys(r["value"] for r in rs))
    width = 0.38
    for k, prec in enumerate(("double", "float")):
        vals = []
        for n in names:
            m = [r for r in rs if r["value"] == n and r["precision"] == prec]
            vals.append(m[0]["wall_per_step_us"] if m else math.nan)
        ax.bar([i + (k - 0.5) * width for i in range(len(names))], vals, width, label=prec)
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels(names, fontsize=8)
    ax.set_ylabel("wall time per step (µs)")
    ax.set_title(f"cost of each effect (forehead patch, h = {g(rs[0]['h_mm'])} mm, "
                 f"{int(rs[0]['elements'])} elements)")
    ax.legend()
    ax.grid(True, axis="y", alpha=0.3)
    save(fig, path)
    return True


# ---- tables ------------------------------------------------------------------------------------
def para(out, text):
    """Appends a Markdown paragraph (text, then a blank line) to the list of lines out."""
    out += [text, ""]


def tables(header, rows, label, images_rel):
    out = [f"Run `{label}`. Provenance (from the CSV header):", ""]
    out += [f"- {h}" for h in header]
    out.append("")
    conv = sel(rows, "convergence", "per_edge")
    if conv:
        para(out, "**Convergence (cantilever under its own weight)**: tip deflection error against the "
                  "Richardson extrapolation of the three finest meshes; also against beam theory.")
        body = []
        for r in conv:
            body.append([g(r["nu"]), int(r["per_edge"]), g(r["h_mm"]), int(r["elements"]),
                         g(r["dt_s"]), int(r["steps"]), g(r["wall_s"]), g(r["wall_per_step_us"]),
                         pct(r["error"]), pct(r["error_rms"]), r["status"]])
        para(out, table(["ν", "n", "h (mm)", "elements", "Δt (s)", "steps", "wall (s)",
                         "µs/step", "error vs Richardson", "vs beam theory", "status"], body))
        for r in sel(rows, "convergence", "reference"):
            out.append(f"- ν = {g(r['nu'])}: reference tip deflection {g(r['measured'], 6)} m "
                       f"({r['value']}, observed order {g(r['error'])}); reference / beam theory − 1 "
                       f"= {pct(r['error_rms'])}.")
        for nu in ("0.3", "0.49"):
            rs = [r for r in conv if g(r["nu"]) == nu and r["status"] == "ok" and r["per_edge"] >= 2]
            if len(rs) >= 2:
                p = slope([r["h_mm"] for r in rs], [r["error"] for r in rs])
                out.append(f"- ν = {nu}: least-squares slope of log error vs log h over n ≥ 2: {g(p)}.")
        out.append("")
        para(out, f"![convergence]({images_rel}/{label}_convergence.png)")
    nus = sel(rows, "nu_sweep", "nu")
    if nus:
        para(out, "**Near-incompressible bending**: tip deflection / beam theory (1 = beam theory; "
                  "below 1 = too stiff, locking).")
        cols = sorted({(r["hourglass_modulus"], r["kappa"], int(r["per_edge"])) for r in nus})
        nuv = sorted({r["nu"] for r in nus})
        body = []
        for nu in nuv:
            row = [g(nu, 5)]
            for c in cols:
                m = [r for r in nus if r["nu"] == nu and (r["hourglass_modulus"], r["kappa"],
                                                          int(r["per_edge"])) == c]
                row.append(g(1 + m[0]["error"], 4) if m and m[0]["status"] == "ok"
                           else (m[0]["status"] if m else "–"))
            body.append(row)
        para(out, table(["ν"] + [f"{m}, κ {g(k)}, n {n}" for m, k, n in cols], body))
        w = [r for r in nus if r["status"] == "ok"]
        if w:
            slow = max(w, key=lambda r: r["wall_s"])
            para(out, f"Slowest point: ν = {g(slow['nu'], 5)} ({slow['hourglass_modulus']}, n = "
                      f"{int(slow['per_edge'])}): {int(slow['steps'])} steps, Δt = {g(slow['dt_s'])} s, "
                      f"{g(slow['wall_s'])} s wall.")
        para(out, f"![nu sweep]({images_rel}/{label}_nu_sweep.png)")
    fh = sel(rows, "forehead")
    if fh:
        para(out, "**Forehead patch, brow raise**: skin (top surface) displacement at 40 ms against "
                  "the reference, max and rms over 153 points, relative to the reference's largest "
                  "skin displacement.")
        body = []
        for r in fh:
            body.append([r["knob"], r["precision"], g(r["h_mm"]), int(r["elements"]), g(r["dt_s"]),
                         int(r["steps"]), g(r["wall_s"]), g(r["wall_per_step_us"]),
                         g(r["wall_per_sim_s"]), pct(r["error"]), pct(r["error_rms"]),
                         g(r["measured"]), r["status"]])
        para(out, table(["run", "precision", "h (mm)", "elements", "Δt (s)", "steps", "wall (s)",
                         "µs/step", "wall s per simulated s", "skin error max", "rms",
                         "largest skin displacement (m)", "status"], body))
        para(out, f"![forehead]({images_rel}/{label}_forehead.png)")
    kn = sel(rows, "knobs")
    if kn:
        para(out, "**Knobs one at a time** (forehead patch at the h of the `baseline` row unless "
                  "the knob says beam; error measure per row):")
        body = []
        for r in kn:
            body.append([r["knob"], r["value"], r["precision"], g(r["h_mm"]), g(r["dt_s"]),
                         int(r["steps"]), g(r["wall_s"]), g(r["wall_per_step_us"]),
                         pct(r["error"]) if r["knob"] != "kappa_beam" else g(r["error"]),
                         pct(r["error_rms"]), g(r["hourglass_ratio"]), r["error_measure"],
                         r["status"]])
        para(out, table(["knob", "value", "precision", "h (mm)", "Δt (s)", "steps", "wall (s)",
                         "µs/step", "error (max)", "rms", "hourglass/strain", "against", "status"],
                        body))
        para(out, f"![knobs]({images_rel}/{label}_knobs.png)")
    ef = sel(rows, "effects")
    if ef:
        para(out, "**Cost of each effect** (time per step, fixed number of steps):")
        body = [[r["value"], r["precision"], int(r["elements"]), int(r["steps"]),
                 g(r["wall_per_step_us"])] for r in ef]
        para(out, table(["effects", "precision", "elements", "steps", "µs/step"], body))
        para(out, f"![effects]({images_rel}/{label}_effects.png)")
    return "\n".join(out)


def slope(h, e):
    pts = [(math.log(a), math.log(b)) for a, b in zip(h, e) if a > 0 and b > 0]
    if len(pts) < 2:
        return math.nan
    n = len(pts)
    sx = sum(p[0] for p in pts)
    sy = sum(p[1] for p in pts)
    sxx = sum(p[0] ** 2 for p in pts)
    sxy = sum(p[0] * p[1] for p in pts)
    return (n * sxy - sx * sy) / (n * sxx - sx * sx)


def update_doc(doc, label, text):
    begin = f"<!-- BEGIN accuracy tables {label} -->"
    end = f"<!-- END accuracy tables {label} -->"
    body = open(doc).read() if os.path.exists(doc) else ""
    block = f"{begin}\n{text}\n{end}"
    pattern = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
    if pattern.search(body):
        body = pattern.sub(lambda _: block, body)
    else:
        body = body.rstrip("\n") + "\n\n" + block + "\n"
    with open(doc, "w") as f:
        f.write(body)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", required=True)
    ap.add_argument("--label", required=True)
    ap.add_argument("--doc", default="docs/accuracy-vs-time.md")
    ap.add_argument("--images", default="docs/images/accuracy")
    a = ap.parse_args()
    import_pyplot()
    header, rows = read(a.csv)
    os.makedirs(a.images, exist_ok=True)
    if sel(rows, "convergence", "per_edge"):
        plot_convergence(rows, os.path.join(a.images, f"{a.label}_convergence.png"))
    plot_nu(rows, os.path.join(a.images, f"{a.label}_nu_sweep.png"))
    plot_forehead(rows, os.path.join(a.images, f"{a.label}_forehead.png"))
    plot_knobs(rows, os.path.join(a.images, f"{a.label}_knobs.png"))
    plot_effects(rows, os.path.join(a.images, f"{a.label}_effects.png"))
    images_rel = os.path.relpath(a.images, os.path.dirname(os.path.abspath(a.doc)) or ".")
    update_doc(a.doc, a.label, tables(header, rows, a.label, images_rel))
    print(f"accuracy_plots: {len(rows)} rows; plots in {a.images}; tables in {a.doc} ({a.label})")


if __name__ == "__main__":
    sys.exit(main())
