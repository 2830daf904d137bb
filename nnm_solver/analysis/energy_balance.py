r"""The resonance peak of a forced, damped response predicted from a conservative NNM (energy balance).

At light damping the forced response at phase resonance (the force in quadrature with the displacement,
i.e. along the velocity) is the conservative NNM of the same frequency: the force and the damping only keep
it alive.  Over one period the damping forces then take out the work the force puts in (Hill et al., 2015):

    W_d = int_0^T v(t)^T C v(t) dt = int_0^T sum_k 2 zeta_k w_k q_k'(t)^2 dt          (+ v^T C_matrix v)
    W_f = int_0^T alpha f^T v(t) cos(omega t + phi) dt,  largest over phi:  alpha (T / 2) |f^T V_1|

with q' the modal velocities of the NNM orbit and V_1 the complex fundamental of its velocity.  W_f = W_d
gives the force scale alpha at which the NNM is the phase-resonant response to alpha f cos(omega t):

    alpha = W_d / ((T / 2) |f^T V_1|) = W_d / (pi |f^T X_1|).

Along a backbone alpha grows with the amplitude; the response to the force scale s peaks where alpha = s,
at that NNM's frequency and amplitude.  ``energy_balance`` returns alpha along a backbone (``EnergyBalance``);
``EnergyBalance.at_scale(s, dof)`` the predicted peak.  Exact for the single-mode (and single-harmonic)
limit at vanishing damping; first order in the damping otherwise (docs/forced.md).
"""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError
from ..model.damping import modal_damping
from ..model.modal import modal_system
from ..results.branch import Branch
from ..results.forced import peak_of_samples

__all__ = ["EnergyBalance", "energy_balance"]


class EnergyBalance:
    """The forcing needed along an NNM backbone for each of its orbits to be the phase-resonant response.

    backbone : the Branch; force (n,) N: the forcing pattern f; damping (n,) modal ratios;
    frequency_hz (N,), energy (N,) J: the backbone's; force_scale (N,): alpha, the multiple of ``force``
    at which each NNM is the resonance peak; damping_work (N,) J: the work of the damping forces over one
    period; force_work (N,) J: the work of ``force`` (scale 1) in quadrature with the displacement.
    ``amplitude(dof)``: peak displacement of each NNM orbit (m); ``at_scale(s, dof)``: the predicted peak.
    """

    def __init__(self, backbone, force, damping, frequency_hz, energy, force_scale, damping_work, force_work,
                 amplitudes, samples):
        self.backbone = backbone
        self.model = backbone.model
        self.force = force
        self.damping = damping
        self.frequency_hz = frequency_hz
        self.energy = energy
        self.force_scale = force_scale
        self.damping_work = damping_work
        self.force_work = force_work
        self._amplitudes = amplitudes          # (N, n) peak |x| of every DOF
        self.samples = samples

    def __len__(self):
        return len(self.frequency_hz)

    def __repr__(self):
        return (f"EnergyBalance(points={len(self)}, force_scale={self.force_scale.min():.3g}.."
                f"{self.force_scale.max():.3g})" if len(self) else "EnergyBalance(empty)")

    def _dof(self, dof):
        n = self.model.n
        if isinstance(dof, str):
            labels = self.model.dof_labels or []
            if dof not in labels:
                raise NNMInputError(f"no DOF labelled {dof!r} in the model (labels: model.dof_labels)")
            return labels.index(dof)
        if not isinstance(dof, (int, np.integer)) or isinstance(dof, bool) or not -n <= dof < n:
            raise NNMInputError(f"dof {dof!r} is out of range: the model has DOFs 0..{n - 1}")
        return int(dof) % n

    def amplitude(self, dof):
        """Peak displacement max_t |x_dof(t)| (N,) m of each backbone orbit."""
        return self._amplitudes[:, self._dof(dof)].copy()

    def scale_of(self, force):
        """The scale s with force = s * self.force (NNMInputError if the two are not parallel)."""
        f = np.asarray(force, dtype=float).reshape(-1)
        ref = self.force
        s = float(f @ ref / (ref @ ref))
        if np.linalg.norm(f - s * ref) > 1e-9 * np.linalg.norm(f):
            raise NNMInputError("this force is not a multiple of the energy balance's force pattern")
        return s

    def at_scale(self, scale=1.0, dof=0):
        """The resonance peak predicted for the force ``scale`` * force: dict(frequency_hz, amplitude (at dof, m),
        energy, index (fractional backbone index)) at the first backbone point where force_scale reaches
        ``scale`` (linear interpolation between the two points bracketing it); None if it is not reached."""
        a = self.force_scale
        amp = self.amplitude(dof)
        for j in range(len(a) - 1):
            lo, hi = sorted((a[j], a[j + 1]))
            if lo <= scale <= hi and hi > lo:
                w = (scale - a[j]) / (a[j + 1] - a[j])
                lerp = lambda c: float((1 - w) * c[j] + w * c[j + 1])   # noqa: E731
                return dict(frequency_hz=lerp(self.frequency_hz), amplitude=lerp(amp), energy=lerp(self.energy),
                            index=j + w)
        return None


