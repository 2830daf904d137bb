"""NNMs of the Paris-like aircraft (seed paper, section 4.2): backbones of modes 10, 13, 19 and 20.

For each mode: the NNM branch from the linear mode up in energy (following the tongues the continuation
meets), the frequency change over the energy range, the MAC between the low- and high-energy NNM shapes,
the internal-resonance tongues found on the branch (ratio, energy, frequency), and figures like the
seed paper's Figs. 8-12.  The branches are appended to the model file so ``nnm-view`` opens with them.

    python examples/paris_fep.py                       # all four modes -> docs/img/paris_*.png, assets/paris.h5
    python examples/paris_fep.py --fast                # modes 13 and 20, coarse steps (about a minute)
    python examples/paris_fep.py --fast --out-dir /tmp/p --save-to /tmp/p/paris_branches.h5
    nnm-view assets/paris.h5

Paper mode numbers (Table 2) are mapped to this model's modes by their labels (first wing bending,
first horizontal-tail bending, first symmetric / anti-symmetric wing torsion) when the file has mode
labels, else taken as they are; ``--map 19=18`` overrides.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from pathlib import Path

# One BLAS thread: the dense solves here are small (2n + 1 = 1097 for 548 DOF) and a multi-threaded
# BLAS competing with other processes on a small machine makes them up to 100x slower.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import nnm_solver as nnm  # noqa: E402
from nnm_solver import analysis  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DPI = 100

#: what the paper says about each mode (seed paper, section 4.2)
PAPER = {
    10: dict(name="first wing bending", hz=8.1913, label=r"^wing bending 1\b",
             paper="weakly softening; MAC low/high 0.99"),
    13: dict(name="first tail bending", hz=21.2193, label=r"^(fin|horizontal tail|tail) bending 1\b",
             paper="frequency and shape practically unchanged"),
    19: dict(name="first (symmetric) wing torsion", hz=31.0847, label=r"^wing torsion \d+ \(symmetric\)",
             paper="marked softening; 3:1, 5:1 and 9:1 tongues; MAC low/high 0.98"),
    20: dict(name="second (anti-symmetric) wing torsion", hz=34.9151,
             label=r"^wing torsion \d+ \(anti-symmetric\)",
             paper="about 5 % frequency drop; a 9:1 tongue at higher energy; MAC low/high 0.97"),
}

#: continuation settings per paper mode: energy_max (J) and max points (full run, fast run)
SETTINGS = {
    10: dict(energy_max=3e4, fast_energy_max=3e4),
    13: dict(energy_max=3e4, fast_energy_max=3e4),
    19: dict(energy_max=3e4, fast_energy_max=3e4),
    20: dict(energy_max=3e4, fast_energy_max=3e4),
}
#: stop a softening branch once its frequency has dropped by this fraction (the NNM then heads for
#: the escape of the softening springs, which is not in the paper's range)
MAX_DROP = 0.15


def map_modes(model, wanted, overrides):
    """Model mode number (1-based) of each paper mode: the same number when its label is of the paper's
    kind (or there are no labels), else the mode of that kind nearest to the paper's frequency."""
    labels = model.mode_labels or []
    freqs, _ = model.linear_modes()
    out = {}
    for m in wanted:
        if m in overrides:
            out[m] = overrides[m]
            continue
        pat = re.compile(PAPER[m]["label"])
        if not labels or (m <= len(labels) and pat.search(labels[m - 1])):
            out[m] = m
            continue
        hits = [k + 1 for k, lab in enumerate(labels[:60]) if pat.search(lab)]
        out[m] = min(hits, key=lambda k: abs(freqs[k - 1] - PAPER[m]["hz"])) if hits else m
    return out


