"""Information about the picked orbit: numbers (frequency, energy, stability, Floquet
multipliers, MAC with the linear modes) and the time series / Fourier coefficients of
chosen DOFs over one period (like the seed paper's Fig. 12)."""
from __future__ import annotations

import math

from dataclasses import dataclass

import numpy as np

import nnm_solver
from nnm_solver import analysis, cubic_scaling, fourier_amplitudes

from .animation import format_length
from .numbering import nearest_row

N_HARMONICS = 15


@dataclass
class PointData:
    """One orbit of a branch, as computed by the solver for the branch's own springs.

    energy J, frequency Hz, period s, stable bool, floquet (2n,) complex, mac (n,),
    t (S,) s, x (S, n) m over one period, harmonics (N_HARMONICS+1, n) m.  stability_known: whether the
    point's Floquet multipliers were computed (``Branch.stability_known``; without them ``stable`` is True for
    want of a test, and the texts say the stability was not computed).
    """

    energy: float
    frequency: float
    period: float
    stable: bool
    floquet: np.ndarray
    mac: np.ndarray
    t: np.ndarray
    x: np.ndarray
    harmonics: np.ndarray
    note: str = ""                 # e.g. why another point than the requested one is shown
    description: str = ""          # what the orbit is, from its own harmonic content (solver's describe_orbit)
    stability_known: bool = True   # False: no multipliers computed (floquet off), ``stable`` says nothing

    def scaled(self, ratio):
        """The same orbit when every k3 is multiplied by ``ratio`` (exact scaling law:
        displacements / sqrt(ratio), energy / ratio, same frequency and multipliers)."""
        if abs(ratio - 1.0) < 1e-15:
            return self
        law = cubic_scaling(ratio)
        return PointData(self.energy * law.energy, self.frequency, self.period, self.stable, self.floquet,
                         self.mac, self.t, self.x * law.amplitude, self.harmonics * law.amplitude, self.note,
                         self.description, self.stability_known)


def orbit_samples(branch):
    """Samples per period for the viewer: the solver's (``analysis.orbit_samples``: for shooting
    branches their own Newmark steps per period, the orbit the solver converged), at least 64 and
    at most 400."""
    return int(np.clip(analysis.orbit_samples(branch), 64, 400))


#: the Point tab's note on an orbit integrated by scipy while the solver's integrator is being compiled
REFERENCE_NOTE = ("orbit integrated by scipy's DOP853 from the stored state (Branch.reference_motion) while the "
                  "solver's integrator is being compiled; the solver's own orbit replaces it when it is ready")


#: the scipy orbit is not tried when it would take more steps (about 3 s; a model with very high modal
#: frequencies: the viewer then waits for the compiled integrator)
REFERENCE_MAX_STEPS = 20000


def point_data(branch, s, samples=None, reference=False):
    """PointData at fractional index s of ``branch`` (the solver interpolates between points).
    samples : per period (default: the branch's own time step, see orbit_samples).
    reference : the orbit by ``Branch.reference_motion`` (scipy, no compiled kernel: what the viewer shows
    before numba has compiled the branch's integrator), without the harmonic description (it would
    integrate the orbit again with the integrator); the note says so.  RuntimeError if that orbit would
    take more than REFERENCE_MAX_STEPS steps or cannot be integrated."""
    if samples is None:
        samples = orbit_samples(branch)
    i = nearest_row(s, len(branch))          # Branch.interpolate's nearer neighbour
    note = REFERENCE_NOTE if reference else ""

    def motion(b, j):
        if reference:
            return b.reference_motion(j, samples=samples, max_steps=REFERENCE_MAX_STEPS)
        return b.motion(j, samples=samples)

    if abs(s - i) < 1e-9 or len(branch) == 1:
        b, j = branch, i
        t, x = motion(b, j)
    else:
        b, j = branch.interpolate(float(s)), 0
        try:
            t, x = motion(b, j)
        except RuntimeError:       # the interpolated state is not on an orbit: show the nearest point
            b, j = branch, i
            t, x = motion(b, j)
            note = f"the orbit between points could not be integrated; showing computed point {i + 1}"
    harm = fourier_amplitudes(np.asarray(x, dtype=float), N_HARMONICS)
    try:
        mac = np.asarray(b.mac_to_linear(j), dtype=float)
    except Exception:
        mac = np.zeros(0)
    floquet = np.asarray(b.floquet[j]) if getattr(b, "floquet", None) is not None and len(b.floquet) else np.zeros(0)
    known = getattr(b, "stability_known", None)
    known = True if known is None else bool(np.asarray(known, dtype=bool).reshape(-1)[j])
    description = ""
    if not reference:
        try:
            description = nnm_solver.describe_orbit(b, j)
        except Exception:  # a description is a bonus: never lose the point for it
            description = ""
    return PointData(energy=float(b.energy[j]), frequency=float(b.frequency_hz[j]), period=float(b.period[j]),
                     stable=bool(b.stable[j]), floquet=floquet, mac=mac, t=np.asarray(t, dtype=float),
                     x=np.asarray(x, dtype=float), harmonics=harm, note=note, description=description,
                     stability_known=known)


