"""Geometrically nonlinear beams (issue 55): NNM 1 of von Karman beams with immovable ends, full FE and ROM.

* hinged-hinged: the FE backbone of NNM 1 against its closed form (w = a(t) sin(pi x / L) reduces the
  continuum exactly to a'' + w0^2 (a + a^3 / (4 r^2)) = 0; ``nnm_fem.vk_beam.hinged_backbone``);
* clamped-clamped: NNM 1 hardens and meets mode 3 at its 5th harmonic (58 Hz, 0.56 J; with mode 5 in the ROM also
  mode 5 at its 9th, 7.2 J, and 7th, 38 J; the 3:1 with mode 3 lies far above, near 680 J); condensed ROMs
  (``nnm_fem.condensed_rom``, membrane condensation) on modes 1, 3 and 1, 3, 5 give its backbone and, compared,
  the convergence check in the number of modes.

Aluminium strip 1 m x 10 mm x 20 mm (L / h = 100), 16 elements.  Writes the frequency-energy plots into
--out-dir (./geometric_beams/); the branches are returned (the nnm file format does not store PolynomialStiffness
elements yet, so they are not saved for nnm-view).
The full FE models are nnm Models too (``nnm_fem.von_karman_beam``); --full runs the hinged one to one thickness.

    python examples/geometric_beams.py            # 16 elements, two clamped ROMs (about a minute)
    python examples/geometric_beams.py --fast     # 8 elements, one clamped ROM (tests)
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import nnm_solver as nnm  # noqa: E402
import nnm_fem  # noqa: E402
from nnm_fem.vk_beam import hinged_backbone  # noqa: E402

LENGTH, THICKNESS, WIDTH, E, RHO = 1.0, 0.01, 0.02, 70e9, 2700.0      # m, m, m, Pa, kg/m^3
#: energy (J) of the clamped beam's runs: past the 5:1 resonance with mode 3 (58 Hz), to about 2.6 thicknesses
CLAMPED_ENERGY_MAX = 40.0
#: tongue policy of the clamped runs: the solver's default, "follow" ("skip" gives the backbone past each tongue:
#: 40 J with one tongue skipped on modes 1, 3, three on modes 1, 3, 5; tests/test_geometric_tongues.py)
TONGUES = "follow"


def energy_at(amplitude):
    """Closed-form energy (J) of the hinged beam's NNM 1 at midspan amplitude ``amplitude`` (m)."""
    return float(hinged_backbone(amplitude, LENGTH, THICKNESS, E, RHO)[1]) * WIDTH


def hinged(elements, amplitude_max=2.0, full=False, log=print):
    """NNM 1 of the hinged beam to ``amplitude_max`` thicknesses from the one-mode ROM (and the full model to one
    thickness with ``full``); returns {name: (branch, rows (a/h, f, f_exact, rel. error))}."""
    structure = nnm_fem.beam_structure(LENGTH, THICKNESS, WIDTH, E, RHO, elements, "hinged")
    mid = structure.dof(structure.info["midspan_dof"])
    out = {}
    t = time.perf_counter()
    rom = nnm_fem.condensed_rom(structure, [1], THICKNESS)
    branch = nnm.continue_nnm(rom.model, 1, energy_max=energy_at(amplitude_max * THICKNESS))
    out["rom"] = branch, _rows(branch, np.abs(rom.expand(branch.x0)[:, mid]))
    log(f"hinged ROM (mode 1 of {elements} elements): {len(branch.energy)} orbits, {branch.status}, "
        f"{time.perf_counter() - t:.1f} s")
    if full:
        model = structure.model()
        t = time.perf_counter()
        branch = nnm.continue_nnm(model, 1, energy_max=energy_at(THICKNESS))
        out["full"] = branch, _rows(branch, np.abs(branch.x0[:, mid]))
        log(f"hinged full model ({model.n} DOFs): {len(branch.energy)} orbits, {branch.status}, "
            f"{time.perf_counter() - t:.1f} s")
    return out


def _rows(branch, a):
    f_exact = hinged_backbone(a, LENGTH, THICKNESS, E, RHO)[0]
    return np.column_stack([a / THICKNESS, branch.frequency_hz, f_exact, branch.frequency_hz / f_exact - 1])


