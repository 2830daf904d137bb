r"""The harmonic content of an orbit: which harmonic k >= 2 it carries, which mode carries it, how much.

Measured in mass-normalised modal coordinates (the amplitude of harmonic k is |a_k| with q(t) = sum Re(a_k
e^{i k w t}); analysis/harmonics.py explains the weighting).  An orbit whose strongest harmonic k >= 2 carries at
least RESONANCE_FRACTION of the amplitude has the content label ``"tongue k:1"``, otherwise ``"backbone"``: the
label of points where no skeleton says more (labels.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..analysis.harmonics import RESONANCE_FRACTION
from ..analysis.hb_series import basis_fourier_coefficients, basis_harmonic_amplitudes
from ..fourier import fourier_coefficients
from .settings import LabelSettings

__all__ = ["Content", "content_of", "harmonic_label", "partner_harmonic", "fundamental_share", "partner_mode",
           "is_fold", "tongue_partner"]

_LABELS = LabelSettings()


@dataclass(frozen=True)
class Content:
    """The harmonic content of a modal orbit: k (strongest harmonic >= 2), fraction (its share of the orbit's
    amplitude), partner_k (the harmonic >= 2 the other modes carry most: the order of a partner's resonance),
    share (the fundamental's share), amplitudes (per harmonic, or None when unknown), coefficients (the orbit's
    complex Fourier coefficients a_0..a_n (n + 1, modes), or None: what ``partners`` is made from, when read), series
    ((HBBasis, A (N_b, modes)) of a harmonic-balance orbit whose coefficients were not made: they are made from it
    when read), r (the followed mode, 0-based), orbit (the modal orbit's samples (S, modes), or None:
    ``tongue_partner``)."""

    k: int = 1
    fraction: float = 0.0
    partner_k: int = 1
    share: float = 1.0
    amplitudes: np.ndarray | None = None
    coefficients: np.ndarray | None = field(default=None, repr=False)
    series: tuple | None = field(default=None, repr=False)
    r: int = 0
    orbit: np.ndarray | None = field(default=None, repr=False)

    @property
    def label(self):
        """The content label (module docstring)."""
        return f"tongue {self.k}:1" if self.k > 1 and self.fraction >= RESONANCE_FRACTION else "backbone"

    @property
    def order(self):
        """The order of the tongue a point off the family is in: the partner's harmonic where one carries it, else
        the strongest k >= 2; 1 (another mode at the fundamental) when no harmonic k >= 2 is present."""
        if self.fraction < _LABELS.fold_content:
            return 1
        return self.partner_k if self.partner_k > 1 else max(self.k, 2)

    @property
    def partners(self):
        """(harmonics + 1, modes): |a_kj| of every other mode j and harmonic k over the orbit's amplitude, the followed
        mode's column zero; None when unknown.  Made when read (only a point off the family needs it:
        ``tongue_partner``), O(n modes)."""
        tot = float(np.sum(self.amplitudes[1:])) if self.amplitudes is not None else 0.0
        c = self.coefficients
        if c is None and self.series is not None:
            c = basis_fourier_coefficients(*self.series, len(self.amplitudes) - 1)
        if c is None or not tot > 0:
            return None
        partners = np.abs(c)
        partners[:, self.r] = 0.0
        return partners / tot


def content_of(Q, r, n=_LABELS.label_harmonics, coefficients=None, series=None):
    """The Content of the modal orbit Q (samples, modes) of the followed mode r (0-based); Content() for None.
    coefficients : its Fourier coefficients a_0..a_n (n + 1, modes) when known (fourier.fourier_coefficients of Q);
    series : (HBBasis, A (N_b, modes)) of a harmonic-balance orbit, whose harmonic amplitudes are read from its basis
    coefficients (analysis/hb_series.basis_harmonic_amplitudes; its complex coefficients only if ``partners`` is read).
    The amplitude of each harmonic and the other modes' (partner_harmonic's) in one pass."""
    if Q is None:
        return Content()
    if series is not None and coefficients is None:
        c = None
        amps, others = basis_harmonic_amplitudes(*series, n, r)
    else:
        c = fourier_coefficients(Q, n) if coefficients is None else coefficients
        amps, others = _harmonic_amplitudes(c, r)
    label, k, fraction = _label_of(amps)
    tot = float(np.sum(amps[1:]))
    if not tot > 0 or len(amps) < 3 or Q.shape[1] < 2:
        partner = 1
    else:
        partner = int(np.argmax(others[2:]) + 2)
    return Content(k, fraction, partner, fundamental_share(amps), amps, c, series if c is None else None, int(r),
                   np.asarray(Q, dtype=float))


def _harmonic_amplitudes(c, r):
    """(amps, others) (n + 1,) each: |a_k| of the complex coefficients c (n + 1, modes) over all modes and over the
    modes but r (np.linalg.norm's sums of |a_kj|^2, in another order: the same to round-off)."""
    v = np.ascontiguousarray(c).view(float)            # (n + 1, 2 modes): real and imaginary parts side by side
    sq = v * v
    amps2 = sq.sum(axis=1)
    sq[:, 2 * r:2 * r + 2] = 0.0
    return np.sqrt(amps2), np.sqrt(sq.sum(axis=1))


def _label_of(amps):
    """(label, k, fraction) of the harmonic amplitudes ``amps`` (harmonic_label)."""
    tot = float(np.sum(amps[1:]))
    if not tot > 0:
        return "backbone", 1, 0.0
    fr = amps / tot
    k = int(np.argmax(fr[2:]) + 2) if len(fr) > 2 else 1
    if k > 1 and fr[k] >= RESONANCE_FRACTION:
        return f"tongue {k}:1", k, float(fr[k])
    return "backbone", k, float(fr[k])


def tongue_partner(content, frequency_hz, system, share=_LABELS.partner_share, mismatch=_LABELS.partner_mismatch,
                   match=_LABELS.partner_match):
    """(k, j): the harmonic k >= 2 and mode j (0-based) of the k:1 resonance a point off the family is in when its
    strongest partner harmonic is not that resonance, from its Content (its orbit and partner shares), its frequency
    (Hz) and the ModalSystem of its orbit's modal coordinates; None (the strongest partner harmonic, content.order,
    names it) otherwise.

    A k:1 internal resonance is where k f meets a partner's frequency, which the orbit itself raises (a beam's membrane
    tension).  A partner mode j's frequency is averaged along the orbit, f_j^2 = (w_j^2 + mean_t d^2 V_nl / dq_j^2
    (q(t))) / (2 pi)^2 (a Mathieu average: it put a clamped beam ROM's 5:1, 9:1 and 7:1 within 0.4-1 % of where the
    branch meets them).  The strongest partner harmonic can be a forced one far from any resonance: a clamped beam's
    mode 3 carries NNM 1's third harmonic everywhere (the cubic coupling), and its 9:1 with mode 5 at 7.15 J (f_5 = 9.04
    f, mode 3 at 3.94 f: 24 % from 3 f) had been labelled 3:1.  So where the strongest pair's k f lies more than
    ``mismatch`` from its mode's frequency, the pair holding at least ``share`` of the strongest share whose k f lies
    nearest its mode's, within ``match``, names the tongue.  (On a full FE beam, whose modal basis holds the axial
    modes, the average along a transverse mode keeps the membrane coupling unrelaxed: 16 % high for mode 3 at the
    hinged beam's 5:1, where no other pair matches and the strongest names it, rightly.)  None too when the orbit or
    the system is unknown or they do not match (another modal basis), and where the partners hold no harmonic k >= 2
    (below fold_content: round-off, e.g. a one-harmonic orbit; content.order is 1 there)."""
    Q = content.orbit
    a = content.partners
    if Q is None or a is None or system is None or getattr(system, "n", -1) != Q.shape[1] or a.shape[0] < 3:
        return None
    a = a[2:]
    top = float(a.max())
    if not (top >= _LABELS.fold_content and frequency_hz > 0):   # no harmonic k >= 2 (an HB orbit at H = 1): none
        return None
    q = Q[:: max(1, len(Q) // 32)]                      # 32 samples of the orbit are enough for a mean
    f_eff = {}

    def off(k, j):                                      # |k f / f_j - 1| of harmonic k (>= 2) and mode j
        if j not in f_eff:
            w2 = float(system.omega2[j] + np.mean(system.curvature(q, j)))
            f_eff[j] = np.sqrt(w2) / (2 * np.pi) if w2 > 0 else np.nan
        return abs(k * frequency_hz / f_eff[j] - 1.0)

    k0, j0 = np.unravel_index(int(np.argmax(a)), a.shape)
    if not off(int(k0) + 2, int(j0)) > mismatch:        # the strongest is resonant (or unknown): it names the tongue
        return None
    best, best_m = None, match
    for k, j in np.argwhere(a >= share * top):
        m = off(int(k) + 2, int(j))
        if m <= best_m:
            best, best_m = (int(k) + 2, int(j)), m
    return best


def harmonic_label(Q, n=_LABELS.label_harmonics, c=None):
    """(label, k, fraction, amplitudes) of a periodic modal orbit Q (samples, n_dof) (c: its Fourier coefficients,
    when known)."""
    if Q is None:
        return "backbone", 1, 0.0, None
    amps = np.linalg.norm(fourier_coefficients(Q, n) if c is None else c, axis=1)
    return _label_of(amps) + (amps,)


def partner_harmonic(Q, r, n=_LABELS.label_harmonics, c=None):
    """The harmonic k >= 2 (and its fraction of the orbit's amplitude) that the modes other than the followed
    one (0-based r) carry most: the order of the resonance a partner is in.  (1, 0) when there is none.  c: the
    orbit's Fourier coefficients, when known (not changed)."""
    if Q is None or Q.shape[1] < 2:
        return 1, 0.0
    c = fourier_coefficients(Q, n) if c is None else np.array(c)
    tot = float(np.sum(np.linalg.norm(c, axis=1)[1:]))
    c[:, r] = 0.0
    amps = np.linalg.norm(c, axis=1)
    if not tot > 0 or len(amps) < 3:
        return 1, 0.0
    k = int(np.argmax(amps[2:]) + 2)
    return k, float(amps[k] / tot)


def fundamental_share(amps):
    """Fraction of a modal orbit's amplitude (harmonic_label's ``amps``) in its fundamental; 1 when unknown."""
    if amps is None or len(amps) < 2:
        return 1.0
    tot = float(np.sum(amps[1:]))
    return float(amps[1] / tot) if tot > 0 else 1.0


def partner_mode(Q, k, r=None):
    """1-based linear mode whose shape is closest (MAC, modal coordinates are mass-normalised) to the
    k-th harmonic of the modal orbit Q, and that MAC; with r (0-based, the followed mode) the followed mode's own
    k-th harmonic is left out (the partner is another mode)."""
    a = fourier_coefficients(Q, k)[k]
    if r is not None and Q.shape[1] > 1:
        a[r] = 0.0
    A = np.column_stack([a.real, a.imag])
    U, S, _ = np.linalg.svd(A, full_matrices=False)
    shape = U[:, 0]
    m = shape ** 2 / max(shape @ shape, 1e-300)        # MAC with each unit modal vector
    r = int(np.argmax(m))
    return r + 1, float(m[r])


def is_fold(Q, k, fold_content=_LABELS.fold_content):
    """Does the modal orbit Q hold no harmonic k (below fold_content of its fundamental)?  Then a departure from
    the backbone into Q is not a k:1 internal resonance but a fold of the family at the fundamental (e.g. the
    springs' saddle at one harmonic): there is no partner harmonic to name."""
    if Q is None or k is None or k < 2:
        return False
    c = np.linalg.norm(fourier_coefficients(Q, k), axis=1)
    return bool(c[k] < fold_content * max(c[1], 1e-300))
