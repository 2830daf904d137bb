"""A virtual ground vibration test of the Paris-like aircraft: the seed paper's §4.1.3 loop, from the test lab to the model.

1. Test: a damped time simulation of assets/paris.h5 (548 DOFs, the 4 cubic springs k3 = -1e13 N/m^3 at the tip
   tanks' attachments, modal damping zeta) under a band-limited swept sine (36 -> 34 Hz, downwards) from two
   shakers, one at the rear attachment of each tank (tank side, vertical, signed like mode 20's shape: the
   second, anti-symmetric wing torsion), then a resonance decay: the shakers stop at the largest response and
   the structure rings down.  Integrator: average-acceleration Newmark in the modal coordinates, the implicit
   step solved on the 4 spring deformations only (``nnm_solver.integrators.newmark.solve_stages``), step
   1/4096 s, checked against solve_ivp (DOP853) in tests/test_testlab_gvt.py.
2. Measured: the vertical accelerations on both sides of the two rear attachments (1 % noise) and the shaker
   forces, written as UFF 58 (``nnm.write_uff58``) and READ BACK (``nnm.read_measured``): the test lab's files.
   Channels: node = attachment number (1 R front wing side, 2 R front tank side, 3 R rear wing side, 4 R rear
   tank side, 5..8 the same on the left wing), direction uz.
3. Restoring force surface at each rear attachment (``nnm.rfs``: Newton's law at the tank side, m_c its
   diagonal mass in the model, the shaker force there measured) and the cubic law fitted to it: the
   identified k3 against the model's -1e13 N/m^3.
4. Backbones of mode 20 (condensed harmonic balance): the nominal model's, the identified model's (every k3 set
   to the mean identified value), the points of the resonance decay (envelope and instantaneous frequency of
   the band-passed tank acceleration) and the factor on k3 fitted to those points (``nnm.fit_backbone``).

    python examples/virtual_gvt.py                    # 20 s sweep; about a minute here (wall time printed)
    python examples/virtual_gvt.py --fast             # 6 s sweep, for the test (about 20 s)
    python examples/virtual_gvt.py --plot gvt.png --out-dir /tmp/gvt

Written (only where asked; default a temporary folder): gvt_accelerations.uff (the measured record), gvt.h5
(the model and its nominal backbone) and gvt_decay_backbone.csv (the decay points) for
``nnm-view gvt.h5 --measured gvt_decay_backbone.csv``, and, with --plot, the figure (RFS stiffness curves,
backbones with the decay points).
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

import nnm_solver as nnm  # noqa: E402
from nnm_solver.integrators.newmark import solve_stages  # noqa: E402
from nnm_solver.model.modal import modal_system  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODE = 20
K3_MODEL = -1e13
#: the measured points: (attachment number used as the UFF node, model DOF label)
POINTS = [(3, "wing R rear (wing side) uz"), (4, "wing R rear (tank side) uz"), (7, "wing L rear (wing side) uz"),
          (8, "wing L rear (tank side) uz")]
#: the two rear connections: (name, tank-side node, wing-side node); the shakers act at the tank sides
CONNECTIONS = [("right rear", 4, 3), ("left rear", 8, 7)]


@dataclass(frozen=True)
class TestPlan:
    """The virtual test: force amplitude per shaker (N), modal damping ratio, sweep f_start -> f_end (Hz) over
    ``sweep_s`` (s), decay record ``decay_s`` (s), integration rate and record rate (Hz), accelerometer noise
    (fraction of each channel's RMS), random seed."""

    force: float = 80.0
    zeta: float = 0.01
    f_start: float = 36.0
    f_end: float = 34.0
    sweep_s: float = 20.0
    decay_s: float = 1.5
    rate_hz: float = 4096.0
    record_hz: float = 2048.0
    noise: float = 0.01
    seed: int = 1


FAST = TestPlan(sweep_s=6.0)


def sweep_force(plan, t):
    """Force per shaker (N) at times t: a linear sweep f_start -> f_end with a 0.5 s ramp-in."""
    rate = (plan.f_end - plan.f_start) / plan.sweep_s
    return plan.force * np.sin(2 * np.pi * (plan.f_start * t + 0.5 * rate * t * t)) * np.minimum(t / 0.5, 1.0)


@dataclass
class State:
    """Modal state of the simulation at step k: q, v, a (modal), d (spring deformations)."""

    k: int
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    d: np.ndarray


def simulate(model, zeta, pattern, load, h, nsteps, dofs, start=None, every=1, keep=None):
    """Damped forced response by average-acceleration Newmark in mass-normalised modal coordinates:

        q'' + 2 zeta w q' + w^2 q + Bq^T g(Bq q) = Phi^T pattern load(t)

    (all modes of the model, damping ratio zeta for every mode), the implicit step reduced to the spring
    deformations as in the conservative kernel (integrators/newmark.py).  pattern (n,) force shape (N per unit
    load), load(t) scalar; dofs: model DOFs recorded every ``every`` steps.  Returns (t (m,), x (m, r) m,
    a (m, r) m/s^2, final State, states) with ``states`` the State at each step number in ``keep``."""
    system = modal_system(model)
    w2 = system.omega2
    c = 2.0 * zeta * np.sqrt(np.maximum(w2, 0.0))
    _, Bq, powers, coeffs, kinks = system.kernel
    Dinv = 1.0 / (1.0 + 0.5 * h * c + 0.25 * h * h * w2)
    G = 0.25 * h * h * (Bq * Dinv) @ Bq.T
    BqD = np.ascontiguousarray(Bq * (0.25 * h * h * Dinv))
    p = system.Phi.T @ pattern
    R = np.ascontiguousarray(system.Phi[list(dofs)])
    s = start or State(0, np.zeros(len(w2)), np.zeros(len(w2)), np.zeros(len(w2)), np.zeros(Bq.shape[0]))
    q, v, a, d = s.q.copy(), s.v.copy(), s.a.copy(), s.d.copy()
    rows = range(s.k + every, s.k + nsteps + 1, every)
    t_out, x_out, a_out, states = [], [], [], {}
    keep = set(keep or ())
    for k in range(s.k + 1, s.k + nsteps + 1):
        qs = q + h * v + 0.25 * h * h * a
        vs = v + 0.5 * h * a
        r = load(k * h) * p - c * vs - w2 * qs
        d, _, g, _, ok = solve_stages(Bq @ qs + BqD @ r, G, 1, len(d), powers, coeffs, kinks, d, True)
        if not ok:
            raise RuntimeError(f"Newmark step {k} did not converge (the springs' softening folded the step)")
        a = (r - Bq.T @ g) * Dinv
        q = qs + 0.25 * h * h * a
        v = vs + 0.5 * h * a
        if (k - s.k) % every == 0:
            t_out.append(k * h)
            x_out.append(R @ q)
            a_out.append(R @ a)
        if k in keep:
            states[k] = State(k, q.copy(), v.copy(), a.copy(), d.copy())
    assert len(t_out) == len(rows)
    return np.array(t_out), np.array(x_out), np.array(a_out), State(s.k + nsteps, q, v, a, d), states


def shaker_pattern(model):
    """Unit vertical forces at the two rear tank-side DOFs, signed like mode 20's shape there."""
    _, shapes = model.linear_modes()
    f = np.zeros(model.n)
    for node, label in POINTS:
        if node in (c[1] for c in CONNECTIONS):
            j = model.dof_labels.index(label)
            f[j] = np.sign(shapes[j, MODE - 1])
    return f


def run_test(model, plan):
    """The swept-sine run and the resonance decay: (sweep record t, a (m, 4), F (m, 2)), (decay t, a) and the
    time of the largest response (s)."""
    dofs = [model.dof_labels.index(lab) for _, lab in POINTS]
    pattern = shaker_pattern(model)
    h = 1.0 / plan.rate_hz
    every = int(round(plan.rate_hz / plan.record_hz))
    nsteps = int(round(plan.sweep_s * plan.rate_hz))
    keep = range(0, nsteps + 1, int(0.05 * plan.rate_hz))           # checkpoints every 50 ms
    t, x, acc, _, states = simulate(model, plan.zeta, pattern, lambda s: sweep_force(plan, s), h, nsteps, dofs,
                                    every=every, keep=keep)
    rel = np.abs(x[:, 1] - x[:, 0])
    k_peak = int(round(t[int(np.argmax(rel))] * plan.rate_hz))
    k0 = max(k for k in states if k <= k_peak)
    forced = k_peak - k0
    td, _, ad, _, _ = simulate(model, plan.zeta, pattern,
                               lambda s: sweep_force(plan, s) if s <= k_peak * h + 1e-12 else 0.0, h,
                               forced + int(round(plan.decay_s * plan.rate_hz)), dofs, start=states[k0], every=every)
    shakers = [j for j, (node, _) in enumerate(POINTS) if node in (c[1] for c in CONNECTIONS)]
    F = np.outer(sweep_force(plan, t), pattern[[dofs[j] for j in shakers]])
    free = td > k_peak * h
    return (t, acc, F), (td[free], ad[free]), k_peak * h


def measured_record(t, acc, F, plan, model):
    """The accelerations (1 % noise) and forces as a Measurement, the way a test system delivers them."""
    rng = np.random.default_rng(plan.seed)
    noisy = acc + plan.noise * np.sqrt(np.mean(acc ** 2, axis=0)) * rng.standard_normal(acc.shape)
    shaker_nodes = [c[1] for c in CONNECTIONS]
    labels = [f"node {n} uz" for n, _ in POINTS] + [f"node {n} uz force" for n in shaker_nodes]
    return nnm.Measurement(kind="time", axis=t, data=np.column_stack([noisy, F]), labels=tuple(labels),
                           quantities=("acceleration",) * 4 + ("force",) * 2, units=("m/s^2",) * 4 + ("N",) * 2,
                           file_units=("m/s^2",) * 4 + ("N",) * 2, nodes=tuple([n for n, _ in POINTS] + shaker_nodes),
                           directions=("uz",) * 6, references=("",) * 6, sampling=plan.record_hz,
                           source=f"virtual GVT of {model.name}")


def decay_points(t, a, count=12, band=(30.0, 40.0)):
    """Backbone points from a resonance decay: (displacement amplitude (m), frequency (Hz)) of the acceleration
    ``a`` band-passed around the mode, from its analytic signal: envelope / (2 pi f)^2 and the instantaneous
    frequency, each averaged over 5 periods; the first 0.15 s (other modes ringing), the last 0.25 s (the
    filter's end) and amplitudes below a tenth of the largest (noise) left out."""
    from scipy.signal import butter, hilbert, sosfiltfilt

    fs = 1.0 / (t[1] - t[0])
    y = sosfiltfilt(butter(4, band, "bandpass", fs=fs, output="sos"), a)
    z = hilbert(y)
    env = np.abs(z)
    f = np.gradient(np.unwrap(np.angle(z)), t) / (2 * np.pi)
    window = int(round(5 / np.mean(band) * fs))
    strong = np.flatnonzero(env >= 0.1 * np.max(env[int(0.15 * fs):]))      # down to a tenth of the amplitude
    end = min(int(strong[-1]), len(t) - int(0.25 * fs)) - window
    starts = np.linspace(int(0.15 * fs), end, count).astype(int)
    freq = np.array([np.mean(f[i:i + window]) for i in starts])
    amp = np.array([np.mean(env[i:i + window]) for i in starts]) / (2 * np.pi * freq) ** 2
    return amp, freq


def frequency_at(backbone, amplitude):
    """Frequency (Hz) where the backbone's amplitude first reaches ``amplitude`` (linear between its points)."""
    a, f = backbone.amplitude, backbone.frequency_hz
    i = int(np.argmax(a >= amplitude))
    if a[i] < amplitude or i == 0:
        return float("nan")
    return float(f[i - 1] + (f[i] - f[i - 1]) * (amplitude - a[i - 1]) / (a[i] - a[i - 1]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default=str(ROOT / "assets" / "paris.h5"))
    ap.add_argument("--fast", action="store_true", help="a 6 s sweep instead of 20 s (the test's run)")
    ap.add_argument("--out-dir", default=None, help="folder for the UFF record (default: a temporary folder)")
    ap.add_argument("--plot", default=None, help="write the figure (RFS and backbones) to this image file")
    args = ap.parse_args(argv)
    plan = FAST if args.fast else TestPlan()
    load0 = os.getloadavg()
    t_all = time.perf_counter()
    model = nnm.load_model(args.model)
    freqs, _ = model.linear_modes()
    print(f"load average {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}")
    print(f"{model.name}: {model.n} DOFs; mode {MODE} at {freqs[MODE - 1]:.4f} Hz; zeta {100 * plan.zeta:g} %; "
          f"sweep {plan.f_start:g} -> {plan.f_end:g} Hz in {plan.sweep_s:g} s, {plan.force:g} N per shaker")

    t0 = time.perf_counter()
    (t, acc, F), (td, ad), t_peak = run_test(model, plan)
    t_sim = time.perf_counter() - t0
    print(f"simulation: {len(t) + len(td)} samples at {plan.record_hz:g} Hz ({(t[-1] + td[-1] - t_peak):.1f} s "
          f"simulated) in {t_sim:.1f} s; largest response at t = {t_peak:.3f} s")

    out = Path(args.out_dir or tempfile.mkdtemp(prefix="virtual_gvt_"))
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    path = nnm.write_uff58(out / "gvt_accelerations.uff", measured_record(t, acc, F, plan, model))
    record = nnm.read_measured(path)
    print(f"UFF 58: {path} ({path.stat().st_size / 1e6:.1f} MB, {record.n_channels} channels, written and read "
          f"back in {time.perf_counter() - t0:.1f} s)")

    laws = []
    for name, tank, wing in CONNECTIONS:
        mass = float(model.M[model.dof_labels.index(dict(POINTS)[tank]), model.dof_labels.index(dict(POINTS)[tank])])
        surface = nnm.rfs(record, f"node {tank} uz", f"node {wing} uz", mass, force=f"node {tank} uz force")
        law = surface.fit("cubic")
        laws.append((name, surface, law))
        x = surface.displacement[surface.valid]
        print(f"RFS {name}: m_c = {mass:.2f} kg, |x_rel| up to {1e3 * np.max(np.abs(x)):.3f} mm: k = {law.k:.4g} N/m, "
              f"k3 = {law.k3:.4g} N/m^3 ({law.k3 / K3_MODEL:.3f} x the model's {K3_MODEL:.0e}), "
              f"residual {law.residual:.3f}")
    k3_id = float(np.mean([law.k3 for _, _, law in laws]))
    print(f"identified k3 (mean of the two): {k3_id:.4g} N/m^3, {k3_id / K3_MODEL:.3f} x the model's")

    t0 = time.perf_counter()
    identified = model.with_springs([nnm.CubicSpring(dof=s.dof, other=s.other, k3=k3_id) for s in model.springs])
    dof = model.dof_labels.index(dict(POINTS)[CONNECTIONS[0][1]])
    amp, freq = decay_points(td, ad[:, [n for n, _ in POINTS].index(CONNECTIONS[0][1])])
    hb = dict(method="hb", harmonics=5, condensed=True)
    lam, phi = model.eigensolution
    energy = 2.0 * lam[MODE - 1] * (np.max(amp) / abs(phi[dof, MODE - 1])) ** 2   # fit_backbone's default
    branches = {}
    for key, m in (("nominal", model), ("identified", identified)):
        branches[key] = nnm.continue_nnm(m, MODE, energy, **hb)
        branches[key].name = f"NNM {MODE} {key} (k3 = {m.springs[0].k3:.3g} N/m^3)"
    fit = nnm.fit_backbone(model, MODE, dof, amp, freq, energy_max=energy, amplitude_rtol=0.02, **hb)
    t_bb = time.perf_counter() - t0
    print(f"resonance decay: {len(amp)} backbone points at {model.dof_labels[dof]}, "
          f"{1e3 * amp.min():.3f}..{1e3 * amp.max():.3f} mm, {freq.min():.3f}..{freq.max():.3f} Hz")
    for key, b in branches.items():
        f_at = frequency_at(nnm.amplitude_backbone(b, dof), np.max(amp))
        print(f"backbone {key}: {len(b)} points, {b.frequency_hz[0]:.4f} -> {b.frequency_hz[-1]:.4f} Hz up to "
              f"{b.energy[-1]:.3g} J; at {1e3 * np.max(amp):.3f} mm: {f_at:.4f} Hz")
    print(f"fit_backbone on the decay points: k3 factor {fit.k3_factor:.3f} (95 % {fit.confidence[0]:.3f}.."
          f"{fit.confidence[1]:.3f}), k3 = {fit.k3_factor * K3_MODEL:.4g} N/m^3, residual {fit.residual:.2f}")
    print(f"backbones and fit: {t_bb:.1f} s")

    viewer = write_for_viewer(out, model, branches["nominal"], dof, amp, freq)
    print(f"for the viewer: nnm-view {viewer[0]} --measured {viewer[1]} (k3 slider at {k3_id / K3_MODEL:.3f}: "
          f"the identified model's branch beside the nominal one, in grey)")
    if args.plot:
        plot(args.plot, laws, branches, dof, amp, freq, fit)
        print(f"plot: {args.plot}")
    load1 = os.getloadavg()
    print(f"wall time {time.perf_counter() - t_all:.1f} s (load average {load1[0]:.2f} at the end)")
    return 0


def write_for_viewer(out, model, branch, dof, amp, freq):
    """gvt.h5 (the model and its nominal backbone) and gvt_decay_backbone.csv (the decay points, mm) in ``out``,
    each written next to its target and renamed over it."""
    from nnm_solver.files.h5file import atomic_file

    h5, csv = out / "gvt.h5", out / "gvt_decay_backbone.csv"
    with atomic_file(h5) as tmp:
        nnm.save_model(tmp, model)
        nnm.save_branch(tmp, branch)
    with atomic_file(csv) as tmp:
        np.savetxt(tmp, np.column_stack([freq, 1e3 * amp]), delimiter=",", comments="",
                   header=f"frequency (Hz), {model.dof_labels[dof]} (mm)")
    return h5, csv


def plot(path, laws, branches, dof, amp, freq, fit):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from nnm_solver.identification.backbone_plot import plot_backbone

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    for ax, (name, surface, law) in zip(axes[:2], laws):
        x, f = surface.stiffness_curve()
        ax.plot(1e3 * x, f, ".", ms=2, label="|velocity| < 5 % of peak")
        grid = np.linspace(x.min(), x.max(), 200)
        ax.plot(1e3 * grid, law.elastic_force(grid) + law.offset, "r-", label=f"k x + k3 x^3, k3 = {law.k3:.3g}")
        ax.set_xlabel("relative displacement (mm)")
        ax.set_ylabel("restoring force (N)")
        ax.set_title(f"stiffness curve, {name} attachment")
        ax.legend(fontsize=8)
    plot_backbone(list(branches.values()), dof, measured=(amp, freq), ax=axes[2], scale=1e3, unit="mm",
                  measured_label="resonance decay")
    axes[2].set_title(f"mode {MODE}: backbones, fitted k3 factor {fit.k3_factor:.3f}")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
