"""Units of measured signals: what a test system writes ("g", "mm/s", "lbf", "g/N") -> SI factor and quantity.

``parse_unit("g")`` returns ``SignalUnit(quantity="acceleration", si="m/s^2", factor=9.80665)``: a value in
the file's unit times ``factor`` is the value in ``si``.  Frequency response functions are a response unit
over a force unit (``"g/N"``, ``"(m/s^2)/N"``, ``"mm/N"``, ``"m/s^2/lbf"``): quantity ``"accelerance"``,
``"mobility"`` or ``"receptance"``.  UFF 58 data sets also state their quantity by number (specific data
type: 8 displacement, 11 velocity, 12 acceleration, 13 force) and their unit by exponents of the file's
length and force units (data set 164): ``uff_quantity`` and ``unit_from_uff``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from ...errors import NNMInputError

#: standard gravity (m/s^2): the "g" of accelerometers
G0 = 9.80665
LENGTHS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "micron": 1e-6, "in": 0.0254, "inch": 0.0254,
           "ft": 0.3048}
FORCES = {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605, "kgf": G0}
TIMES = {"s": 1.0, "sec": 1.0, "ms": 1e-3}
FREQUENCIES = {"hz": 1.0, "khz": 1e3, "rad/s": 1.0 / (2.0 * 3.141592653589793)}
#: SI unit of each quantity
SI = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2", "force": "N", "time": "s", "frequency": "Hz",
      "receptance": "m/N", "mobility": "m/s/N", "accelerance": "m/s^2/N", "amplitude": "m", "unknown": ""}
_FRF = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}
#: UFF 58 "specific data type" numbers of the quantities read
UFF_TYPES = {8: "displacement", 11: "velocity", 12: "acceleration", 13: "force"}
#: UFF length / force exponents of each quantity (time is always seconds)
UFF_EXPONENTS = {"displacement": (1, 0), "velocity": (1, 0), "acceleration": (1, 0), "force": (0, 1),
                 "receptance": (1, -1), "mobility": (1, -1), "accelerance": (1, -1)}


@dataclass(frozen=True)
class SignalUnit:
    """A signal's unit: its ``quantity`` (displacement, velocity, acceleration, force, receptance, mobility,
    accelerance, time, frequency or unknown), the SI unit ``si`` and the ``factor`` (file value x factor = SI)."""

    quantity: str
    si: str
    factor: float


def _clean(text):
    s = str(text).strip().replace(" ", "").replace("**", "^").replace("²", "^2").replace("·", "*")
    if s.startswith("(") and s.endswith(")") and s.count("(") == 1:
        s = s[1:-1]
    return s


def _kinematic(s):
    """SignalUnit of a displacement / velocity / acceleration unit ('mm', 'in/s', 'm/s^2', 'g'), or None."""
    low = s.lower()
    if low in ("g", "gn", "g0"):
        return SignalUnit("acceleration", SI["acceleration"], G0)
    m = re.fullmatch(r"([a-zµ]+)(?:/(s|sec)(?:\^?([12]))?|/s/s)?", low)
    if not m or m.group(1) not in LENGTHS:
        return None
    if low.endswith("/s/s"):
        power = 2
    else:
        power = 0 if m.group(2) is None else int(m.group(3) or 1)
    quantity = ("displacement", "velocity", "acceleration")[power]
    return SignalUnit(quantity, SI[quantity], LENGTHS[m.group(1)])


def parse_unit(text, where=""):
    """SignalUnit of a unit as written by a test system (module doc); NNMInputError (one line) if unknown."""
    s = _clean(text)
    low = s.lower()
    if not low:
        return SignalUnit("unknown", "", 1.0)
    if low in FORCES:
        return SignalUnit("force", "N", FORCES[low])
    if low in TIMES:
        return SignalUnit("time", "s", TIMES[low])
    if low in FREQUENCIES:
        return SignalUnit("frequency", "Hz", FREQUENCIES[low])
    u = _kinematic(s)
    if u is not None:
        return u
    num, sep, den = s.rpartition("/")
    if sep and den.lower() in FORCES:
        r = _kinematic(_clean(num))
        if r is not None:
            q = _FRF[r.quantity]
            return SignalUnit(q, SI[q], r.factor / FORCES[den.lower()])
    raise NNMInputError(f"{where}unit {text!r} is not known; use e.g. m, mm, m/s, m/s^2, g, N, lbf, g/N, (m/s^2)/N")


def uff_quantity(spec_type, denominator_type=0):
    """Quantity of a UFF 58 data set from its specific data types (ordinate, ordinate denominator)."""
    q = UFF_TYPES.get(int(spec_type), "unknown")
    if int(denominator_type) == 13 and q in _FRF:
        return _FRF[q]
    return q


def unit_from_uff(quantity, length_factor, force_factor):
    """SignalUnit of a UFF quantity stated in the file's units: data set 164 gives the factors that convert SI
    to file units (1000 for mm), so the SI value is the file value / (length^a force^b)."""
    if quantity not in UFF_EXPONENTS:
        return SignalUnit(quantity, SI.get(quantity, ""), 1.0)
    a, b = UFF_EXPONENTS[quantity]
    return SignalUnit(quantity, SI[quantity], 1.0 / (length_factor ** a * force_factor ** b))