def clamped(elements, mode_sets=((1, 3), (1, 3, 5)), tongues=TONGUES, log=print):
    """NNM 1 of the clamped beam from ROMs on ``mode_sets`` (the convergence check in the number of modes);
    returns {modes: (rom, branch)}."""
    structure = nnm_fem.beam_structure(LENGTH, THICKNESS, WIDTH, E, RHO, elements, "clamped")
    out = {}
    for modes in mode_sets:
        t = time.perf_counter()
        rom = nnm_fem.condensed_rom(structure, list(modes), THICKNESS)
        branch = nnm.continue_nnm(rom.model, 1, energy_max=CLAMPED_ENERGY_MAX, tongues=tongues)
        labels = sorted(set(map(str, branch.labels))) if branch.labels is not None else []
        log(f"clamped ROM on modes {modes} ({rom.samples} static solutions): {len(branch.energy)} orbits, "
            f"{branch.status}, {time.perf_counter() - t:.1f} s; labels {labels}")
        out[modes] = rom, branch
    return out


def compare_backbones(b1, b2):
    """Largest relative frequency difference between two branches on b1's energies (interpolated in log energy),
    the points labelled 'backbone' only (NaN when there are none)."""
    def on(b):
        keep = np.array([str(lab) == "backbone" for lab in b.labels]) if b.labels is not None else \
            np.ones(len(b.energy), bool)
        order = np.argsort(b.energy[keep])
        return b.energy[keep][order], b.frequency_hz[keep][order]
    e1, f1 = on(b1)
    e2, f2 = on(b2)
    inside = (e1 >= e2[0]) & (e1 <= e2[-1]) if len(e2) else np.zeros(len(e1), bool)
    if not np.any(inside):
        return float("nan")
    return float(np.max(np.abs(np.interp(np.log(e1[inside]), np.log(e2), f2) / f1[inside] - 1)))


def plot(hinged_runs, clamped_runs, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    branch, rows = hinged_runs["rom"]
    a = np.linspace(0, rows[-1, 0], 200) * THICKNESS
    f, e = hinged_backbone(a, LENGTH, THICKNESS, E, RHO)
    ax[0].semilogx(e * WIDTH, f, "k-", lw=1, label="closed form")
    ax[0].semilogx(branch.energy, branch.frequency_hz, "o", ms=3, mfc="none", label="ROM (mode 1)")
    if "full" in hinged_runs:
        ax[0].semilogx(hinged_runs["full"][0].energy, hinged_runs["full"][0].frequency_hz, ".", ms=3, label="full FE")
    ax[0].set(xlabel="energy (J)", ylabel="frequency (Hz)", title="hinged-hinged beam, NNM 1")
    ax[0].legend()
    nnm.plot_fep([b for _, b in clamped_runs.values()], ax=ax[1])
    ax[1].set_title("clamped-clamped beam, NNM 1 (ROMs on modes " + ", ".join(str(m) for m in clamped_runs) + ")")
    fig.tight_layout()
    fig.savefig(out / "geometric_beams_fep.png", dpi=100)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fast", action="store_true", help="8 elements, the clamped ROM on modes 1, 3 only")
    p.add_argument("--full", action="store_true", help="also the full hinged FE model to one thickness (slow)")
    p.add_argument("--tongues", default=TONGUES, choices=["follow", "skip"], help="the clamped runs' tongue policy")
    p.add_argument("--out-dir", default="geometric_beams", help="folder for the figure")
    args = p.parse_args(argv)
    elements = 8 if args.fast else nnm_fem.vk_beam.DEFAULT_BEAM_ELEMENTS
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    hinged_runs = hinged(elements, full=args.full)
    for name, (branch, rows) in hinged_runs.items():
        print(f"hinged, {name}:   a/h    f (Hz)    closed form    rel. error")
        for r in rows[:: max(1, len(rows) // 10)]:
            print(f"  {r[0]:5.3f}  {r[1]:8.4f}  {r[2]:8.4f}  {r[3]:+.2e}")
        print(f"  largest |error|: {np.max(np.abs(rows[:, 3])):.2e}")
    clamped_runs = clamped(elements, ((1, 3),) if args.fast else ((1, 3), (1, 3, 5)), args.tongues)
    if len(clamped_runs) > 1:
        (_, b1), (_, b2) = list(clamped_runs.values())[:2]
        print(f"clamped: ROM backbones on modes 1, 3 and 1, 3, 5 differ by at most {compare_backbones(b2, b1):.2e}")
    plot(hinged_runs, clamped_runs, out)
    # the branches are not saved: the nnm file format does not store PolynomialStiffness elements yet (issue 55)
    print(f"wrote {out / 'geometric_beams_fep.png'}")
    return hinged_runs, clamped_runs


if __name__ == "__main__":
    main()
