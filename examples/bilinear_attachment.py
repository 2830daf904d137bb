"""The seed paper's tip-tank attachment as a bilinear softening spring, compared with the paper's cubic fit.

The paper measured the restoring force of the Paris's tip-tank attachments (its Fig. 7): linear up to a
deformation, then softer -- a piecewise characteristic that its NNM algorithm could not handle, so it
fitted a softening cubic spring, k3 = -1e13 N/m^3.  Here the attachment gets the bilinear law instead
(``nnm.PiecewiseLinearSpring``) and the backbones of both laws are compared.

The fit.  The linear stiffness of the attachment stays in K; the nonlinear force is
    cubic:     g_c(d) = k3 d^3,
    bilinear:  g_b(d) = k1 sign(d) max(|d| - d1, 0)      (slope 0 below d1, k1 < 0 beyond: softening).
At a representative deformation d_r -- the largest peak deformation of the attachments along the cubic
backbone, i.e. the deformation the cubic fit is used at -- the bilinear law has the same force and the
same potential energy as the cubic one:
    k1 (d_r - d1) = k3 d_r^3   and   k1 (d_r - d1)^2 / 2 = k3 d_r^4 / 4   =>   d1 = d_r / 2,  k1 = 2 k3 d_r^2.
So both laws store the same energy and push back with the same force at d_r; below d_r / 2 the bilinear
joint is linear, and past d_r it softens linearly where the cubic softens quadratically.

Two structures:
* the 2-DOF benchmark (M = I, K = [[2, -1], [-1, 2]]) with a softening grounded spring on DOF 0,
  k3 = -0.05 N/m^3 (the tank attachment's role), NNM1 up to 2 J;
* the Paris-like aircraft (``assets/paris.h5``, 548 DOF): its four cubic springs (relative vertical
  displacement across each attachment) replaced by bilinear ones with one common fit, mode 20 (the
  anti-symmetric wing torsion) up to 10 J with ``tongues="skip"``, below the 9:1 tongue at ~12 J.

    python examples/bilinear_attachment.py                     # both, ~5 min on 2 shared cores
    python examples/bilinear_attachment.py --two-dof-only      # a few seconds
    python examples/bilinear_attachment.py --summary out.json  # the numbers, as JSON

Figures: bilinear_two_dof.png, bilinear_paris_mode20.png in --out-dir (the docs': --out-dir docs/img).  Results: docs/bilinear_attachments.md.
"""
from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # small dense solves: one BLAS thread is fastest on a shared machine

import numpy as np  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import nnm_solver as nnm
from nnm_solver.integrators.registry import get_integrator  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PARIS = ROOT / "assets" / "paris.h5"
DPI = 100

TWO_DOF_K3 = -0.05        # N/m^3, softening spring to ground on DOF 0
TWO_DOF_ENERGY = 2.0      # J, NNM1 backbone up to here (the cubic's escape is at 5 J)
PARIS_MODE = 20
PARIS_ENERGY = 10.0       # J, below the 9:1 tongue of mode 20 (12.2 J, docs/paris_results.md)
MAX_POINTS = 40


def bilinear_fit(k3, d_r):
    """(d1, k1) of the bilinear law g_b(d) = k1 sign(d) max(|d| - d1, 0) with the cubic law's force and
    potential at the deformation d_r (m): d1 = d_r / 2 (m), k1 = 2 k3 d_r^2 (N/m)."""
    return 0.5 * d_r, 2.0 * k3 * d_r ** 2


def bilinear_model(model, d_r, eps=None):
    """The model with each CubicSpring(dof, other, k3) replaced by PiecewiseLinearSpring(dof, other,
    stiffnesses=[0, k1], breakpoints=[d1]) of ``bilinear_fit(k3, d_r)`` (k0 = 0: the attachment's linear
    stiffness stays in K, so the linear modes are unchanged)."""
    springs = []
    for s in model.springs:
        if not isinstance(s, nnm.CubicSpring):
            raise ValueError(f"expected cubic springs, got {type(s).__name__}")
        d1, k1 = bilinear_fit(s.k3, d_r)
        kw = {} if eps is None else {"eps": eps}
        springs.append(nnm.PiecewiseLinearSpring(dof=s.dof, other=s.other, stiffnesses=[0.0, k1], breakpoints=[d1], **kw))
    return nnm.Model(model.M, model.K, springs, dof_labels=model.dof_labels, mode_labels=model.mode_labels,
                     mesh=model.mesh, name=f"{model.name} (bilinear attachments)", info=dict(model.info))


def peak_deformation(branch, i, samples=256):
    """Largest |d| (m) over the orbit of point i, for each spring (n_s,)."""
    _, x, _ = branch.orbit(i, samples)
    return np.max(np.abs(x @ branch.model.elements.B.T), axis=0)


def backbone(model, mode, energy_max):
    """Backbone of ``mode`` up to energy_max (J), tongues skipped; (branch, seconds)."""
    t0 = time.perf_counter()
    b = nnm.continue_nnm(model, mode, energy_max, tongues="skip", max_points=MAX_POINTS)
    return b, time.perf_counter() - t0


