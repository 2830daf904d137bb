"""The methods' settings: what a user asks for (``continue_nnm(model, mode, energy_max, Shooting(...) |
HarmonicBalance(...))``) and, the same objects with every None resolved, what a branch records (``branch.settings``,
HDF5 attribute ``settings_json``): a branch's settings passed back as ``method=`` compute it the same way.

Each method's settings know how to rebuild the periodic orbit of a point from its stored columns
(``orbit``), so a Branch never switches on the method's name.  Settings read like a mapping as well
(``branch.settings["steps_per_period"]``, ``.get``), as in the first release, and old files whose
settings lack a key get the documented default.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..errors import NNMInputError

__all__ = ["MethodSettings", "Shooting", "HarmonicBalance", "ShootingSettings", "HarmonicBalanceSettings",
           "settings_from_dict", "ResultSettings", "RESULTS"]


@dataclass(frozen=True)
class MethodSettings:
    """Settings every method shares.

    tol : corrector tolerance (relative).  The branch's record (set by the driver; on a request they are
    ignored: continue_nnm's energy_max and floquet decide): energy_max : J, the requested end of the branch;
    k3_factor : the branch's springs relative to the model it was computed for (scaling law); floquet : whether
    multipliers were computed.
    """

    method: ClassVar[str] = ""
    record_fields: ClassVar[tuple] = ("energy_max", "k3_factor", "floquet", "cutoff_hz")
    tol: float = 1e-6
    energy_max: float = math.inf
    k3_factor: float = 1.0
    floquet: bool = True

    # mapping-style access (first-release API)
    def __getitem__(self, key):
        if key == "method":
            return self.method
        if key in self._fields():
            return getattr(self, key)
        raise KeyError(key)

    def get(self, key, default=None):
        try:
            return self[key]
        except KeyError:
            return default

    def __contains__(self, key):
        return key == "method" or key in self._fields()

    def keys(self):
        return ["method", *self._fields()]

    @classmethod
    def _fields(cls):
        return [f.name for f in dataclasses.fields(cls)]

    def as_dict(self):
        """Plain dict (JSON-ready) with the method's name under "method"."""
        return {"method": self.method, **{k: getattr(self, k) for k in self._fields()}}

    def replace(self, **changes):
        return dataclasses.replace(self, **changes)

    def orbit(self, branch, i, samples):  # pragma: no cover - every method overrides it
        raise NotImplementedError


@dataclass(frozen=True)
class Shooting(MethodSettings):
    """Shooting (orbits/shooting.py) with the exact monodromy: what a user asks for (``continue_nnm(model, mode,
    energy_max, Shooting(...))``) and, with every None resolved, what the branch records (``branch.settings``).

    integrator : one of nnm.INTEGRATORS ("gauss6": order 6; "newmark": the seed paper's, order 2; "gauss4");
    steps_per_period : time steps a period (None: the integrator's default, integrators/registry.py: gauss6 100,
        Newmark 200); rounded up to a multiple of 4 for quarter-period shooting of symmetric orbits; on a branch:
        the steps of its first point (``branch.steps``: each point's, raised by freq_tol);
    symmetric : half-period shooting (None: when every element's force is odd); reversible : orbits starting at
        rest (None: with symmetric, or for even forces);
    tol : relative periodicity tolerance ||H|| / ||z0|| (seed eq. 11);
    freq_tol : raise the steps where a point's estimated frequency error exceeds it (None: never; driver/settings.py
        says why 1e-4);
    error_estimate : estimate each point's relative frequency error (branch.freq_error; step doubling);
    max_steps_per_period : the most steps per period the freq_tol refinement goes to.
    Files written before a field existed read as they were computed: Newmark at 200 steps, no target.
    """

    method: ClassVar[str] = "shooting"
    name: ClassVar[str] = "shooting"
    integrator: str = "gauss6"
    steps_per_period: int | None = None
    symmetric: bool | None = None
    reversible: bool | None = None
    tol: float = 1e-6
    freq_tol: float | None = 1e-4
    error_estimate: bool = True
    max_steps_per_period: int = 20000

    def options(self):
        """The orbit problem's options (driver/problems.py)."""
        return dict(steps_per_period=self.steps_per_period, symmetric=self.symmetric, reversible=self.reversible,
                    integrator=self.integrator)

    def orbit(self, branch, i, samples):
        from ..model.modal import modal_system
        from ..orbits.shooting import shooting_orbit
        steps = int(branch.steps[i]) if getattr(branch, "steps", None) is not None and branch.steps[i] else 0
        return shooting_orbit(modal_system(branch.model), branch.x0[i], branch.v0[i], branch.period[i],
                              steps or self.steps_per_period, bool(self.symmetric), samples, self.integrator)


