"""Internal-resonance tongues of the 2-DOF benchmark (Kerschen, Peeters, Golinval & Vakakis, 2009).

    x1'' + (2 x1 - x2) + 0.5 x1^3 = 0,     x2'' + (2 x2 - x1) = 0

Computes the NNM1 and NNM2 backbones, follows NNM1 through its 3:1 and 5:1 tongues (tongues="follow-all": the
default follows tongues up to 3:1 and jumps higher orders) (shooting; in the full
run also by harmonic balance, as a check), draws the frequency-energy plots and the motions at the beginning, middle and end of
the 3:1 tongue (time series, configuration space, Fourier coefficients), and saves everything, with a
small 3D scene (two masses, springs, walls), to an nnm file that ``nnm-view`` animates.

    python examples/two_dof_tongues.py                 # full run, ~1 min: ./two_dof_figures/*.png, ./two_dof.h5
    python examples/two_dof_tongues.py --fast          # a few seconds: coarser steps, no HB check; its own
                                                       # ./two_dof_figures_fast/, ./two_dof_fast.h5
    python examples/two_dof_tongues.py --fast --out-dir /tmp/x --assets /tmp/x/two_dof.h5
    python examples/two_dof_tongues.py --update-shipped   # maintainers: docs/img/two_dof_*.png, assets/two_dof.h5
    nnm-view two_dof.h5
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # small dense solves: one BLAS thread is fastest on a shared machine

import numpy as np  # noqa: E402

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import nnm_solver as nnm  # noqa: E402
from nnm_solver import analysis  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DPI = 100

# ---------------------------------------------------------------------- the model and its 3D scene
PARTS = ["ground", "mass 1", "mass 2", "linear springs", "cubic spring"]


def _box(lo, hi):
    """Vertices (8, 3) and triangles (12, 3) of the axis-aligned box lo..hi."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    v = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    # vertex index = 4 ix + 2 iy + iz
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],      # x = lo, x = hi
                  [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],      # y = lo, y = hi
                  [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])     # z = lo, z = hi
    return v, f


def _segment(p, q, w):
    """Thin square bar of width w from p to q (in the x-z plane): vertices (8, 3), triangles (12, 3)."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    d = q - p
    d /= np.linalg.norm(d)
    n1 = np.cross(d, [0.0, 1.0, 0.0])
    n1 /= np.linalg.norm(n1)
    n2 = np.cross(d, n1)
    v, f = _box([0, -0.5, -0.5], [1, 0.5, 0.5])
    pts = p + np.outer(v[:, 0], q - p) + w * (np.outer(v[:, 1], n1) + np.outer(v[:, 2], n2))
    return pts, f


class SceneBuilder:
    def __init__(self, n_dof):
        self.n = n_dof
        self.vertices, self.faces, self.parts, self.rows = [], [], [], []

    def add(self, verts, faces, part, weights):
        """weights(vertex) -> (n,) displacement of the vertex along x per unit of each DOF."""
        base = sum(len(v) for v in self.vertices)
        self.vertices.append(verts)
        self.faces.append(faces + base)
        self.parts.append(np.full(len(faces), PARTS.index(part)))
        for p in verts:
            w = np.zeros((3, self.n))
            w[0] = weights(p)
            self.rows.append(w)

    def spring(self, x_a, x_b, y, z, part, w_a, w_b, coils=6, amp=0.18, width=0.045):
        """Zig-zag spring from x_a (attached to w_a) to x_b (attached to w_b); its points move by the
        linear interpolation of the two ends' displacements, so it stretches with the motion."""
        xs = np.linspace(x_a, x_b, 2 * coils + 1)
        zs = z + amp * np.array([0.0] + [(-1) ** k for k in range(2 * coils - 1)] + [0.0])
        pts = [np.array([x, y, zz]) for x, zz in zip(xs, zs)]

        def weights(p):
            s = min(max((p[0] - x_a) / (x_b - x_a), 0.0), 1.0)
            return (1 - s) * w_a + s * w_b

        for a, b in zip(pts[:-1], pts[1:]):
            v, f = _segment(a, b, width)
            self.add(v, f, part, weights)

    def mesh(self):
        return nnm.DisplayMesh(np.vstack(self.vertices), np.vstack(self.faces),
                               np.vstack(self.rows).reshape(-1, self.n), np.concatenate(self.parts), PARTS)


