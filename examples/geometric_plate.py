"""Clamped square von Karman plate (issue 55): NNM 1 from condensed ROMs, with the convergence check in the modes.

Aluminium plate 0.3 m x 0.3 m x 1 mm, clamped immovable edges, 6 x 6 elements (342 DOFs; the full model is an
nnm Model too, ``nnm_fem.von_karman_plate``).  NNM 1 couples with the doubly symmetric modes only (by symmetry):
the ROMs on modes 1; 1, 5, 6; 1, 5, 6, 11 (membrane condensation, ``nnm_fem.condensed_rom``) are continued to a
centre amplitude of about two thicknesses and their backbones compared.

    python examples/geometric_plate.py            # three ROMs (a few minutes)
    python examples/geometric_plate.py --fast     # 4 x 4 elements, modes 1 and 1, 5, 6 (tests)
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

SIDE, THICKNESS, E, NU, RHO = 0.3, 0.001, 70e9, 0.3, 2700.0      # m, m, Pa, -, kg/m^3
MODE_SETS = ((1,), (1, 5, 6), (1, 5, 6, 11))                    # doubly symmetric modes of the square plate
AMPLITUDE = 2.0                                                 # centre amplitude reached, in thicknesses


def energy_for(rom, centre, amplitude):
    """Energy (J) of the one-mode Duffing  q'' + w^2 q + k q^3 = 0  at the centre amplitude ``amplitude`` (m):
    the continuation's energy_max (the ROM's own orbits then report their amplitudes)."""
    q = amplitude / abs(rom.Phi[centre, 0])
    k = rom.coefficients[rom.exponents.tolist().index([3] + [0] * (len(rom.modes) - 1)), 0]
    return float(rom.omega2[0] * q ** 2 / 2 + k * q ** 4 / 4)


def run(elements, mode_sets, log=print):
    """{modes: (rom, branch, centre amplitudes (m))} of the ROMs on ``mode_sets``."""
    structure = nnm_fem.plate_structure(SIDE, SIDE, THICKNESS, E, NU, RHO, elements, "clamped")
    centre = structure.dof(structure.info["centre_dof"])
    out, e_max = {}, None
    for modes in mode_sets:
        t = time.perf_counter()
        rom = nnm_fem.condensed_rom(structure, list(modes), THICKNESS)
        t_rom = time.perf_counter() - t
        # twice the one-mode ROM's energy at AMPLITUDE: the coupled ROMs put some of it into the other modes
        e_max = 2 * energy_for(rom, centre, AMPLITUDE * THICKNESS) if e_max is None else e_max
        t = time.perf_counter()
        branch = nnm.continue_nnm(rom.model, 1, energy_max=e_max)
        a = np.abs(rom.expand(branch.x0)[:, centre])
        log(f"plate ROM on modes {modes}: {rom.samples} static solutions in {t_rom:.1f} s (fit residual "
            f"{rom.fit_residual:.1e}); {len(branch.energy)} orbits, {branch.status}, {time.perf_counter() - t:.1f} s; "
            f"f {branch.frequency_hz[0]:.3f} -> {branch.frequency_hz[-1]:.3f} Hz at a = {a[-1] / THICKNESS:.2f} h")
        out[modes] = rom, branch, a
    return structure, out


def frequency_at(branch, a, amplitudes):
    """The branch's frequency at centre amplitudes ``amplitudes`` (interpolated along its points where a increases;
    NaN beyond the largest amplitude reached)."""
    keep = np.concatenate([[True], np.diff(a) > 0])
    f = np.interp(amplitudes, a[keep], branch.frequency_hz[keep])
    return np.where(amplitudes <= a[keep][-1], f, np.nan)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fast", action="store_true", help="4 x 4 elements, two ROMs")
    p.add_argument("--out-dir", default="geometric_plate", help="folder for the figure")
    args = p.parse_args(argv)
    elements, sets = (4, MODE_SETS[:2]) if args.fast else (6, MODE_SETS)
    structure, runs = run(elements, sets)
    probe = np.array([0.5, 1.0, 1.5, 2.0]) * THICKNESS
    table = {m: frequency_at(b, a, probe) for m, (_, b, a) in runs.items()}
    last = table[sets[-1]]
    print("centre amplitude / h:       " + "  ".join(f"{v:8.2f}" for v in probe / THICKNESS))
    for m, f in table.items():
        print(f"modes {str(m):16s} f (Hz): " + "  ".join(f"{v:8.3f}" for v in f)
              + "   vs the largest ROM: " + "  ".join(f"{v:+.1e}" for v in f / last - 1))
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for m, (_, b, a) in runs.items():
        ax.plot(a / THICKNESS, b.frequency_hz, ".-", ms=2, lw=0.8, label=f"ROM on modes {', '.join(map(str, m))}")
    ax.set(xlabel="centre amplitude / thickness", ylabel="frequency (Hz)", title="clamped square plate, NNM 1")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "geometric_plate_backbone.png", dpi=100)
    plt.close(fig)
    print(f"wrote {out / 'geometric_plate_backbone.png'}")
    return runs, table


if __name__ == "__main__":
    main()
