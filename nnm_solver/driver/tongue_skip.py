r"""Internal-resonance tongues met during a continuation: point labels, skipping, and tongue branches.

Label.  Each converged orbit's harmonic content is measured in mass-normalised modal coordinates
(the amplitude of harmonic k is |a_k| with q(t) = sum Re(a_k e^{i k w t}); analysis/harmonics.py
explains the weighting).  An orbit whose strongest harmonic k >= 2 carries at least RESONANCE_FRACTION
of the amplitude is labelled ``"tongue k:1"`` (a k:1 internal resonance with a mode near k times its
frequency), otherwise ``"backbone"``.

Skip (``continue_nnm(..., tongues="skip")``).  When the continuation steps from a backbone orbit into
a tongue, the tongue is recorded (ratio k:1, the partner mode: the linear mode closest to the k-th
harmonic's shape, entry energy and frequency, and the entry orbit) and the continuation jumps over
it: from the last backbone orbit, energy targets E_b (1 + delta), delta = 2 %, 5 %, 10 %, 20 %, 50 %,
are tried; the guess is the backbone orbit rescaled to that energy with its period extrapolated along
the backbone's tangent, corrected on the hyperplane tangent to the energy level set (so the energy
stays ~E_t); the jump is accepted when the corrected orbit is labelled ``backbone`` again.  The
continuation then restarts there, with the backbone's direction.  If no target works, the branch
follows the tongue (and says so in the tongue record).

A tongue as its own branch (``continue_tongue(branch, tongue)``): the continuation restarts at the
tongue's entry orbit towards the tongue and follows it through its turning points until it is back
on the backbone above the entry energy (or closes a loop, or reaches energy_max).
"""
from __future__ import annotations

import math

import numpy as np

from ..analysis.harmonics import RESONANCE_FRACTION
from ..continuation.engine import CorrectorFailure, _energy_slope, correct, tangent
from ..fourier import fourier_coefficients

__all__ = ["harmonic_label", "TongueSkipper", "RESONANCE_FRACTION", "leaves_backbone", "same_tongue", "tongue_record",
           "fundamental_share", "partner_harmonic", "upward_tangent"]

#: highest harmonic looked at for labels
LABEL_HARMONICS = 25

#: relative energy jumps tried over a tongue
JUMPS = (0.02, 0.05, 0.1, 0.2, 0.5)

#: a harmonic below this fraction of the fundamental is absent (is_fold: a fold of the family, not a tongue)
FOLD_CONTENT = 1e-6

#: skip mode: a harmonic k >= 2 growing to this fraction of the amplitude marks a tongue's entrance
SKIP_FRACTION = 0.05

#: a jump from the skeleton lands on the backbone family within this relative frequency of the skeleton
#: (the single-harmonic truncation: 0.1-0.3 % on the aircraft's mode 20 at 8-12 J)
FAMILY_TOL = 0.01


def harmonic_label(Q, n=LABEL_HARMONICS):
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


def partner_harmonic(Q, r, n=LABEL_HARMONICS):
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


def partner_mode(system, Q, k):
    """1-based linear mode whose shape is closest (MAC, modal coordinates are mass-normalised) to the
    k-th harmonic of the modal orbit Q, and that MAC."""
    a = fourier_coefficients(Q, k)[k]
    A = np.column_stack([a.real, a.imag])
    U, S, _ = np.linalg.svd(A, full_matrices=False)
    shape = U[:, 0]
    m = shape ** 2 / max(shape @ shape, 1e-300)        # MAC with each unit modal vector
    r = int(np.argmax(m))
    return r + 1, float(m[r])


def is_fold(Q, k):
    """Does the modal orbit Q hold no harmonic k (below FOLD_CONTENT of its fundamental)?  Then a departure from
    the backbone into Q is not a k:1 internal resonance but a fold of the family at the fundamental (e.g. the
    springs' saddle at one harmonic): there is no partner harmonic to name."""
    if Q is None or k is None or k < 2:
        return False
    c = np.linalg.norm(fourier_coefficients(Q, k), axis=1)
    return bool(c[k] < FOLD_CONTENT * max(c[1], 1e-300))