@dataclass(frozen=True)
class HarmonicBalance(MethodSettings):
    """Harmonic balance (orbits/harmonic_balance.py; condensed onto the nonlinear elements: condensed_hb.py): what a
    user asks for and, resolved, what the branch records.

    harmonics : highest harmonic (on a branch: the most its accuracy target reached); samples : AFT time samples
    (None: enough for a cubic without aliasing); basis : "odd" / "full" (None: "odd" for odd forces); condensed :
    solve the equations condensed onto the elements' deformations (n_s (H + 1) / 2 + 2 unknowns whatever the model
    size); modal_basis : "full" or "ritz" (None: Ritz above driver/settings.SIZES.ritz_min_dof DOFs: the modes below
    ``cutoff_hz`` (Hz, recorded) plus the residual flexibility of the others, model/ritz.py); tol : relative
    residual; error_estimate : each point's truncation error (orbits/hb_error.py); freq_tol : where a point's
    estimated truncation error exceeds it, the branch goes on with two more harmonics from there (None: never), up
    to max_harmonics (driver/refinement.HarmonicRefinement; problems on every mode only, not a Ritz basis).
    """

    method: ClassVar[str] = "harmonic_balance"
    name: ClassVar[str] = "hb"
    harmonics: int = 7
    samples: int | None = None
    basis: str | None = None
    condensed: bool = False
    modal_basis: str | None = None
    tol: float = 1e-8
    error_estimate: bool = True
    freq_tol: float | None = 1e-4
    max_harmonics: int = 31
    cutoff_hz: float = 0.0

    def options(self):
        return dict(harmonics=self.harmonics, samples=self.samples, basis=self.basis, condensed=self.condensed,
                    modal_basis=self.modal_basis)

    def hb_basis(self):
        from ..orbits.hb_basis import HBBasis
        return HBBasis(int(self.harmonics), self.basis or "odd", self.samples)

    def orbit(self, branch, i, samples):
        from ..orbits.harmonic_balance import series_orbit
        return series_orbit(self.hb_basis(), branch.coefficients_at(i), branch.period[i], samples)


#: the names of earlier releases: the same classes
ShootingSettings = Shooting
HarmonicBalanceSettings = HarmonicBalance


METHODS = {cls.method: cls for cls in (Shooting, HarmonicBalance)}


def settings_from_dict(d):
    """Typed settings from a mapping (a file's ``settings_json``, or a first-release dict).

    ``method`` defaults to "shooting"; keys a method does not know are ignored; a branch whose
    "symmetric" is missing was shot over the full period.
    """
    if isinstance(d, MethodSettings):
        return d
    d = dict(d or {})
    method = d.pop("method", "shooting")
    cls = METHODS.get(method)
    if cls is None:
        raise NNMInputError(f"unknown branch method {method!r}; known: {', '.join(METHODS)}")
    known = {f.name: f for f in dataclasses.fields(cls)}
    kw = {}
    for k, v in d.items():
        if k in known:
            kw[k] = v.item() if isinstance(v, np.generic) else v
    for k in [k for k, v in kw.items() if v is None and k in _NOT_NONE]:
        del kw[k]
    # what files written before a field existed were computed with (their defaults then)
    for k, v in _BEFORE[cls].items():
        kw.setdefault(k, v)
    if kw.get("freq_tol") == 0.0:
        kw["freq_tol"] = None                           # (files of 2026-12: 0 for "no target")
    if cls is Shooting:
        kw.setdefault("reversible", bool(kw["symmetric"]))
    return cls(**kw)


#: fields that cannot be None (a first-release dict may hold None for them: the default then)
_NOT_NONE = ("tol", "energy_max", "k3_factor", "floquet", "integrator", "harmonics", "condensed", "error_estimate",
             "max_steps_per_period", "max_harmonics", "cutoff_hz")
#: a stored branch's settings missing these were computed so (Newmark at 200 steps over the full period, no target;
#: an odd Fourier basis on every mode)
_BEFORE = {Shooting: dict(integrator="newmark", steps_per_period=200, symmetric=False, freq_tol=None),
           HarmonicBalance: dict(basis="odd", modal_basis="full", freq_tol=None)}


@dataclass(frozen=True)
class ResultSettings:
    """Thresholds of the result layer's claims about a branch (results/stops.py)."""

    #: restoring force at the turning point relative to the linear one below which the orbit has escaped (status
    #: ``escape``; stops.py explains the ratio)
    escape_ratio: float = 1e-2
    #: ... and below which a branch whose continuation fails has escaped too (the failure is the escape's)
    escape_ratio_failed: float = 0.1


#: the result layer's settings (the defaults above, written once)
RESULTS = ResultSettings()