#: samples per period of a linear mode's orbit (one harmonic: a few samples would do)
LINEAR_SAMPLES = 64


def linear_mode_point(model, k, freqs, shapes, amplitude=1.0, samples=LINEAR_SAMPLES):
    """PointData of linear mode ``k`` (1-based) of ``model``: x(t) = a phi_k cos(2 pi f_k t) over one
    period, phi_k mass-normalised (``model.linear_modes()``: ``freqs`` Hz, ``shapes[:, k-1]``), a =
    ``amplitude``.  Energy: the linear mode's at that amplitude, (2 pi f_k a)^2 / 2; stable, no Floquet
    multipliers; MAC (mass-weighted) with every linear mode (1 with itself)."""
    freqs = np.asarray(freqs, dtype=float)
    shapes = np.asarray(shapes, dtype=float)
    if not 1 <= int(k) <= len(freqs):
        raise ValueError(f"linear mode {k} does not exist (valid: 1..{len(freqs)})")
    k = int(k)
    f = float(freqs[k - 1])
    if not np.isfinite(f) or f <= 1e-9 * max(float(np.max(np.abs(freqs))), 1e-300):
        raise ValueError(f"linear mode {k} has no frequency ({f:.3g} Hz: a rigid-body mode): nothing to animate")
    phi = shapes[:, k - 1]
    period = 1.0 / f
    t = np.arange(int(samples)) * period / int(samples)
    x = float(amplitude) * np.cos(2.0 * np.pi * f * t)[:, None] * phi[None, :]
    mac = np.asarray(nnm_solver.mac(phi, shapes, model.M)[0], dtype=float)
    modal_mass = float(phi @ np.asarray(model.M @ phi).reshape(-1))
    energy = 0.5 * (2.0 * np.pi * f * float(amplitude)) ** 2 * modal_mass
    note = (f"linear mode: x(t) = a φ{k} cos(2π f{k} t), φ{k} mass-normalised, a = {float(amplitude):.3g} chosen "
            "for display; the energy is the linear mode's at that amplitude (no Floquet multipliers: linear)")
    return PointData(energy=energy, frequency=f, period=period, stable=True, floquet=np.zeros(0, complex),
                     mac=mac, t=t, x=x, harmonics=fourier_amplitudes(x, N_HARMONICS), note=note,
                     description="")


def linear_mode_title(model, linear_freqs, k, freq=True):
    """'linear mode 2 (out-of-phase mode), f = 1.234 Hz' (the label when the model has one)."""
    labels = model.mode_labels or []
    lab = f" ({labels[k - 1]})" if k - 1 < len(labels) and labels[k - 1] else ""
    return f"linear mode {k}{lab}" + (f", f = {float(linear_freqs[k - 1]):.6g} Hz" if freq else "")


def method_text(branch):
    """How a branch's orbits were computed, in a few words: 'shooting, newmark, 200 steps per period',
    'harmonic balance, 7 harmonics'; '' when the branch does not say."""
    st = getattr(branch, "settings", None)
    method = getattr(st, "method", "")
    if method == "shooting":
        integ = getattr(st, "integrator", None) or "newmark"
        spp = getattr(st, "steps_per_period", None)
        return f"shooting, {integ}" + (f", {int(spp)} steps per period" if spp else "")
    if method == "harmonic_balance":
        h = getattr(st, "harmonics", None)
        return "harmonic balance" + (f", {int(h)} harmonics" if h else "")
    return ""