def tongue_record(system, Q, k, bpoint, point, entry_index):
    """The record of a k:1 tongue entered from the backbone point ``bpoint`` (index entry_index) into ``point``
    (Q: its modal orbit): ratio, partner mode (partner_mode) and the entry and inside orbits.  Where Q holds
    no harmonic k (is_fold), or k = 1 (a point off the family with no harmonic k >= 2: its partner at the
    fundamental, if any, is the skeleton's to name, ends.family_end), the record is a fold of the family: label
    "fold", order 1, partner_mode 0."""
    fold = k <= 1 or is_fold(Q, k)
    mode, mac = partner_mode(system, Q, k) if Q is not None and not fold else (0, float("nan"))
    extra = dict(note="the energy turned back with no harmonic k >= 2 in the orbit: a fold of the family, "
                      "not an internal resonance") if fold else {}
    k = 1 if fold else k
    return dict(ratio=[k, 1], order=k, label="fold" if fold else f"tongue {k}:1", partner_mode=mode,
                partner_mac=mac, **extra,
                entry_index=entry_index, entry_energy=bpoint.energy, entry_frequency_hz=bpoint.frequency_hz,
                entry_period=bpoint.period, entry_x0=np.asarray(bpoint.x0).tolist(),
                entry_v0=np.asarray(bpoint.v0).tolist(), inside_x0=np.asarray(point.x0).tolist(),
                inside_v0=np.asarray(point.v0).tolist(), inside_period=point.period)


def harmonic_content(point):
    """(k, fraction) of the strongest harmonic k >= 2 of a point's orbit (measured when it was recorded)."""
    return getattr(point, "_content", (1, 0.0))


def leaves_backbone(point, bpoint):
    """Skip mode: does ``point`` leave the backbone (last backbone point ``bpoint``)?  Its energy turned back (a
    backbone continued in energy has no fold); where the skeleton measured it (labels.py), its label says; else
    a harmonic k >= 2 carries SKIP_FRACTION of its amplitude and grew by half since the last backbone point."""
    if point.energy < bpoint.energy:
        return True
    if getattr(point, "_dev", None) is not None:
        return point.label != "backbone"
    k, frac = harmonic_content(point)
    kb, frac_b = harmonic_content(bpoint)
    return k > 1 and frac >= SKIP_FRACTION and frac >= 1.5 * (frac_b if kb == k else 0.0)


def same_tongue(a, b):
    """Is tongue record b the tongue a entered again?  Same order and partner mode, entry frequency within
    0.1 %, and b's entry at most 10 % above a's exit (or a's entry when it has no exit)."""
    E_out = a.get("exit_energy", a["entry_energy"])
    return (a["order"] == b["order"] and a["partner_mode"] == b["partner_mode"]
            and abs(b["entry_frequency_hz"] / a["entry_frequency_hz"] - 1) < 1e-3
            and b["entry_energy"] <= 1.1 * E_out)


def upward_tangent(prob, u, J, previous):
    """The branch's tangent at the orbit u (Jacobian J), oriented so that the energy increases.  After a jump
    the old backbone tangent ``previous`` (only used to pick the null direction of J) may point either way
    at the landing orbit, and a restart that goes down in energy re-enters the tongue just jumped: the
    backbone continued in energy has no fold, so beyond a tongue it goes on upwards."""
    w = prob.scale(u) if hasattr(prob, "scale") else np.ones(len(u))
    p = tangent(J, previous, w)
    return -p if _energy_slope(prob.energy, u, p) < 0 else p


def level_set(prob, guess, settings, tol, w=None):
    """(u, J): the orbit of ``prob`` nearest ``guess`` on its energy level set (corrected on the hyperplane
    tangent to it), or (None, None) when the corrector fails."""
    w = prob.scale(guess) if w is None else w
    row = prob.energy_gradient(guess) / (w * w)          # correct() constrains (w^2 row)^T (u - guess) = 0
    try:
        u, J, _, _ = correct(prob, guess, row / np.linalg.norm(w * row), settings, tol, w)
    except (CorrectorFailure, np.linalg.LinAlgError):      # no convergence, or a singular Jacobian on the way
        return None, None
    return u, J