def compare(model, mode, energy_max):
    """Cubic backbone, the bilinear fit at its largest attachment deformation, bilinear backbone, and
    the numbers of the comparison (dict)."""
    cubic, t_c = backbone(model, mode, energy_max)
    peaks = np.array([peak_deformation(cubic, i) for i in range(len(cubic))])
    d_r = float(peaks[-1].max())
    k3 = model.springs[0].k3
    d1, k1 = bilinear_fit(k3, d_r)
    bil_model = bilinear_model(model, d_r)
    bil, t_b = backbone(bil_model, mode, energy_max)
    bil_peaks = np.array([peak_deformation(bil, i) for i in range(len(bil))])
    f_lin = float(model.linear_modes()[0][mode - 1])
    # the linear frequency as the time step sees it: the integrator's discrete linear orbit of angular frequency w
    # closes in linear_period(w, N) (integrators/registry.py; Newmark 200 steps: 8e-5 above 1/f, gauss6 100: 1e-11)
    N = cubic.settings.steps_per_period
    f_ref = 1.0 / get_integrator(cubic.settings.integrator).linear_period(2 * np.pi * f_lin, N)

    def drop(b, E):
        """Frequency change (%) at energy E (interpolated in log E) from the discrete linear frequency."""
        return float(100 * (np.interp(np.log(E), np.log(b.energy), b.frequency_hz) / f_ref - 1))

    def tongues(b):
        """The tongues the backbone met (tongues='skip'): label, entry energy (J) and frequency (Hz), the
        higher mode it couples to, and whether the backbone was found again beyond it."""
        return [dict(label=t["label"], entry_energy=float(t["entry_energy"]), entry_frequency_hz=float(t["entry_frequency_hz"]),
                     partner_mode=t.get("partner_mode"), skipped=bool(t.get("skipped")), note=t.get("note", ""),
                     hidden_points=t.get("hidden_points")) for t in b.tongues]

    def summary(b, pk, seconds):
        """What the JSON and the page report of one backbone b (peak spring deformations pk per point)."""
        return dict(points=len(b), status=b.status, message=b.message, tongues=tongues(b), seconds=round(seconds, 1),
                    energy=[float(b.energy[0]), float(b.energy[-1])],
                    frequency_hz=[float(b.frequency_hz[0]), float(b.frequency_hz[-1])],
                    drop_percent=drop(b, b.energy[-1]), stable=bool(np.all(b.stable)),
                    unstable_energies=[float(E) for E in b.energy[~np.asarray(b.stable, bool)]],
                    peak_d=float(pk[-1].max()))

    E_hi = min(cubic.energy[-1], bil.energy[-1])
    E_lo = max(cubic.energy[0], bil.energy[0])
    energies = [float(E) for E in np.geomspace(E_lo, E_hi, 7)]
    onset = [float(E) for E, p in zip(bil.energy, bil_peaks.max(axis=1)) if p > d1]
    out = dict(mode=mode, f_linear_hz=f_lin, f_linear_discrete_hz=f_ref, steps_per_period=N, k3=k3, d_r=d_r, d1=d1, k1=k1, eps=bil_model.springs[0].eps,
               force_at_d_r=k3 * d_r ** 3, potential_at_d_r=k3 * d_r ** 4 / 4,
               cubic=summary(cubic, peaks, t_c),
               bilinear=dict(summary(bil, bil_peaks, t_b),
                             first_energy_past_d1=onset[0] if onset else None,
                             linear_below_d1=float(np.max(np.abs(bil.frequency_hz[bil_peaks.max(axis=1) < 0.9 * d1]
                                                                 / f_ref - 1), initial=0.0))),
               table=[dict(energy=E, cubic_percent=drop(cubic, E), bilinear_percent=drop(bil, E)) for E in energies])
    return cubic, bil, out


