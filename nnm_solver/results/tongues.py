r"""The record of an internal-resonance tongue met by a backbone (``Branch.tongues``): a typed, frozen dataclass.

A ``tongues="skip"`` continuation (nnm_solver/backbone/) records each tongue it leaves the family at: its order k
(a k:1 resonance: the orbit's k-th harmonic near the partner mode's frequency), the partner mode (1-based; 0 when
there is none: a fold of the family), the departure (entry orbit: the last point on the family, J, Hz, s, m, m/s)
and the first orbit inside, and how it was passed (the jump's landing energy, or why the family ends there).
Records read like the mappings of earlier releases (``t["label"]``, ``t.get("exit_energy")``) and are stored in
files as JSON (``as_dict``).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

__all__ = ["TongueRecord", "continue_hint"]


@dataclass(frozen=True)
class TongueRecord:
    """One tongue passed (or met) by a backbone (module docstring).

    order : k of the k:1 resonance (1: a fold of the family or a 1:1 resonance); partner_mode : 1-based linear mode
    whose shape is closest to the orbit's k-th harmonic (0: none), partner_mac : that MAC;
    entry_* : the last orbit on the family before it (index into the branch's points, energy J, frequency Hz,
    period s, x0 m, v0 m/s), inside_* : the first orbit off the family;
    skipped : the branch goes on beyond it (exit_energy J, exit_frequency_hz Hz: where it lands), ``jump`` says how;
    attempts : orbits corrected to find the landing; reentries : times the family was left again into the same
    tongue (one record); landings : the branch indices (0-based) of the points where the continuation restarted
    beyond it (no line of the branch joins a landing to the point before it); family_end : the backbone family itself ends here (no landing exists); note : why.
    """

    order: int
    partner_mode: int = 0
    partner_mac: float = math.nan
    entry_index: int = -1
    entry_energy: float = math.nan
    entry_frequency_hz: float = math.nan
    entry_period: float = math.nan
    entry_x0: tuple = field(default=(), repr=False)
    entry_v0: tuple = field(default=(), repr=False)
    inside_x0: tuple = field(default=(), repr=False)
    inside_v0: tuple = field(default=(), repr=False)
    inside_period: float = math.nan
    skipped: bool = False
    exit_energy: float | None = None
    exit_frequency_hz: float | None = None
    jump: str = ""
    attempts: int = 0
    reentries: int = 0
    landings: tuple = ()
    family_end: bool = False
    note: str = ""

    @property
    def label(self):
        """'tongue k:1' (k >= 2), 'fold' (order 1 with no partner) or 'tongue 1:1' (a 1:1 resonance with a partner)."""
        if self.order <= 1 and not self.partner_mode:
            return "fold"
        return f"tongue {self.order}:1"

    @property
    def ratio(self):
        return [self.order, 1]

    def replace(self, **changes):
        return dataclasses.replace(self, **changes)

    def scaled(self, amplitude, energy):
        """The record of the same tongue on a branch whose orbits are scaled (Branch.scaled, model/scaling.py): its
        orbits' displacements (m) and velocities (m/s) x ``amplitude``, its energies (J) x ``energy``; frequencies,
        periods, indices and free text (jump, note) unchanged."""
        def orbit(x):
            return tuple(float(a) * amplitude for a in x)

        return self.replace(entry_energy=self.entry_energy * energy,
                            exit_energy=None if self.exit_energy is None else self.exit_energy * energy,
                            entry_x0=orbit(self.entry_x0), entry_v0=orbit(self.entry_v0),
                            inside_x0=orbit(self.inside_x0), inside_v0=orbit(self.inside_v0))

    # mapping-style access (the records of earlier releases were dicts)
    def keys(self):
        return list(self.as_dict())

    def items(self):
        return self.as_dict().items()

    def values(self):
        return self.as_dict().values()

    def __iter__(self):
        return iter(self.as_dict())

    def __len__(self):
        return len(self.as_dict())

    def __getitem__(self, key):
        d = self.as_dict()
        if key not in d:
            raise KeyError(key)
        return d[key]

    def get(self, key, default=None):
        return self.as_dict().get(key, default)

    def __contains__(self, key):
        return key in self.as_dict()

    def as_dict(self):
        """Plain dict (JSON-ready), with ``label`` and ``ratio``; unset exits left out."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        d = {k: (list(v) if isinstance(v, tuple) else v) for k, v in d.items() if v is not None}
        return {"label": self.label, "ratio": self.ratio, **d}

    @classmethod
    def from_mapping(cls, d):
        """A record from a mapping (a file's JSON, an earlier release's dict); keys it does not know are ignored."""
        if isinstance(d, cls):
            return d
        known = {f.name for f in dataclasses.fields(cls)}
        kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in dict(d).items() if k in known}
        if "order" not in kw:
            ratio = d.get("ratio") or [1, 1]
            kw["order"] = int(ratio[0])
        kw["order"] = int(kw["order"])
        if "landings" in kw:
            kw["landings"] = tuple(int(i) for i in kw["landings"])
        for key in ("partner_mode", "entry_index", "attempts", "reentries"):
            if key in kw and kw[key] is not None:
                kw[key] = int(kw[key])
        return cls(**kw)


def continue_hint(tongues, index, shooting=True):
    """How a user follows tongue ``index`` (0-based in ``tongues``, a branch's records) as its own branch, in the API
    and on the command line: ' (tongue K: continue_tongue(branch, index) or nnm-solve FILE --tongue K follows it)',
    K 1-based among the records continue_tongue can start (not those where the family itself ends), as nnm-solve
    lists and numbers them (cli/families.py); '' when it cannot be followed (a family's end; a branch not computed
    by shooting, which continue_tongue refuses)."""
    if not shooting or not 0 <= index < len(tongues) or tongues[index].get("family_end"):
        return ""
    k = 1 + sum(1 for t in tongues[:index] if not t.get("family_end"))
    return f" (tongue {k}: continue_tongue(branch, {index}) or nnm-solve FILE --tongue {k} follows it)"