class TongueSkipper:
    """Jumps over a tongue from the last backbone point (see the module docstring).

    system : the branch's ModalSystem; skeleton : a callable returning the branch's Skeleton (skeleton.py),
    or None (then only the rescaled backbone orbits are tried).
    """

    def __init__(self, problem, settings, tol, system=None, skeleton=None, labels=None):
        self.problem = problem
        self.settings = settings
        self.tol = tol
        self.system = system
        self.skeleton = skeleton
        self.labels = labels               # FamilyLabels (labels.py): is a landing orbit on the family?

    def jump(self, u_b, p_b, E_b, E_base=None, k=None, partner_hz=None):
        """A backbone orbit u beyond the tongue, from the backbone point u_b (tangent p_b, energy E_b):
        first the skeleton's orbits where its k f has left the band around the partner's frequency
        partner_hz (Hz), then energies E_base (1 + delta) from the rescaled backbone orbit (E_base >= E_b:
        the highest energy seen at the tongue's entrance); the landing orbit must have less than
        SKIP_FRACTION in harmonic k (and, from the skeleton, lie on its side of the band).  Returns
        (u, J, how) (how: "skeleton at E J" or the relative energy jump) or None."""
        E_base = E_b if E_base is None else E_base
        prob = self.problem
        w = prob.scale(u_b) if hasattr(prob, "scale") else np.ones(len(u_b))
        self.attempts = 0
        for guess, how, side in self._skeleton_guesses(E_b, k, partner_hz):
            self.attempts += 1
            u, J = self._level_set(guess, w)
            # beyond the band the k-th harmonic may still exceed SKIP_FRACTION (the partner is near): the orbit
            # must be on the family (labels.py), on the skeleton's side of the band (if any)
            if u is not None and self._on_family(u, k, E_b) and (side is None or self._on_side(u, k, partner_hz, side)):
                return u, J, how
        slope = (prob.energy(u_b + 1e-6 * p_b) - prob.energy(u_b - 1e-6 * p_b)) / 2e-6
        for delta in JUMPS:
            guess = self._guess(u_b, p_b, slope, E_b, E_base * (1 + delta))
            if guess is None:
                continue
            self.attempts += 1
            u, J = self._level_set(guess, w)
            if u is not None and self._lands(u, k, E_base) and not self._beyond_family(u):
                return u, J, f"a jump of {100 * delta:g} % in energy"
        return None

    def _skeleton_guesses(self, E_base, k, partner_hz):
        """(u guess, description, side of the band) for the skeleton's orbits beyond the k:1 band."""
        prob = self.problem
        if self.skeleton is None or not (hasattr(prob, "from_state") or hasattr(prob, "from_family")):
            return
        fold = k is None                   # a fold of the family (is_fold): no band, the family just above it
        if not fold and (not partner_hz or k < 2):
            return
        sk = self.skeleton()
        if sk is None:
            return
        band = [] if fold else sk.targets(E_base, k, partner_hz)
        # then the family just above the entry (a tongue the skeleton does not place, or one re-entered)
        # (from where the skeleton's own stepping found the backbone's sheet beyond the tongue, when it did: below
        # that its points are the tongue's sheet)
        starts = [E * (1 + 1e-9) for E in sk.sheet_starts if E_base < E <= E_base * (1 + JUMPS[-1])
                  and sk.covers(E * (1 + 1e-9))][:1]
        near = starts + [E_base * (1 + d) for d in JUMPS if sk.covers(E_base * (1 + d))
                         and not any(abs(E_base * (1 + d) / E_t - 1) < 0.01 for E_t in band)
                         and not (starts and E_base * (1 + d) < starts[0])]
        for E_t in band + near:
            side = np.sign(k * sk.frequency_at(E_t) / partner_hz - 1.0) if E_t in band else None
            refined = sk.family_orbit(self.system, E_t, self.settings, self.tol)
            if refined is None:
                continue
            fam, u = refined
            if hasattr(prob, "from_family") and getattr(prob, "sys", None) is fam.sys:
                guess = prob.from_family(fam, u)       # harmonic balance: the family's harmonics as they are
            else:
                q0, v0, T = fam.state(u)
                if fam.sys is not self.system:         # the skeleton's basis is not the branch's (a Ritz basis)
                    q0, v0 = (self.system.to_modal(fam.sys.to_physical(x)) for x in (q0, v0))
                guess = prob.from_state(q0, v0, T)
            yield guess, f"the skeleton's orbit at {E_t:.4g} J", side

    def _level_set(self, guess, w):
        return level_set(self.problem, guess, self.settings, self.tol, w)

    def _on_family(self, u, k, E_base):
        """Is the orbit u above E_base and on the backbone family: labelled backbone against the skeleton
        (labels.py), or, without one, by its harmonic content and within FAMILY_TOL of the skeleton?"""
        prob = self.problem
        E = prob.energy(u)
        if not E > E_base:
            return False
        f = 1.0 / prob.state(u)[2]
        label, dev = self._family_label(u, E, f)
        if dev is not None:
            return label == "backbone"
        f_sk = self.skeleton().frequency_at(E)
        return self._lands(u, k, E_base, RESONANCE_FRACTION) and bool(abs(f / f_sk - 1.0) <= FAMILY_TOL)

    def _beyond_family(self, u):
        """Is the orbit u where the backbone family does not exist: above the skeleton's energy maximum (a
        softening family's saddle) or beyond where it ends in a k:1 resonance (labels.py: dev = inf)?  A jump
        that lands there has left the family (e.g. onto another family above the saddle), not jumped a tongue."""
        _, dev = self._family_label(u, self.problem.energy(u), 1.0 / self.problem.state(u)[2])
        return dev is not None and math.isinf(dev)

    def _family_label(self, u, E, f):
        """(label, dev) of the orbit u (energy E J, frequency f Hz) against the skeleton (labels.py); dev is None
        without labels or where no skeleton covers E (then the label is the harmonic content's)."""
        label, kk, frac, amps = harmonic_label(self.problem.modal_orbit(u))
        if self.labels is None:
            return label, None
        return self.labels.label(E, f, label, kk, frac, amps)

    def _lands(self, u, k, E_base, limit=SKIP_FRACTION):
        """Is u a backbone orbit (label, less than ``limit`` in harmonic k) above E_base?"""
        prob = self.problem
        label, kk, frac, amps = harmonic_label(prob.modal_orbit(u))
        tot = np.sum(amps[1:]) if amps is not None else 0.0
        frac_k = amps[k] / tot if (k is not None and amps is not None and tot > 0 and k < len(amps)) else frac
        return label == "backbone" and frac_k < limit and prob.energy(u) > E_base

    def _on_side(self, u, k, partner_hz, side):
        """Is the orbit u's k f on the far side of the band (the side the skeleton moved to)?"""
        f = 1.0 / self.problem.state(u)[2]
        return np.sign(k * f / partner_hz - 1.0) == side

    def _guess(self, u_b, p_b, slope, E_b, E_t):
        """The backbone orbit scaled to energy E_t, its period (last entry) moved along the tangent."""
        prob = self.problem
        u = u_b.copy()
        lo, hi = 0.0, 1.0                               # log of the amplitude factor c with E(c u) = E_t
        while True:
            trial = u_b.copy()
            trial[:-1] *= np.exp(hi)
            if prob.energy(trial) >= E_t or hi > 10:
                break
            hi *= 2
        if hi > 10:
            return None
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            trial = u_b.copy()
            trial[:-1] *= np.exp(mid)
            lo, hi = (mid, hi) if prob.energy(trial) < E_t else (lo, mid)
        u[:-1] *= np.exp(hi)
        if slope != 0:
            u[-1] = u_b[-1] + p_b[-1] * (E_t - E_b) / slope
        return u