def parse_dofs(text, n, auto):
    """DOF indices from 'auto' or a comma/space separated list of 0-based indices."""
    text = (text or "").strip().lower()
    if text in ("", "auto"):
        return list(auto)
    out = []
    for tok in text.replace(",", " ").split():
        try:
            d = int(tok)
        except ValueError:
            raise ValueError(f"DOF '{tok}' is not an integer (use 0-based DOF indices or 'auto')") from None
        if not 0 <= d < n:
            raise ValueError(f"DOF {d} does not exist (valid: 0..{n - 1})")
        out.append(d)
    return out[:6]


def auto_dofs(model, x, count=2):
    """DOFs to plot by default: the spring DOFs moving most, else the DOFs moving most."""
    amp = np.ptp(np.asarray(x), axis=0)
    spring_dofs = sorted({s.dof for s in model.springs if hasattr(s, "dof")}
                         | {s.other for s in model.springs if getattr(s, "other", None) is not None})
    cands = spring_dofs if spring_dofs else list(range(model.n))
    cands = sorted(cands, key=lambda d: -amp[d])
    return cands[:count]


def dof_name(model, d):
    if model.dof_labels is not None:
        return f"{d} ({model.dof_labels[d]})"
    return f"DOF {d}"


#: a DOF is named in the harmonic notes when it moves at least this fraction of the largest DOF motion
DOF_NOTE_FRACTION = 0.01
#: DOFs named in the harmonic notes at most
DOF_NOTE_MAX = 3


def ordinal(k):
    """'1st', '2nd', '3rd', '4th', ..., '11th', ..."""
    return f"{k}{'th' if 10 <= k % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10, 'th')}"


def dof_harmonic_notes(pd):
    """DOFs (moving at least DOF_NOTE_FRACTION of the most moving one) whose strongest higher harmonic
    exceeds their first: [(dof, k, A_k / A_1)], largest ratio first."""
    h = np.asarray(pd.harmonics, dtype=float)          # (K+1, n) amplitudes per DOF
    if h.ndim != 2 or h.shape[0] < 3 or not h.size:
        return []
    n = h.shape[1]
    size = h[1:].max(axis=0)
    k = np.argmax(h[2:], axis=0) + 2
    ak, a1 = h[k, np.arange(n)], h[1]
    ratio = ak / np.maximum(a1, 1e-300)
    idx = np.flatnonzero((size >= DOF_NOTE_FRACTION * size.max()) & (size > 0) & (ak > a1))
    return [(int(d), int(k[d]), float(ratio[d])) for d in idx[np.argsort(-ratio[idx])]]


def orbit_lines(pd, model):
    """Markdown lines describing the orbit: its harmonic content over all DOFs (the solver's
    ``describe_orbit``, mass-weighted), and the single DOFs whose higher harmonic exceeds the first
    (inside a k:1 tongue the DOF of the spring may move mostly at k times the frequency while the
    mass-weighted content is still dominated by harmonic 1)."""
    lines = []
    if pd.description:
        lines.append(f"- orbit (harmonic content mass-weighted over all {model.n} DOFs, i.e. of the modal "
                     f"amplitudes): {pd.description}")
    notes = dof_harmonic_notes(pd)
    if notes:
        parts = [f"{dof_name(model, d)}: its {ordinal(k)} harmonic is {r:.3g} x its 1st"
                 for d, k, r in notes[:DOF_NOTE_MAX]]
        more = f" (and {len(notes) - DOF_NOTE_MAX} more DOFs)" if len(notes) > DOF_NOTE_MAX else ""
        lines.append("- single DOFs where a higher harmonic exceeds the 1st: " + "; ".join(parts) + more)
    return lines


#: what a point label means (by its first word: 'backbone', 'tongue')
LABEL_WORDS = {"backbone": " (the fundamental NNM family)", "tongue": " (inside an internal-resonance tongue)"}


