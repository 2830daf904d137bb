r"""The harmonic content of an orbit: which harmonic k >= 2 it carries, which mode carries it, how much.

Measured in mass-normalised modal coordinates (the amplitude of harmonic k is |a_k| with q(t) = sum Re(a_k
e^{i k w t}); analysis/harmonics.py explains the weighting).  An orbit whose strongest harmonic k >= 2 carries at
least RESONANCE_FRACTION of the amplitude has the content label ``"tongue k:1"``, otherwise ``"backbone"``: the
label of points where no skeleton says more (labels.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.harmonics import RESONANCE_FRACTION
from ..fourier import fourier_coefficients
from .settings import LabelSettings

__all__ = ["Content", "content_of", "harmonic_label", "partner_harmonic", "fundamental_share", "partner_mode",
           "is_fold", "grown_harmonic"]

_LABELS = LabelSettings()


@dataclass(frozen=True)
class Content:
    """The harmonic content of a modal orbit: k (strongest harmonic >= 2), fraction (its share of the orbit's
    amplitude), partner_k (the harmonic >= 2 the other modes carry most: the order of a partner's resonance),
    share (the fundamental's share), amplitudes (per harmonic, or None when unknown), partners ((harmonics + 1,
    modes): |a_kj| of every other mode j and harmonic k over the orbit's amplitude, the followed mode's column zero; None
    when unknown: ``grown_harmonic``)."""

    k: int = 1
    fraction: float = 0.0
    partner_k: int = 1
    share: float = 1.0
    amplitudes: np.ndarray | None = None
    partners: np.ndarray | None = None

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


def content_of(Q, r, n=_LABELS.label_harmonics):
    """The Content of the modal orbit Q (samples, modes) of the followed mode r (0-based); Content() for None."""
    if Q is None:
        return Content()
    label, k, fraction, amps = harmonic_label(Q, n)
    c = np.abs(fourier_coefficients(Q, n))
    c[:, r] = 0.0
    tot = float(np.sum(amps[1:]))
    return Content(k, fraction, partner_harmonic(Q, r, n)[0], fundamental_share(amps), amps,
                   c / tot if tot > 0 else None)


def grown_harmonic(content, reference, harmonics, floor=_LABELS.growth_floor):
    """(k, j): the harmonic k >= 2 and mode j (0-based) of the other modes that grew most from ``reference`` (the
    Content of the backbone family's orbit at the same energy, which resolves harmonics up to ``harmonics``) to
    ``content``: the resonance a point off the family is in.  Each share a of the orbit is scored by
    a ln(a / (a_ref + floor x the largest share)): large and risen.  A harmonic the other modes carry on the family as
    much (a clamped beam's mode 3 carries NNM 1's third harmonic, forced by the cubic coupling, everywhere) does not
    name the tongue, the one that rose does: that beam's 9:1 with mode 5 at 7.15 J (mode 5's 9th harmonic 1.5e-3 of
    the orbit on the family, 2.5e-3 at the tongue's first point; mode 3's third 1.9e-2 in both) and its 7:1 with
    mode 5 at 38 J (7th: 1.8e-2 -> 2.6e-2).  None (no score above 0) where none rose: next to a tongue the family's
    own orbit can carry more of the resonant harmonic than the point (the soft 2-DOF chain's 3:1 at 0.068 J: 0.10
    against 0.07), and the strongest partner harmonic (content.order) names it.  None too when either table is
    unknown or they do not match (another modal basis).  Harmonics above ``harmonics`` are not compared."""
    a = None if content is None else content.partners
    b = None if reference is None else reference.partners
    top_k = min(int(harmonics), a.shape[0] - 1, b.shape[0] - 1) if a is not None and b is not None else 0
    if top_k < 2 or a.shape[1] != b.shape[1]:
        return None
    a, b = a[2:top_k + 1], b[2:top_k + 1]
    top = float(a.max())
    if not top > 0:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        score = np.where(a > 0, a * np.log(a / (b + floor * top)), 0.0)
    k, j = np.unravel_index(int(np.argmax(score)), score.shape)
    return (int(k) + 2, int(j)) if score[k, j] > 0 else None


def harmonic_label(Q, n=_LABELS.label_harmonics):
    """(label, k, fraction, amplitudes) of a periodic modal orbit Q (samples, n_dof)."""
    if Q is None:
        return "backbone", 1, 0.0, None
    amps = np.linalg.norm(fourier_coefficients(Q, n), axis=1)
    tot = float(np.sum(amps[1:]))
    if not tot > 0:
        return "backbone", 1, 0.0, amps
    fr = amps / tot
    k = int(np.argmax(fr[2:]) + 2) if len(fr) > 2 else 1
    if k > 1 and fr[k] >= RESONANCE_FRACTION:
        return f"tongue {k}:1", k, float(fr[k]), amps
    return "backbone", k, float(fr[k]), amps


def partner_harmonic(Q, r, n=_LABELS.label_harmonics):
    """The harmonic k >= 2 (and its fraction of the orbit's amplitude) that the modes other than the followed
    one (0-based r) carry most: the order of the resonance a partner is in.  (1, 0) when there is none."""
    if Q is None or Q.shape[1] < 2:
        return 1, 0.0
    c = fourier_coefficients(Q, n)
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