def stop_reason(points, drop, window=25):
    """Why to stop the continuation after ``points`` (a list of nnm.Point), or '' to go on: the
    frequency has dropped by more than ``drop`` below the linear value (the NNM then heads for the
    escape of the softening springs, outside the paper's range), or the continuation crawls (the last
    ``window`` points within 1 % of energy and 1e-5 of frequency: it is stuck at a singular point)."""
    f0, f = points[0].frequency_hz, points[-1].frequency_hz
    if f < (1 - drop) * f0:
        return f"stopped after a {100 * drop:.0f} % frequency drop"
    if len(points) > window:
        e = np.array([p.energy for p in points[-window:]])
        fr = np.array([p.frequency_hz for p in points[-window:]])
        if e.max() < 1.01 * e.min() and fr.max() - fr.min() < 1e-5 * fr.max():
            return f"stopped: the continuation crawled for {window} points (singular point)"
    return ""


def run_mode(model, mode, energy_max, spp, tol, max_points, floquet=True, log=print):
    t = time.perf_counter()
    it = nnm.iter_nnm(model, mode, energy_max=energy_max, steps_per_period=spp, tol=tol,
                      max_points=max_points, floquet=floquet)
    for _ in it:
        reason = stop_reason(it.points, MAX_DROP)
        if reason:
            break
    b = it.branch()
    if b.status == "stopped":
        b.message = reason
    dt = time.perf_counter() - t
    log(f"mode {mode}: {len(b)} points, E {b.energy[0]:.3g}..{b.energy.max():.3g} J, "
        f"f {b.frequency_hz[0]:.5g} -> {b.frequency_hz[-1]:.5g} Hz in {dt:.1f} s ({b.message})")
    return b, dt


def backbone_points(b, tongues, F):
    """Indices of the backbone: not inside a tongue, and no harmonic k >= 2 above 10 %."""
    ok = np.ones(len(b), dtype=bool)
    for t in tongues:
        ok[t.start + 1: t.end] = False
    sec = F[:, 2:].max(axis=1)
    ok &= np.nan_to_num(sec, nan=1.0) < 0.10   # NaN: the orbit could not be integrated again
    ok[0] = True
    return np.flatnonzero(ok)


def analyse(b, paper_mode, log=print):
    F = analysis.harmonic_fractions(b, 15)
    tongues = analysis.find_tongues(b, n=15, fractions=F)
    bb = backbone_points(b, tongues, F)
    lo, hi = int(bb[0]), int(bb[np.argmax(b.energy[bb])])
    f0 = b.frequency_hz[0]
    res = dict(paper_mode=paper_mode, mode=b.mode, label=(b.model.mode_labels or [""] * b.mode)[b.mode - 1],
               linear_hz=float(f0), points=len(b), energy_min=float(b.energy[lo]), energy_max=float(b.energy[hi]),
               f_high=float(b.frequency_hz[hi]), drop_pct=float(100 * (1 - b.frequency_hz[hi] / f0)),
               min_f_pct=float(100 * (1 - b.frequency_hz.min() / f0)),
               mac_low_high=float(analysis.mac_orbits(b, lo, b, hi)),
               mac_low_high_x0=float(analysis.mac_orbits(b, lo, b, hi, kind="x0")),
               low=lo, high=hi, stable_fraction=float(np.mean(b.stable)), status=b.status, message=b.message,
               backbone_min_f_pct=float(100 * (1 - b.frequency_hz[bb].min() / f0)),
               tongues=[dict(label=t.label, kind=t.kind, direction=t.direction, start=t.start, tip=t.tip, end=t.end,
                             energy_range=list(t.energy_range), tip_energy=t.tip_energy,
                             tip_frequency_hz=t.tip_frequency_hz, tip_fraction=t.tip_fraction,
                             complete=t.complete, closest_mode=t.mode, closest_mode_label=(
                                 (b.model.mode_labels or [""] * t.mode)[t.mode - 1] if t.mode else ""),
                             mac=t.mac) for t in tongues])
    log(f"  paper mode {paper_mode} -> model mode {b.mode} ({res['label']}): "
        f"{res['linear_hz']:.4f} Hz, drop {res['drop_pct']:.2f} % at {res['energy_max']:.3g} J, "
        f"MAC low/high {res['mac_low_high']:.4f}")
    for t in tongues:
        log(f"    {t.summary()}")
    return res, tongues, F