def two_dof_model():
    """The benchmark with a scene: walls at x = 0 and 6 m, masses (0.8 m cubes) at x = 2 and 4 m moving
    along x; springs wall-mass 1 (k = 1, plus the cubic 0.5 x1^3 beside it), mass 1-mass 2 (k = 1),
    mass 2-wall (k = 1)."""
    M = np.eye(2)
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    s = SceneBuilder(2)
    zero, e1, e2 = np.zeros(2), np.array([1.0, 0.0]), np.array([0.0, 1.0])
    still = lambda p: zero  # noqa: E731
    for lo, hi in (([-0.6, -0.7, -0.2], [6.6, 0.7, 0.0]),      # floor
                   ([-0.25, -0.7, 0.0], [0.0, 0.7, 1.4]),      # left wall
                   ([6.0, -0.7, 0.0], [6.25, 0.7, 1.4])):      # right wall
        s.add(*_box(lo, hi), "ground", still)
    s.add(*_box([1.6, -0.4, 0.05], [2.4, 0.4, 0.85]), "mass 1", lambda p: e1)
    s.add(*_box([3.6, -0.4, 0.05], [4.4, 0.4, 0.85]), "mass 2", lambda p: e2)
    s.spring(0.0, 1.6, -0.2, 0.45, "linear springs", zero, e1)
    s.spring(0.0, 1.6, 0.2, 0.45, "cubic spring", zero, e1, coils=4, amp=0.12, width=0.07)
    s.spring(2.4, 3.6, 0.0, 0.45, "linear springs", e1, e2)
    s.spring(4.4, 6.0, 0.0, 0.45, "linear springs", e2, zero)
    return nnm.Model(M, K, [nnm.CubicSpring(dof=0, k3=0.5)], dof_labels=["x1 (mass 1)", "x2 (mass 2)"],
                     mode_labels=["in-phase mode (NNM1)", "out-of-phase mode (NNM2)"], mesh=s.mesh(),
                     name="2-DOF benchmark (Kerschen et al. 2009)",
                     info=dict(equations="x1'' + 2 x1 - x2 + 0.5 x1^3 = 0; x2'' + 2 x2 - x1 = 0",
                               builder="examples/two_dof_tongues.py"))


# ---------------------------------------------------------------------- computation
def compute(model, fast, log=print):
    # --fast: coarser time steps, the same tolerance (with tol = 1e-5 a run stepped from one side of the 5:1
    # tongue to the other near its mouth, where the two sides and the backbone run close together)
    spp, tol = (80, 1e-6) if fast else (200, 1e-6)
    out, times = {}, {}
    t = time.perf_counter()
    out["nnm1"] = nnm.continue_nnm(model, 1, energy_max=3e5, steps_per_period=spp, tol=tol, tongues="follow-all")
    times["nnm1"] = time.perf_counter() - t
    log(f"NNM1 (shooting, {spp} steps/period): {len(out['nnm1'])} points in {times['nnm1']:.1f} s; "
        f"{out['nnm1'].message}")
    t = time.perf_counter()
    # NNM2's period changes fast with energy and the continuation limits the period change per step:
    # many small steps
    out["nnm2"] = nnm.continue_nnm(model, 2, energy_max=3e5, steps_per_period=spp, tol=tol, max_points=1200,
                                   tongues="follow-all")
    times["nnm2"] = time.perf_counter() - t
    log(f"NNM2 (shooting): {len(out['nnm2'])} points in {times['nnm2']:.1f} s; {out['nnm2'].message}")
    out["nnm1"].name, out["nnm2"].name = "NNM1", "NNM2"
    if not fast:
        # the same family by harmonic balance (odd harmonics up to 15, Floquet multipliers by Hill's
        # method): an independent check of the tongues
        t = time.perf_counter()
        H = 15
        out["nnm1_hb"] = nnm.hb.continue_nnm_hb(model, 1, energy_max=3e5, harmonics=H, max_points=600,
                                                tongues="follow-all")
        times["nnm1_hb"] = time.perf_counter() - t
        out["nnm1_hb"].name = f"NNM1 harmonic balance H{H}"
        log(f"NNM1 (harmonic balance, odd harmonics <= {H}): {len(out['nnm1_hb'])} points in "
            f"{times['nnm1_hb']:.1f} s; {out['nnm1_hb'].message}")
    return out, times


