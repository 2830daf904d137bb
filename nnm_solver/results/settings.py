"""Typed settings of a branch's method, stored with the branch (HDF5 attribute ``settings_json``).

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

__all__ = ["MethodSettings", "ShootingSettings", "HarmonicBalanceSettings", "settings_from_dict"]


@dataclass(frozen=True)
class MethodSettings:
    """Settings every method shares.

    tol : corrector tolerance (relative);  energy_max : J, the requested end of the branch;
    k3_factor : the branch's springs relative to the model it was computed for (scaling law);
    floquet : whether multipliers were computed.
    """

    method: ClassVar[str] = ""
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
class ShootingSettings(MethodSettings):
    """Shooting (orbits/shooting.py): steps_per_period, half-period ``symmetric`` shooting,
    ``reversible`` orbits (v0 = 0), the time ``integrator`` (integrators.INTEGRATORS; files written
    before it existed used Newmark)."""

    method: ClassVar[str] = "shooting"
    steps_per_period: int = 200
    symmetric: bool = True
    reversible: bool = True
    integrator: str = "newmark"
    freq_tol: float = 0.0

    def orbit(self, branch, i, samples):
        from ..model.modal import modal_system
        from ..orbits.shooting import shooting_orbit
        steps = int(branch.steps[i]) if getattr(branch, "steps", None) is not None and branch.steps[i] else 0
        return shooting_orbit(modal_system(branch.model), branch.x0[i], branch.v0[i], branch.period[i],
                              steps or self.steps_per_period, self.symmetric, samples, self.integrator)


@dataclass(frozen=True)
class HarmonicBalanceSettings(MethodSettings):
    """Harmonic balance (orbits/harmonic_balance.py): highest harmonic, basis "odd"/"full", AFT samples;
    ``condensed``: the equations were condensed onto the elements' deformations (orbits/condensed_hb.py);
    ``modal_basis``: "full" (every mode) or "ritz" (the modes below ``cutoff_hz`` (Hz) plus the residual
    flexibility of the others, model/ritz.py); ``freq_tol``: the branch raised its harmonics where a point's
    estimated truncation error exceeded it (0: it did not; ``harmonics`` is then the most it reached)."""

    method: ClassVar[str] = "harmonic_balance"
    tol: float = 1e-8
    harmonics: int = 7
    basis: str = "odd"
    samples: int | None = None
    condensed: bool = False
    modal_basis: str = "full"
    cutoff_hz: float = 0.0
    freq_tol: float = 0.0

    def hb_basis(self):
        from ..orbits.hb_basis import HBBasis
        return HBBasis(int(self.harmonics), self.basis, self.samples)

    def orbit(self, branch, i, samples):
        from ..orbits.harmonic_balance import series_orbit
        return series_orbit(self.hb_basis(), branch.coefficients_at(i), branch.period[i], samples)


METHODS = {cls.method: cls for cls in (ShootingSettings, HarmonicBalanceSettings)}


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
        if k in known and v is not None:
            kw[k] = v.item() if isinstance(v, np.generic) else v
    if cls is ShootingSettings:
        kw.setdefault("symmetric", False)
        kw.setdefault("reversible", bool(kw["symmetric"]))
    return cls(**kw)