def energy_balance(backbone, force, damping, damping_matrix=None, samples=256):
    """For each point of the conservative NNM ``backbone`` (a Branch), the force scale alpha at which that NNM
    is the phase-resonant response to alpha * force cos(omega t) with the given damping (module docstring).

    force : (n,) N, the forcing pattern (as for ``forced_response``); damping : modal damping ratio (one, or
    one per mode); damping_matrix : optional (n, n) N s/m; samples : time samples of each orbit.
    Returns an EnergyBalance (frequency_hz, force_scale, amplitude(dof), at_scale(s, dof)).
    """
    if not isinstance(backbone, Branch):
        raise NNMInputError(f"backbone must be an nnm_solver.Branch (from continue_nnm), got {type(backbone).__name__}")
    if not len(backbone):
        raise NNMInputError("the backbone is empty")
    model = backbone.model
    n = model.n
    try:
        f = np.asarray(force, dtype=float)
    except (TypeError, ValueError):
        raise NNMInputError(f"force must be numbers, got {type(force).__name__}") from None
    if f.shape != (n,):
        raise NNMInputError(f"force has {f.size} entries, the model has {n} DOFs: give one amplitude (N) per DOF")
    if not np.all(np.isfinite(f)):
        raise NNMInputError("force contains NaN or infinite entries")
    if not np.any(f != 0):
        raise NNMInputError("force is zero everywhere: no force can balance the damping")
    samples = int(samples)
    if samples < 8:
        raise NNMInputError("samples must be at least 8")
    zeta, c_modal, Cq = modal_damping(model, damping, damping_matrix)
    system = modal_system(model)
    N = len(backbone)
    Wd, Wf, amps = np.zeros(N), np.zeros(N), np.zeros((N, n))
    theta = 2 * np.pi * np.arange(samples) / samples
    for i in range(N):
        t, x, v = backbone.orbit(i, samples)
        T = float(backbone.period[i])
        qd = system.to_modal(v)                                   # modal velocities (samples, n)
        power = (qd * qd) @ c_modal if c_modal is not None else np.sum((qd @ Cq) * qd, axis=1)   # v^T C v
        Wd[i] = T * float(np.mean(power))
        g = v @ f                                                 # f^T v(t)
        G1 = 2.0 * np.mean(g * np.exp(-1j * theta))
        Wf[i] = 0.5 * T * abs(G1)
        amps[i] = peak_of_samples(x)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(Wf > 0, Wd / Wf, np.inf)
    return EnergyBalance(backbone, f, zeta, backbone.frequency_hz.copy(), backbone.energy.copy(), alpha, Wd, Wf,
                         amps, samples)