def tongue_table(branches, log=print):
    tongues = {}
    for key in [k for k in ("nnm1", "nnm1_hb") if k in branches]:
        b = branches[key]
        tongues[key] = analysis.find_tongues(b, n=15)
        for tg in tongues[key]:
            log(f"  {b.name}: {tg.summary()}")
    return tongues


# ---------------------------------------------------------------------- figures
def _save(fig, path):
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def fig_fep(branches, tongues, path):
    b1, b2, bh = branches["nnm1"], branches["nnm2"], branches.get("nnm1_hb")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3))
    ax = axes[0]
    nnm.plot_fep([b1, b2], ax=ax)
    ax.set_title("NNM1 and NNM2 backbones")
    ax.set_ylim(0.14, 0.9)
    ax = axes[1]
    if bh is not None:
        ax.plot(bh.energy, bh.frequency_hz, "-", color="0.7", lw=2.5, label=bh.name)
    ax.plot(b1.energy, b1.frequency_hz, ".-", color="C0", ms=2.5, lw=0.8, label="NNM1 (shooting)")
    E2 = b2.energy
    for k, ls in ((3, "--"), (5, ":")):
        ax.plot(E2, b2.frequency_hz / k, ls, color="C1", lw=1.4, label=f"NNM2 frequency / {k}")
    for tg in tongues["nnm1"]:
        ax.plot(tg.tip_energy, tg.tip_frequency_hz, "v", color="k", ms=6)
        ax.annotate(f"{tg.label} tongue", (tg.tip_energy, tg.tip_frequency_hz), xytext=(0, 8),
                    textcoords="offset points", ha="center", fontsize=9)
    ax.set_xscale("log")
    ax.set_xlim(1.0, b1.energy.max() * 1.5)
    ax.set_ylim(0.2, 0.228)
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency (Hz)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    ax.set_title("NNM1 close-up: tongues end on NNM2 / 3 and NNM2 / 5")
    fig.tight_layout()
    return _save(fig, path)


def fig_tongue(branch, tg, picks, path):
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    i0, i1 = max(tg.start - 8, 0), min(tg.end + 6, len(branch) - 1)
    seg = slice(i0, i1 + 1)
    ax.plot(branch.energy[seg], branch.frequency_hz[seg], "-", color="C0", lw=1)
    st = branch.stable[seg]
    ax.plot(branch.energy[seg][st], branch.frequency_hz[seg][st], "o", color="C0", ms=3.5, label="stable")
    ax.plot(branch.energy[seg][~st], branch.frequency_hz[seg][~st], "o", mfc="none", color="C3", ms=4,
            label="unstable")
    for lab, i in picks.items():
        ax.plot(branch.energy[i], branch.frequency_hz[i], "s", color="k", ms=6)
        # (c), the tip, is the leftmost point and (b) often lies just beside it: (c) is written below-left
        below = lab == "c"
        ax.annotate(f"({lab})", (branch.energy[i], branch.frequency_hz[i]), xytext=(-4, -14) if below else (6, 4),
                    textcoords="offset points", fontsize=10, ha="right" if below else "left")
    ax.set_xscale("log")
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency (Hz)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{tg.label} tongue of NNM1: (a) beginning, (b) middle, (c) end")
    fig.tight_layout()
    return _save(fig, path)