def info_markdown(pd, model, linear_freqs, k3_factor=1.0, where="", top=5, label=None, freq_error=None,
                  method=""):
    """Markdown summary of the orbit (units: J, Hz, s).  label: the point's label ('backbone',
    'tongue 3:1'); freq_error: its estimated relative frequency error (the solver's, if the branch
    has one); method: how the branch was computed (``method_text``: the integrator), on the same line;
    k3_factor None: no k3 line (a linear mode)."""
    lines = [f"**{where}**" if where else "",
             f"- frequency **{pd.frequency:.6g} Hz** (period {pd.period:.4g} s)"
             + ((f", estimated relative error {freq_error:.1e} (± {abs(freq_error) * pd.frequency:.2g} Hz)"
                 if math.isfinite(freq_error) else ", not resolved by the harmonics (no orbit with two more near it)")
                if freq_error is not None else "")
             + (f" · {method}" if method else ""),
             f"- energy **{pd.energy:.4g} J**",
             *([f"- k3 factor x{k3_factor:.3g}"] if k3_factor is not None else []),
             (f"- stability: **{'stable' if pd.stable else 'UNSTABLE'}**" if pd.stability_known else
              "- stability: **not computed** (no Floquet multipliers for this point: computed with floquet off)"),
             *([f"- label: **{label}**{LABEL_WORDS.get(str(label).split(' ')[0], '')}"] if label else []),
             *orbit_lines(pd, model)]
    if pd.note:
        lines.append(f"- note: {pd.note}")
    mu = np.asarray(pd.floquet).reshape(-1) if pd.stability_known else np.zeros(0, complex)
    mu = mu[np.isfinite(mu)]                      # NaN: not computed
    if mu.size:
        mod = np.abs(mu)
        order = np.argsort(-mod)[:6]
        mults = ", ".join(f"{mu[k].real:+.4f}{mu[k].imag:+.4f}i" for k in order)
        lines.append(f"- Floquet multipliers: max |mu| = {mod.max():.6f}; largest: {mults}")
    if pd.mac.size:
        order = np.argsort(-pd.mac)[:top]
        labels = model.mode_labels or []
        rows = ["", "| mode | f lin (Hz) | MAC |", "|---|---|---|"]
        for k in order:
            lab = f" {labels[k]}" if k < len(labels) else ""
            rows.append(f"| {k + 1}{lab} | {linear_freqs[k]:.4g} | {pd.mac[k]:.3f} |")
        lines += rows
    return "\n".join(l for l in lines if l is not None)


SERIES_COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#17becf"]


def length_unit(values):
    """(scale, unit) so that values * scale are of order 1..1000: m, mm, µm or nm."""
    v = float(np.max(np.abs(values))) if np.size(values) else 0.0
    for unit, f in (("m", 1.0), ("mm", 1e-3), ("µm", 1e-6)):
        if v >= f:
            return 1.0 / f, unit
    return 1e9, "nm"


def uplot_time_series(pd, model, dofs):
    """(data, series) for a uPlot chart of x_d(t) over one period, t in units of T; the
    displacements in the unit that suits them (uPlot rounds small numbers)."""
    from viser import uplot

    tt = np.append((pd.t - pd.t[0]) / pd.period, 1.0)
    scale, unit = length_unit(pd.x[:, dofs]) if dofs else (1.0, "m")
    data = [tt] + [scale * np.append(pd.x[:, d], pd.x[0, d]) for d in dofs]
    series = [uplot.Series(label="t/T")] + [
        uplot.Series(label=f"{dof_name(model, d)} ({unit})", stroke=SERIES_COLORS[j % len(SERIES_COLORS)],
                     width=1.5, dash=(6.0, 4.0) if j % 2 else ())
        for j, d in enumerate(dofs)]
    return tuple(data), tuple(series)


def uplot_harmonics(pd, model, dofs):
    """(data, series) for a uPlot chart of log10 Fourier amplitudes (m) vs harmonic k
    (plotted as log10 values: uPlot's own log axis labels small numbers poorly)."""
    from viser import uplot

    K = pd.harmonics.shape[0]
    top = max(float(pd.harmonics[:, dofs].max()) if dofs else 1.0, 1e-300)
    data = [np.arange(K, dtype=float)] + [np.log10(np.maximum(pd.harmonics[:, d], top * 1e-12)) for d in dofs]
    series = [uplot.Series(label="k")] + [
        uplot.Series(label=f"log10 |c_k| {dof_name(model, d)}", stroke=SERIES_COLORS[j % len(SERIES_COLORS)],
                     width=1.0, points={"show": True, "size": 7.0})
        for j, d in enumerate(dofs)]
    return tuple(data), tuple(series)


def peak_text(peak_max, amplification, auto):
    return (f"peak displacement **{format_length(peak_max)}**, shown x{amplification:.3g}"
            + (" (auto)" if auto else ""))