# ---------------------------------------------------------------------- figures
def _save(fig, path, dpi=DPI):
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def draw_shape(ax, model, x, title):
    """Top view of the display mesh coloured by the vertical displacement of the shape x."""
    mesh = model.mesh
    if mesh is None:
        ax.bar(np.arange(model.n), x)
        ax.set_title(title, fontsize=8)
        return
    u = mesh.displacements(x)
    V = mesh.vertices
    uz = u[:, 2]
    s = np.max(np.abs(uz)) or 1.0
    face_val = uz[mesh.faces].mean(axis=1) / s
    ax.tripcolor(V[:, 1], -V[:, 0], mesh.faces, facecolors=face_val, cmap="coolwarm", vmin=-1, vmax=1,
                 edgecolors="none")
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title(title, fontsize=8)


def fig_mode(b, res, tongues, path):
    fig = plt.figure(figsize=(10, 4.2))
    ax = fig.add_axes([0.07, 0.13, 0.5, 0.75])
    st = b.stable
    ax.plot(b.energy, b.frequency_hz, "-", color="C0", lw=1)
    ax.plot(b.energy[st], b.frequency_hz[st], "o", color="C0", ms=3, label="stable")
    if np.any(~st):
        ax.plot(b.energy[~st], b.frequency_hz[~st], "o", mfc="none", color="C3", ms=3.5, label="unstable")
    for lab, i in (("a", res["low"]), ("b", res["high"])):
        ax.plot(b.energy[i], b.frequency_hz[i], "s", color="k", ms=6)
        ax.annotate(f"({lab})", (b.energy[i], b.frequency_hz[i]), xytext=(5, 5), textcoords="offset points")
    for t in tongues:
        ax.annotate(f"{t.label}", (t.tip_energy, t.tip_frequency_hz), xytext=(-4, -14),
                    textcoords="offset points", fontsize=9, color="C3")
    ax.set_xscale("log")
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency (Hz)")
    f0 = res["linear_hz"]
    span = max(0.004 * f0, 1.15 * (f0 - b.frequency_hz.min()))
    ax.set_ylim(f0 - span, f0 + 0.25 * span)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    ax.set_title(f"Paper mode {res['paper_mode']} ({PAPER[res['paper_mode']]['name']}): model mode {b.mode}, "
                 f"{f0:.2f} Hz", fontsize=10)
    for k, (lab, i) in enumerate((("a", res["low"]), ("b", res["high"]))):
        axs = fig.add_axes([0.6 + 0.2 * k, 0.12, 0.19, 0.78])
        draw_shape(axs, b.model, analysis.orbit_shape(b, i),
                   f"({lab}) E = {b.energy[i]:.2g} J\nf = {b.frequency_hz[i]:.4f} Hz")
    fig.text(0.8, 0.03, f"MAC (a)-(b) = {res['mac_low_high']:.3f}; colour: vertical displacement", ha="center",
             fontsize=8)
    return _save(fig, path)