def fig_motions(branch, picks, path, n_harm=9):
    fig, axes = plt.subplots(3, len(picks), figsize=(11, 8))
    for col, (lab, i) in enumerate(picks.items()):
        t, x = branch.motion(i, 256)
        T = branch.period[i]
        amps = np.abs(analysis.harmonic_coefficients(branch, i, n_harm))
        hc = analysis.dominant_harmonic(branch, i)
        ax = axes[0, col]
        ax.plot(t / T, x[:, 0], "-", color="C3", label="x1")
        ax.plot(t / T, x[:, 1], "--", color="k", label="x2")
        ax.set_xlabel("t / T")
        ax.set_ylabel("displacement (m)")
        ax.set_title(f"({lab}) E = {branch.energy[i]:.4g} J, f = {branch.frequency_hz[i]:.4f} Hz\n"
                     f"harmonic 1: {100 * hc.fractions[1]:.0f} %, harmonic 3: {100 * hc.fractions[3]:.0f} %",
                     fontsize=9)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        ax = axes[1, col]
        xc = np.vstack([x, x[:1]])
        ax.plot(xc[:, 0], xc[:, 1], "-", color="C0")
        ax.plot(x[0, 0], x[0, 1], "o", color="C0", ms=4)
        ax.set_xlabel("x1 (m)")
        ax.set_ylabel("x2 (m)")
        ax.set_title("configuration space", fontsize=9)
        ax.grid(alpha=0.3)
        ax = axes[2, col]
        k = np.arange(1, n_harm + 1)
        ax.bar(k - 0.2, amps[1:, 0], 0.4, color="0.6", label="x1")
        ax.bar(k + 0.2, amps[1:, 1], 0.4, color="k", label="x2")
        ax.set_xticks(k)
        ax.set_xlabel("harmonic")
        ax.set_ylabel("Fourier amplitude (m)")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def fig_shares(branch, fractions, tongues, path):
    fig, ax = plt.subplots(figsize=(8, 3.8))
    idx = np.arange(len(branch))
    for k, c in ((1, "C0"), (3, "C3"), (5, "C2")):
        ax.plot(idx, 100 * fractions[:, k], "-", color=c, label=f"harmonic {k}")
    ax.set_xlabel("point along the branch (continuation order)")
    ax.set_ylabel("share of the amplitude (%)")
    ax.set_ylim(0, 100)
    for tg in tongues:
        ax.axvspan(tg.start, tg.end, color="0.9")
        ax.text(tg.tip, 96, f"{tg.label} tongue", ha="center", va="top", fontsize=9)
    ax2 = ax.twinx()
    ax2.semilogy(idx, branch.energy, ":", color="0.4", lw=1)
    ax2.set_ylabel("energy (J), dotted")
    ax.legend(fontsize=8, loc="center left")
    ax.set_title(f"Harmonic content along {branch.name}", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


# ---------------------------------------------------------------------- main
#: the shipped file and figures, written only with --update-shipped
SHIPPED, SHIPPED_FIGURES = ROOT / "assets" / "two_dof.h5", ROOT / "docs" / "img"


def default_outputs(args):
    """(figure folder, nnm file) of a run: --out-dir / --assets if given, else ./two_dof_figures and
    ./two_dof.h5 in the current folder (a --fast run: ./two_dof_figures_fast and ./two_dof_fast.h5, so that it
    never replaces the full run's results); the shipped docs/img and assets/two_dof.h5 only with --update-shipped."""
    suffix = "_fast" if getattr(args, "fast", False) and not args.update_shipped else ""
    out_dir = args.out_dir or str(SHIPPED_FIGURES if args.update_shipped else Path(f"two_dof_figures{suffix}"))
    assets = args.assets or str(SHIPPED if args.update_shipped else Path(f"two_dof{suffix}.h5"))
    return out_dir, assets


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fast", action="store_true", help="coarser steps, fewer points (a few seconds)")
    p.add_argument("--out-dir", default=None, help="folder of the PNG figures (default ./two_dof_figures, "
                   "./two_dof_figures_fast with --fast; docs/img with --update-shipped)")
    p.add_argument("--assets", default=None, help="nnm file written (replaced; default ./two_dof.h5, "
                   "./two_dof_fast.h5 with --fast; the shipped assets/two_dof.h5 with --update-shipped)")
    p.add_argument("--update-shipped", action="store_true", help="maintainers: write the shipped assets/two_dof.h5 "
                   "and docs/img/two_dof_*.png (without it they are never written)")
    p.add_argument("--summary", default=None, help="optional JSON file with the numbers shown")
    args = p.parse_args(argv)
    args.out_dir, args.assets = default_outputs(args)
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t_all = time.perf_counter()

    model = two_dof_model()
    branches, times = compute(model, args.fast)
    tongues = tongue_table(branches)
    b1 = branches["nnm1"]
    t31 = next((t for t in tongues["nnm1"] if t.label == "3:1"), None)
    if t31 is None:
        print("error: the 3:1 tongue was not found on NNM1", file=sys.stderr)
        return 1
    picks = {"a": t31.start, "b": t31.middle(b1), "c": t31.tip}
    for lab, i in picks.items():
        print(f"  ({lab}) point {i}: E = {b1.energy[i]:.4g} J, f = {b1.frequency_hz[i]:.5f} Hz: "
              f"{analysis.describe_orbit(b1, i)}")
    fractions = analysis.harmonic_fractions(b1, 15)

    figs = [fig_fep(branches, tongues, out_dir / "two_dof_fep.png"),
            fig_tongue(b1, t31, picks, out_dir / "two_dof_tongue31.png"),
            fig_motions(b1, picks, out_dir / "two_dof_tongue31_motions.png"),
            fig_shares(b1, fractions, tongues["nnm1"], out_dir / "two_dof_harmonics.png")]

    summary = dict(fast=bool(args.fast), times_s={k: round(v, 2) for k, v in times.items()},
                   tongues={key: [dict(label=t.label, start=t.start, tip=t.tip, end=t.end,
                                       entry_energy=t.energy_range[1], tip_energy=t.tip_energy,
                                       tip_frequency_hz=t.tip_frequency_hz, tip_fraction=t.tip_fraction,
                                       complete=t.complete, mode=t.mode) for t in v]
                            for key, v in tongues.items()},
                   picks={lab: dict(index=int(i), energy=float(b1.energy[i]),
                                    frequency_hz=float(b1.frequency_hz[i]),
                                    fraction3=float(fractions[i, 3]),
                                    description=analysis.describe_orbit(b1, i)) for lab, i in picks.items()})
    assets = Path(args.assets)
    assets.parent.mkdir(parents=True, exist_ok=True)
    nnm.save_model(assets, model, extra=dict(provenance=dict(
        builder="examples/two_dof_tongues.py", summary_json=json.dumps(summary))))
    for key in ("nnm1", "nnm2", "nnm1_hb"):
        if key in branches:
            nnm.save_branch(assets, branches[key])
    summary["total_s"] = round(time.perf_counter() - t_all, 1)
    if args.summary:
        Path(args.summary).write_text(json.dumps(summary, indent=1))
    for f in figs:
        print(f"wrote {f} ({f.stat().st_size // 1024} kB)")
    print(f"wrote {assets} ({assets.stat().st_size // 1024} kB); total {summary['total_s']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
