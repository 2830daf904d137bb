"""Geometrically nonlinear beams (issue 55): NNM 1 of von Karman beams with immovable ends, full FE and ROM.

* hinged-hinged: the FE backbone of NNM 1 against its closed form (w = a(t) sin(pi x / L) reduces the
  continuum exactly to a'' + w0^2 (a + a^3 / (4 r^2)) = 0; ``nnm_fem.vk_beam.hinged_backbone``);
* clamped-clamped: NNM 1 hardens until its frequency meets a third of mode 3's, the classic 3:1 tongue; the
  backbone (tongues="skip") passes it and lists it in ``branch.tongues``; the condensed ROM on modes 1 and 3
  (``nnm_fem.condensed_rom``) gives the same backbone in a fraction of the time.

Aluminium strip 1 m x 10 mm x 20 mm (L / h = 100), 16 elements.  Writes frequency-energy plots and the
branches (``nnm-view geometric_beams/clamped.h5`` animates the beam) into --out-dir (default ./geometric_beams/).

    python examples/geometric_beams.py            # full run (a few minutes)
    python examples/geometric_beams.py --fast     # 8 elements, fewer points (tests)
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
#: energy (J) of the clamped beam's run: past the 3:1 tongue (~14 J, midspan amplitude ~6.5 thicknesses)
CLAMPED_ENERGY_MAX = 40.0


def beam(ends, elements):
    return nnm_fem.von_karman_beam(LENGTH, THICKNESS, WIDTH, E, RHO, elements, ends=ends)


def energy_at(amplitude):
    """Closed-form energy (J) of the hinged beam's NNM 1 at midspan amplitude ``amplitude`` (m)."""
    return float(hinged_backbone(amplitude, LENGTH, THICKNESS, E, RHO)[1]) * WIDTH


def amplitudes(branch, model):
    """Midspan amplitude (m) of each orbit: |uz| at the turning point t = 0 (velocities zero there)."""
    return np.abs(branch.x0[:, model.dof_labels.index(model.info["midspan_dof"])])


def hinged(elements, amplitude_max=2.0, log=print):
    """NNM 1 of the hinged beam to ``amplitude_max`` thicknesses; returns (branch, table rows (a/h, f, f_exact,
    rel error))."""
    model = beam("hinged", elements)
    t = time.perf_counter()
    branch = nnm.continue_nnm(model, 1, energy_max=energy_at(amplitude_max * THICKNESS), tongues="skip")
    log(f"hinged, {elements} elements ({model.n} DOFs): {len(branch.energy)} orbits, {branch.status}, "
        f"{time.perf_counter() - t:.1f} s")
    a = amplitudes(branch, model)
    f_exact = hinged_backbone(a, LENGTH, THICKNESS, E, RHO)[0]
    rows = np.column_stack([a / THICKNESS, branch.frequency_hz, f_exact, branch.frequency_hz / f_exact - 1])
    return model, branch, rows


def clamped(elements, log=print):
    """NNM 1 of the clamped beam past the 3:1 tongue (full model) and the same from the ROM on modes 1, 3."""
    model = beam("clamped", elements)
    e_max = CLAMPED_ENERGY_MAX
    t = time.perf_counter()
    full = nnm.continue_nnm(model, 1, energy_max=e_max, tongues="skip")
    t_full = time.perf_counter() - t
    log(f"clamped, {elements} elements ({model.n} DOFs): {len(full.energy)} orbits, {full.status}, {t_full:.1f} s")
    for tg in full.tongues:
        log(f"  {tg.order}:1 tongue with mode {tg.partner_mode} at {tg.entry_frequency_hz:.2f} Hz, "
            f"{tg.entry_energy:.4g} J, skipped={tg.skipped}")
    structure = nnm_fem.beam_structure(LENGTH, THICKNESS, WIDTH, E, RHO, elements, "clamped")
    t = time.perf_counter()
    rom = nnm_fem.condensed_rom(structure, [1, 3], THICKNESS)
    reduced = nnm.continue_nnm(rom.model, 1, energy_max=e_max, tongues="skip")
    t_rom = time.perf_counter() - t
    log(f"clamped ROM (modes 1, 3; {rom.samples} static solutions): {len(reduced.energy)} orbits, {reduced.status}, "
        f"{t_rom:.1f} s")
    return model, full, rom, reduced


def compare_backbones(full, reduced):
    """Largest relative frequency difference of the ROM's backbone from the full one, on the full one's energies
    below the first tongue (interpolated in log energy)."""
    stop = min([t.entry_energy for t in full.tongues] + [full.energy[-1]])
    keep = full.energy <= stop
    order = np.argsort(reduced.energy)
    f_rom = np.interp(np.log(full.energy[keep]), np.log(reduced.energy[order]), reduced.frequency_hz[order])
    return float(np.max(np.abs(f_rom / full.frequency_hz[keep] - 1)))


def plot(hinged_branch, rows, full, reduced, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    a = np.linspace(0, rows[-1, 0], 200) * THICKNESS
    f, e = hinged_backbone(a, LENGTH, THICKNESS, E, RHO)
    ax[0].semilogx(e * WIDTH, f, "k-", lw=1, label="closed form")
    ax[0].semilogx(hinged_branch.energy, hinged_branch.frequency_hz, "o", ms=3, label="FE (full)")
    ax[0].set(xlabel="energy (J)", ylabel="frequency (Hz)", title="hinged-hinged, NNM 1")
    ax[0].legend()
    nnm.plot_fep([full, reduced], ax=ax[1])
    ax[1].set_title("clamped-clamped, NNM 1 (full FE and ROM on modes 1, 3)")
    fig.tight_layout()
    fig.savefig(out / "geometric_beams_fep.png", dpi=100)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--fast", action="store_true", help="8 elements, fewer orbits")
    p.add_argument("--out-dir", default="geometric_beams", help="folder for the figure and the branches")
    args = p.parse_args(argv)
    elements = 8 if args.fast else nnm_fem.vk_beam.DEFAULT_BEAM_ELEMENTS
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    hm, hb, rows = hinged(elements)
    print("  a/h    f (Hz)    closed form    rel. error")
    for r in rows[:: max(1, len(rows) // 12)]:
        print(f"  {r[0]:5.3f}  {r[1]:8.4f}  {r[2]:8.4f}  {r[3]:+.2e}")
    cm, full, rom, reduced = clamped(elements)
    print(f"ROM vs full backbone below the tongue: max rel. frequency difference {compare_backbones(full, reduced):.2e}")
    plot(hb, rows, full, reduced, out)
    for name, b in (("hinged", hb), ("clamped", full), ("clamped_rom", reduced)):
        if (out / f"{name}.h5").exists():
            (out / f"{name}.h5").unlink()                 # this run's branches replace the previous run's
        nnm.save_branch(out / f"{name}.h5", b)
    print(f"wrote {out / 'geometric_beams_fep.png'} and {out}/{{hinged,clamped,clamped_rom}}.h5")
    return hb, rows, full, reduced


if __name__ == "__main__":
    main()