def fig_overview(results, branches, path):
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for j, (m, b) in enumerate(branches.items()):
        r = results[m]
        ax.plot(b.energy, 100 * (b.frequency_hz / r["linear_hz"] - 1), ".-", ms=2.5, lw=1, color=f"C{j}",
                label=f"paper mode {m} ({PAPER[m]['name']}, {r['linear_hz']:.2f} Hz)")
    ax.set_xscale("log")
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency change (%)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="center left")
    ax.set_title("Paris-like aircraft: NNM frequencies against energy", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def _watch_points(b, t):
    """Two DOFs to show along a tongue, like the seed's Fig. 12: the tank attachment that deforms most
    and the DOF that carries the resonant harmonic most (mesh vertex if there is a mesh)."""
    model = b.model
    B = model.spring_matrix
    C = analysis.harmonic_coefficients(b, t.tip, t.order)
    d = np.abs(B @ C[1].real) + np.abs(B @ C[1].imag)
    s = int(np.argmax(d))
    spring = model.springs[s]
    lab = (model.dof_labels or [f"DOF {spring.dof}"] * model.n)[spring.dof]
    rows = [("attachment " + lab, np.eye(model.n)[spring.dof])]
    if model.mesh is not None:
        Dz = model.mesh.displacement_map[2::3].astype(float)
        amp = np.abs(Dz @ C[t.order].real) + np.abs(Dz @ C[t.order].imag)
        v = int(np.argmax(amp))
        parts = model.mesh.part_names
        face = np.flatnonzero((model.mesh.faces == v).any(axis=1))
        pname = parts[int(model.mesh.part_ids[face[0]])] if len(face) and model.mesh.part_ids is not None else ""
        xyz = model.mesh.vertices[v]
        rows.append((f"{pname} point ({xyz[0]:.1f}, {xyz[1]:.1f}, {xyz[2]:.1f}) m, vertical", Dz[v]))
    return rows


def fig_tongue(b, t, path, n_harm=None):
    n_harm = n_harm or max(9, t.order + 2)
    picks = {"a": t.start, "b": t.middle(b), "c": t.tip}
    watch = _watch_points(b, t)
    fig = plt.figure(figsize=(10, 7.6))
    gs = fig.add_gridspec(4, 3, height_ratios=[1.1, 1, 1, 1])
    ax = fig.add_subplot(gs[0, :])
    i0, i1 = max(t.start - 6, 0), min(t.end + 4, len(b) - 1)
    seg = slice(i0, i1 + 1)
    ax.plot(b.energy[seg], b.frequency_hz[seg], ".-", color="C0", ms=3, lw=1)
    for lab, i in picks.items():
        ax.plot(b.energy[i], b.frequency_hz[i], "s", color="k", ms=5)
        ax.annotate(f"({lab})", (b.energy[i], b.frequency_hz[i]), xytext=(5, 4), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency (Hz)")
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title(f"{t.label} tongue of model mode {b.mode}: close-up of the FEP", fontsize=10)
    for col, (lab, i) in enumerate(picks.items()):
        axs = fig.add_subplot(gs[1, col])
        draw_shape(axs, b.model, analysis.orbit_shape(b, i),
                   f"({lab}) E = {b.energy[i]:.3g} J, f = {b.frequency_hz[i]:.4f} Hz")
        try:
            tt, x = b.motion(i, analysis.orbit_samples(b))
        except RuntimeError:
            continue
        T = b.period[i]
        C = np.abs(analysis.harmonic_coefficients(b, i, n_harm))
        ax = fig.add_subplot(gs[2, col])
        ax2 = fig.add_subplot(gs[3, col])
        kk = np.arange(1, n_harm + 1)
        for j, ((name, w), ls, c) in enumerate(zip(watch, ("-", "--"), ("0.55", "k"))):
            ax.plot(tt / T, 1e3 * (x @ w), ls, color=c, label=name[:40])
            amp = np.abs(analysis.harmonic_coefficients(b, i, n_harm) @ w)
            ax2.bar(kk + (j - 0.5) * 0.4, 1e3 * amp[1:], 0.4, color=c)
        ax.set_xlabel("t / T", fontsize=8)
        ax.set_ylabel("displacement (mm)", fontsize=8)
        ax.grid(alpha=0.3)
        if col == 0:
            ax.legend(fontsize=6, loc="lower left")
        hc = analysis.dominant_harmonic(b, i)
        ax2.set_title(f"harmonic {t.order}: {100 * hc.fractions[t.order]:.0f} % of the amplitude", fontsize=8)
        ax2.set_xticks(kk)
        ax2.set_xlabel("harmonic", fontsize=8)
        ax2.set_ylabel("Fourier amplitude (mm)", fontsize=8)
        del C
    fig.tight_layout()
    return _save(fig, path, dpi=90)


# ---------------------------------------------------------------------- saving
#: the model file must stay below this size (bytes) with the branches added
MAX_FILE_BYTES = 25e6


def keep_points(b, tongues, n_keep):
    """At most ``n_keep`` indices of branch b spread along the curve (log energy, frequency), always
    keeping the first and last points, the folds, and the entries, tips and exits of the tongues."""
    N = len(b)
    if N <= n_keep:
        return np.arange(N)
    must = {0, N - 1} | {e["index"] for e in b.events if e["kind"] == "fold"}
    for t in tongues:
        must |= {t.start, t.tip, t.end, t.middle(b)}
    x = np.log10(np.maximum(b.energy, 1e-300))
    y = b.frequency_hz / b.frequency_hz[0]
    d = np.r_[0, np.cumsum(np.hypot(np.diff(x) / max(np.ptp(x), 1e-12), np.diff(y) / max(np.ptp(y), 1e-12)))]
    rest = max(n_keep - len(must), 2)
    spread = {int(np.argmin(np.abs(d - s))) for s in np.linspace(0, d[-1], rest)}
    return np.array(sorted(must | spread))


def thin_for_file(path, branches, tongues, model_path=None, log=print):
    """Branches thinned so that the file at ``path`` stays below MAX_FILE_BYTES (a new file starts with
    a copy of the model, about the size of ``model_path``)."""
    path = Path(path)
    base = path.stat().st_size if path.exists() else (Path(model_path).stat().st_size if model_path else 0)
    if not branches:
        return []
    n = branches[0].model.n
    per_point = 8 * (2 * n) + 16 * (2 * n) + 32          # x0, v0, floquet (complex), scalars
    budget = 0.9 * (MAX_FILE_BYTES - base) - 20e3 * len(branches)
    total = sum(len(b) for b in branches)
    if total * per_point <= budget:
        return branches
    n_keep = max(int(budget / per_point / len(branches)), 20)
    out = []
    for b, t in zip(branches, tongues):
        idx = keep_points(b, t, n_keep)
        c = b.subset(idx)
        c.message = f"{b.message} [saved {len(idx)} of {len(b)} points to keep the file small]"
        out.append(c)
    log(f"  thinned to at most ~{n_keep} points per branch for {path} (limit {MAX_FILE_BYTES / 1e6:.0f} MB)")
    return out


def save_branches(path, branches, log=print):
    path = Path(path)
    existing = set()
    if path.exists():
        try:
            existing = {b.name for b in nnm.load_branches(path)}
        except Exception as exc:  # a damaged file is reported, not overwritten
            log(f"cannot read the branches of {path}: {exc}; not saving")
            return []
    saved = []
    for b in branches:
        if b.name in existing:
            log(f"  {path} already holds a branch named {b.name!r}: kept as it is (delete the file's copy "
                f"or use --save-to to write elsewhere)")
            continue
        saved.append(nnm.save_branch(path, b))
    if path.exists():
        log(f"  {path}: {path.stat().st_size / 1e6:.1f} MB")
    return saved


# ---------------------------------------------------------------------- main
def parse_map(items):
    out = {}
    for it in items or []:
        a, b = it.split("=")
        out[int(a)] = int(b)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", default=str(ROOT / "assets" / "paris.h5"), help="nnm file with the aircraft model")
    p.add_argument("--fast", action="store_true", help="modes 13 and 20 only, coarse time steps")
    p.add_argument("--modes", default=None, help="paper modes to compute, e.g. 10,13,19,20")
    p.add_argument("--map", nargs="*", help="paper=model mode overrides, e.g. 19=18")
    p.add_argument("--steps", type=int, default=None, help="Newmark steps per period (default 100, fast 40)")
    p.add_argument("--energy-max", type=float, default=None, help="energy_max (J) for every mode")
    p.add_argument("--out-dir", default=str(ROOT / "docs" / "img"), help="folder of the PNG figures")
    p.add_argument("--save-to", default=None, help="nnm file the branches are appended to (default: --model)")
    p.add_argument("--no-save", action="store_true", help="do not save the branches")
    p.add_argument("--from-file", action="store_true",
                   help="no computation: analyse and draw the branches already saved in --model")
    p.add_argument("--summary", default=None, help="JSON file with the numbers (default: <out-dir>/paris_summary.json "
                   "is not written unless given)")
    args = p.parse_args(argv)
    t_all = time.perf_counter()
    model_path = Path(args.model)
    if not model_path.exists():
        print(f"error: {model_path} does not exist (build it with examples/build_paris.py)", file=sys.stderr)
        return 2
    model = nnm.load_model(model_path)
    wanted = [int(m) for m in args.modes.split(",")] if args.modes else ([13, 20] if args.fast else [10, 13, 19, 20])
    mapping = map_modes(model, wanted, parse_map(args.map))
    spp = args.steps or (40 if args.fast else 100)
    tol = 1e-5 if args.fast else 1e-6
    max_points = 30 if args.fast else 150
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    freqs, _ = model.linear_modes()
    print(f"{model_path}: {model.n} DOF, {len(model.springs)} cubic springs; {spp} steps/period, tol {tol:g}")
    branches, results, tongues_all, times = {}, {}, {}, {}
    saved = {b.name: b for b in nnm.load_branches(model_path, model)} if args.from_file else {}
    # the unaffected tail mode last, over the energy range the wing modes reached
    order = [m for m in wanted if m != 13] + [m for m in wanted if m == 13]
    for m in order:
        mm = mapping[m]
        lab = (model.mode_labels or [""] * model.n)[mm - 1]
        print(f"paper mode {m} ({PAPER[m]['name']}) -> model mode {mm}: {freqs[mm - 1]:.4f} Hz {lab}")
        emax = args.energy_max or SETTINGS[m]["fast_energy_max" if args.fast else "energy_max"]
        if m == 13 and branches and not args.energy_max:
            emax = max(b.energy.max() for b in branches.values())
        name = f"mode{mm} (paper mode {m})" if mm != m else f"mode{mm}"
        if args.from_file:
            b = saved.get(name)
            if b is None:
                print(f"error: {model_path} has no branch named {name!r}", file=sys.stderr)
                return 2
            dt = float("nan")
        else:
            b, dt = run_mode(model, mm, emax, spp, tol, 120 if m == 13 else max_points,
                             floquet=not args.fast)
        b.name = name
        times[m] = dt
        res, tongues, _ = analyse(b, m)
        res["seconds"] = dt
        res["steps_per_period"] = spp
        branches[m], results[m], tongues_all[m] = b, res, tongues
    branches = {m: branches[m] for m in wanted}
    results = {m: results[m] for m in wanted}
    figs = [fig_overview(results, branches, out_dir / "paris_fep_overview.png")] if len(branches) > 1 else []
    for m, b in branches.items():
        figs.append(fig_mode(b, results[m], tongues_all[m], out_dir / f"paris_fep_mode{m}.png"))
        folds = [t for t in tongues_all[m] if t.kind == "fold"]
        if folds and not args.fast:   # the clearest tongue of the mode, like the seed's Fig. 12
            t = max(folds, key=lambda t: t.tip_fraction)
            figs.append(fig_tongue(b, t, out_dir / f"paris_tongue_mode{m}_{t.label.replace(':', 'to')}.png"))
    if not args.no_save and not args.from_file:
        target = Path(args.save_to or model_path)
        save_branches(target, thin_for_file(target, list(branches.values()), list(tongues_all.values()),
                                            model_path))
    total = time.perf_counter() - t_all
    summary = dict(model=str(model_path), fast=bool(args.fast), steps_per_period=spp, tol=tol,
                   total_seconds=total, modes={str(m): r for m, r in results.items()})
    if args.summary:
        Path(args.summary).write_text(json.dumps(summary, indent=1, default=float))
    print("\n| paper mode | model mode | linear Hz | energy range (J) | frequency change | MAC low/high | tongues |")
    print("|---|---|---|---|---|---|---|")
    for m, r in results.items():
        tg = "; ".join(f"{t['label']} at {t['tip_energy']:.3g} J, {t['tip_frequency_hz']:.4f} Hz"
                       for t in r["tongues"]) or "none"
        print(f"| {m} | {r['mode']} | {r['linear_hz']:.4f} | {r['energy_min']:.2g} .. {r['energy_max']:.2g} | "
              f"-{r['drop_pct']:.2f} % | {r['mac_low_high']:.3f} | {tg} |")
    for f in figs:
        print(f"wrote {f} ({f.stat().st_size // 1024} kB)")
    print(f"total {total:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
