"""Forced responses of the Paris-like aircraft near its mode 20, as in the seed paper's ground vibration test.

Shakers at the four tip-tank attachments (vertical force on the tank side of each attachment, each signed
like mode 20's shape there: the force pattern appropriated to that mode) excite the second wing torsion
(anti-symmetric, 35.46 Hz) at three force levels.  For each level: the forced response by condensed harmonic
balance (``nnm.forced_response``; 4 cubic springs in 548 DOFs, so the equations are condensed onto the
springs' deformations), its peak, its folds; next to the conservative backbone of mode 20
(``nnm.continue_nnm(model, 20, E, method="hb", harmonics=5, condensed=True)``) and the resonance predicted on
it by energy balance (``nnm.energy_balance``).  The springs soften (k3 < 0): the resonance frequency drops
with the level, as the test showed.

    python examples/forced_aircraft.py                        # 1, 2 and 4 N; zeta 0.2 %; ~10 s
    python examples/forced_aircraft.py --levels 2,5 --zeta 0.005 --plot /tmp/frf.png --save-to /tmp/f.h5
    nnm-view /tmp/paris_forced.h5                             # the model and the backbone (forced: not shown yet)

Written: the amplitude-frequency plot (``--plot``, default forced_aircraft.png in the current folder) and an nnm file with
the model, the backbone and the forced responses (``--save-to``, default paris_forced.h5 in the temporary
folder), read back to check it.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

# One BLAS thread: the dense algebra here is small, and a multi-threaded BLAS competing with other
# processes on a small machine is much slower (see examples/paris_fep.py).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import nnm_solver as nnm  # noqa: E402
from nnm_solver.results.forced_plot import plot_forced  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODE = 20
#: the four tank-side vertical DOFs of the tip-tank attachments (R front, R rear, L front, L rear)
TANK_LABELS = ["wing R front (tank side) uz", "wing R rear (tank side) uz", "wing L front (tank side) uz",
               "wing L rear (tank side) uz"]


def force_pattern(model, mode=MODE):
    """Unit vertical forces (N) at the tank-side attachment DOFs, signed like the mode's shape there."""
    _, shapes = model.linear_modes()
    idx = [model.dof_labels.index(lab) for lab in TANK_LABELS]
    f = np.zeros(model.n)
    f[idx] = np.sign(shapes[idx, mode - 1])
    return f, idx


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default=str(ROOT / "assets" / "paris.h5"))
    ap.add_argument("--levels", default="1,2,4", help="force per shaker (N), comma-separated")
    ap.add_argument("--zeta", type=float, default=0.002, help="modal damping ratio of every mode")
    ap.add_argument("--range", default=None, help="frequency range (Hz), e.g. 34.5,35.8 (default: mode 20's linear "
                                                  "frequency x [0.98, 1.005])")
    ap.add_argument("--energy", type=float, default=4.0, help="energy_max of the backbone (J)")
    ap.add_argument("--harmonics", type=int, default=5)
    ap.add_argument("--plot", default="forced_aircraft.png", help="the amplitude-frequency plot (default: in the "
                    "current folder; the docs' figure: --plot docs/img/forced_aircraft.png)")
    ap.add_argument("--save-to", default=str(Path(tempfile.gettempdir()) / "paris_forced.h5"))
    args = ap.parse_args(argv)
    levels = [float(s) for s in args.levels.split(",")]
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")

    model = nnm.load_model(args.model)
    freqs, _ = model.linear_modes()
    label = model.mode_labels[MODE - 1] if model.mode_labels else f"mode {MODE}"
    f_range = (tuple(float(s) for s in args.range.split(",")) if args.range
               else (0.98 * freqs[MODE - 1], 1.005 * freqs[MODE - 1]))
    pattern, tank = force_pattern(model)
    dof = tank[0]
    print(f"{model.name}: {model.n} DOFs, {len(model.springs)} springs; mode {MODE} ({label}) at "
          f"{freqs[MODE - 1]:.4f} Hz; "
          f"shakers at {', '.join(TANK_LABELS)}; zeta = {100 * args.zeta:g} %")

    t0 = time.perf_counter()
    # max_rel_step=0.1: twice as many backbone points as the default, for a smooth curve (0.7 s)
    backbone = nnm.continue_nnm(model, MODE, args.energy, method="hb", harmonics=args.harmonics, condensed=True,
                                max_rel_step=0.1)
    backbone.name = f"NNM {MODE} backbone (HB, H={args.harmonics}, condensed)"
    t_bb = time.perf_counter() - t0
    print(f"backbone: {len(backbone)} points, {backbone.frequency_hz[0]:.4f} -> {backbone.frequency_hz[-1]:.4f} Hz "
          f"up to {backbone.energy[-1]:.3g} J, {t_bb:.2f} s ({backbone.status})")
    eb = nnm.energy_balance(backbone, pattern, args.zeta)

    responses, rows = [], []
    for level in levels:
        t0 = time.perf_counter()
        r = nnm.forced_response(model, level * pattern, f_range, args.zeta, harmonics=args.harmonics,
                                name=f"{level:g} N per shaker")
        dt = time.perf_counter() - t0
        responses.append(r)
        pk, pred = r.peak(dof), eb.at_scale(level, dof)
        rows.append((level, r, pk, pred, dt))
        print(f"  {level:5g} N: {r.message}; condensed={r.condensed}, stability by {r.stability}")

    print()
    print("| force per shaker | peak (forced) | amplitude (forced) | phase resonance (forced) | energy balance: peak "
          "| amplitude | folds (Hz) | points | s | points/s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for level, r, pk, pred, dt in rows:
        eb_f = f"{pred['frequency_hz']:.4f} Hz" if pred else "beyond the backbone"
        eb_a = f"{1e3 * pred['amplitude']:.4f} mm" if pred else "-"
        folds = ", ".join(f"{f:.4f}" for f in r.fold_frequencies_hz) or "none"
        pr90 = ", ".join(f"{p['frequency_hz']:.4f} Hz" for p in r.phase_resonance(dof)) or "none"
        print(f"| {level:g} N | {pk['frequency_hz']:.4f} Hz | {1e3 * pk['amplitude']:.4f} mm | {pr90} | {eb_f} "
              f"| {eb_a} "
              f"| {folds} | {len(r)} | {dt:.2f} | {len(r) / dt:.0f} |")
    peaks = [pk["frequency_hz"] for _, _, pk, _, _ in rows]
    drops = bool(np.all(np.diff(peaks) < 0)) if len(peaks) > 1 else True
    print(f"\npeak frequencies {'drop' if drops else 'DO NOT drop'} with the level: "
          + " > ".join(f"{p:.4f}" for p in peaks) + " Hz")

    if args.plot:
        ax = plot_forced(responses, dof, backbones=backbone, predictions=eb, scale=1e3, unit="mm",
                         title=f"Paris-like aircraft, mode {MODE}: forced responses at {TANK_LABELS[0]}, "
                               f"zeta {100 * args.zeta:g} %")
        ax.set_xlim(*sorted(f_range))
        Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
        ax.figure.set_size_inches(8, 5)
        ax.figure.tight_layout()
        ax.figure.savefig(args.plot, dpi=110)
        print(f"plot: {args.plot}")
    if args.save_to:
        path = Path(args.save_to)
        if path.exists():
            path.unlink()
        nnm.save_model(path, model)
        nnm.save_branch(path, backbone)
        for r in responses:
            nnm.save_forced_response(path, r)
        back = nnm.load_forced_responses(path)
        same = all(np.array_equal(a.amplitude(dof), b.amplitude(dof)) for a, b in zip(back, responses))
        print(f"saved: {path} ({path.stat().st_size / 1e6:.1f} MB; {len(back)} forced responses read back"
              f"{' identical' if same else ' DIFFERENT'})")
    return 0 if drops else 1


if __name__ == "__main__":
    sys.exit(main())