def fig_compare(cubic, bil, res, title, path, d_unit=1.0, d_label="d (m)", f_unit=1.0, f_label="N", d_name="m"):
    """(a) nonlinear attachment force of both laws, the representative deformation marked; (b) FEP."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2), dpi=DPI)
    d_max = 1.25 * max(res["cubic"]["peak_d"], res["bilinear"]["peak_d"])
    d = np.linspace(-d_max, d_max, 801)
    pw = bil.model.springs[0]
    ax1.plot(d / d_unit, res["k3"] * d ** 3 / f_unit, label=f"cubic fit, k3 = {res['k3']:.3g} N/m$^3$")
    ax1.plot(d / d_unit, pw.exact_force(d) / f_unit, label=f"bilinear, d1 = {res['d1'] / d_unit:.3g} {d_name}, "
             f"k1 = {res['k1']:.3g} N/m")
    for s in (-1, 1):
        ax1.axvline(s * res["d_r"] / d_unit, color="0.6", ls=":", lw=1)
    ax1.plot([res["d_r"] / d_unit], [res["force_at_d_r"] / f_unit], "ko", ms=4,
             label="same force and energy at d$_r$")
    ax1.set_xlabel(d_label)
    ax1.set_ylabel(f"nonlinear attachment force ({f_label})")
    ax1.set_title("(a) restoring force beyond the linear stiffness")
    ax1.legend(fontsize=8, loc="upper right")
    ax1.grid(alpha=0.3)
    for b, lab, st, key in ((cubic, "cubic", "-o", "cubic"), (bil, "bilinear", "-s", "bilinear")):
        ax2.semilogx(b.energy, b.frequency_hz, st, ms=3, lw=1.2, label=lab)
        for t in res[key]["tongues"]:
            ax2.plot(t["entry_energy"], t["entry_frequency_hz"], "kx", ms=7)
            ax2.annotate(t["label"].replace("tongue ", ""), (t["entry_energy"], t["entry_frequency_hz"]),
                         textcoords="offset points", xytext=(4, 4), fontsize=8)
        if b.status != "done":
            ax2.plot(b.energy[-1], b.frequency_hz[-1], "r*", ms=9, label=f"{lab}: branch ends ({b.status})")
    ax2.axhline(res["f_linear_discrete_hz"], color="0.5", ls="--", lw=0.8,
                label=f"linear ({res['steps_per_period']} steps/period)")
    if res["bilinear"]["first_energy_past_d1"]:
        ax2.axvline(res["bilinear"]["first_energy_past_d1"], color="C1", ls=":", lw=1,
                    label="bilinear: first point with |d| > d1")
    ax2.set_xlabel("energy (J)")
    ax2.set_ylabel("frequency (Hz)")
    ax2.set_title(f"(b) backbone of mode {res['mode']}")
    ax2.legend(fontsize=8, loc="lower left")
    ax2.grid(alpha=0.3, which="both")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return str(path)


def two_dof_model(k3=TWO_DOF_K3):
    """The 2-DOF benchmark with a softening cubic spring to ground on DOF 0 (k3 in N/m^3)."""
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=k3)],
                     name="2-DOF, softening attachment")


def run_two_dof(out_dir):
    cubic, bil, res = compare(two_dof_model(), 1, TWO_DOF_ENERGY)
    res["figure"] = fig_compare(cubic, bil, res, "2-DOF benchmark: softening attachment on DOF 0, cubic vs bilinear",
                                out_dir / "bilinear_two_dof.png", d_label="d = x1 (m)")
    return res


def run_paris(out_dir):
    model = nnm.load_model(PARIS)
    cubic, bil, res = compare(model, PARIS_MODE, PARIS_ENERGY)
    res["figure"] = fig_compare(cubic, bil, res, "Paris-like aircraft, mode 20: tip-tank attachments, cubic fit vs "
                                "bilinear", out_dir / "bilinear_paris_mode20.png", d_unit=1e-6,
                                d_label="d = relative vertical displacement across an attachment (µm)",
                                f_unit=1e3, f_label="kN", d_name="µm")
    return res


def report(name, r):
    c, b = r["cubic"], r["bilinear"]
    print(f"{name}: mode {r['mode']}, f_lin = {r['f_linear_hz']:.5f} Hz; fit at d_r = {r['d_r']:.4g} m: "
          f"d1 = {r['d1']:.4g} m, k1 = {r['k1']:.4g} N/m")
    for lab, x in (("cubic", c), ("bilinear", b)):
        print(f"  {lab:8s}: {x['points']} points in {x['seconds']} s ({x['status']}), {x['energy'][0]:.3g} -> "
              f"{x['energy'][1]:.3g} J, {x['frequency_hz'][0]:.5f} -> {x['frequency_hz'][1]:.5f} Hz "
              f"({x['drop_percent']:+.3f} %), peak |d| {x['peak_d']:.4g} m, all stable: {x['stable']}")
        for t in x["tongues"]:
            print(f"      {t['label']} at {t['entry_energy']:.4g} J, {t['entry_frequency_hz']:.5f} Hz, "
                  f"partner mode {t['partner_mode']}: {t['note'] or ('skipped' if t['skipped'] else '')}")
        if x["status"] != "done":
            print(f"      ends: {x['message']}")
    for row in r["table"]:
        print(f"    E = {row['energy']:9.4g} J: cubic {row['cubic_percent']:+8.4f} %, bilinear {row['bilinear_percent']:+8.4f} %")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--two-dof-only", action="store_true", help="skip the aircraft (a few seconds)")
    p.add_argument("--out-dir", default=".", help="folder of the PNG figures (default: the current one; the docs' "
                   "figures: --out-dir docs/img)")
    p.add_argument("--summary", default=None, help="optional JSON file with the numbers shown")
    args = p.parse_args(argv)
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    summary = {"two_dof": run_two_dof(out_dir)}
    report("2-DOF", summary["two_dof"])
    if not args.two_dof_only:
        summary["paris"] = run_paris(out_dir)
        report("Paris mode 20", summary["paris"])
    if args.summary:
        Path(args.summary).write_text(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
