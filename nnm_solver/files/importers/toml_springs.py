"""The ``[[springs]]`` tables of a model description (toml.py): element types, their placement and units.

Each table names its element with ``type`` (``SPRING_TYPES``): ``cubic`` (k3), ``polynomial`` (coefficients =
{p = c_p}), ``piecewise_linear`` (stiffnesses, breakpoints), each on one deformation x[dof] - x[other] placed by
``dof``/``other`` or ``node``/``direction``/``other_node``; and ``polynomial_stiffness``, the force in several
coordinates of ``nnm.PolynomialStiffness`` (NLvib's convention), placed by ``dofs`` or ``nodes`` (toml_coupled.py).
Coefficients are in the description's units and converted to SI with ``Units.coefficient_scale``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ...errors import NNMInputError
from ...model.elements import CubicSpring
from .common import direction_name
from .toml_coupled import build_polynomial_stiffness

LOCATION_KEYS = {"type", "dof", "other", "node", "direction", "other_node", "other_direction"}


@dataclass(frozen=True)
class SpringType:
    """A nonlinear element type of the ``[[springs]]`` tables.

    parameters : its required keys (in the description's units);
    build(dof, other, params, scale) -> element, where scale(p) converts the coefficient of d^p
    of a force law to SI;
    parse(key, value, where) -> the parameter's value (default: a finite number);
    optional : keys that may be given (passed to build only when present);
    table(row, n, dof_map, units, where) -> element: instead of the above, builds an element that is not on one
    deformation (placement, parameters and units) from its whole table.
    """

    parameters: tuple
    build: Callable | None = None
    parse: Callable | None = None
    optional: tuple = ()
    table: Callable | None = None


def _cubic(dof, other, params, scale):
    return CubicSpring(dof=dof, other=other, k3=params["k3"] * scale(3))


def _law_table(key, value, where):
    """{power: coefficient} from a TOML table such as {2 = 1e5, 3 = 1e9}."""
    if not isinstance(value, dict) or not value:
        raise NNMInputError(f"{where}: {key} must be a table of powers and coefficients, e.g. {{2 = 1e5, 3 = 1e9}}")
    law = {}
    for p, c in value.items():
        if not str(p).isdigit() or int(p) < 2:
            raise NNMInputError(f"{where}: {key}: power {p!r} is not an integer >= 2 (the linear stiffness is in K)")
        law[int(p)] = _number(c, f"{key}.{p}", where)
    return law


def _polynomial(dof, other, params, scale):
    from ...model.elements import PolynomialSpring
    return PolynomialSpring(dof=dof, other=other, coefficients={p: c * scale(p) for p, c in
                                                                params["coefficients"].items()})


def _pwl_parse(key, value, where):
    """A list of numbers (stiffnesses, breakpoints) or one number (eps)."""
    if key == "eps":
        return _number(value, key, where)
    if not isinstance(value, list):
        raise NNMInputError(f"{where}: {key} must be a list of numbers, e.g. {key} = [1e5, 2e4]")
    return [_number(v, f"{key}[{i}]", where) for i, v in enumerate(value)]


def _piecewise(dof, other, params, scale):
    """PiecewiseLinearSpring: stiffnesses are coefficients of d^1 (force / length), breakpoints lengths."""
    from ...model.elements import PiecewiseLinearSpring
    law = {k: params[k] for k in ("stiffnesses", "breakpoints", "stiffnesses_negative", "breakpoints_negative", "eps")
           if k in params}
    return to_si(PiecewiseLinearSpring(dof=dof, other=other, **law), scale)


def to_si(spring, scale):
    """The element ``spring`` given in file units, in SI; scale(p) converts the coefficient of d^p (E / s^(p+1),
    s the DOF's unit), so a stiffness scales by scale(1) and a length (breakpoint) by scale(0) / scale(1) = s."""
    from ...model.elements import PiecewiseLinearSpring, PolynomialSpring
    if isinstance(spring, CubicSpring):
        return spring.scaled(scale(3))
    if isinstance(spring, PolynomialSpring):
        return PolynomialSpring(dof=spring.dof, other=spring.other,
                                coefficients={p: c * scale(p) for p, c in spring.coefficients.items()})
    if isinstance(spring, PiecewiseLinearSpring):
        k, s = scale(1), scale(0) / scale(1)
        if k == 1.0 and s == 1.0:
            return spring
        neg = {} if spring.symmetric else dict(stiffnesses_negative=[c * k for c in spring.stiffnesses_negative],
                                               breakpoints_negative=[b * s for b in spring.breakpoints_negative])
        return PiecewiseLinearSpring(dof=spring.dof, other=spring.other, stiffnesses=[c * k for c in spring.stiffnesses],
                                     breakpoints=[b * s for b in spring.breakpoints], eps=spring.eps, **neg)
    raise NNMInputError(f"no unit conversion for {type(spring).__name__}")


#: element types by name; a new element type registers its builder here (``type = "<name>"``)
SPRING_TYPES = {"cubic": SpringType(("k3",), _cubic),
                "polynomial": SpringType(("coefficients",), _polynomial, _law_table),
                "piecewise_linear": SpringType(("stiffnesses", "breakpoints"), _piecewise, _pwl_parse,
                                               ("eps", "stiffnesses_negative", "breakpoints_negative")),
                "polynomial_stiffness": SpringType(("exponents", "coefficients"), table=build_polynomial_stiffness)}


def _unknown(table, allowed, where):
    extra = sorted(set(table) - set(allowed))
    if extra:
        raise NNMInputError(f"{where}: unknown key(s) {', '.join(extra)}; known: {', '.join(sorted(allowed))}")


def _number(value, key, where):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise NNMInputError(f"{where}: {key} = {value!r} is not a number")
    if not np.isfinite(value):
        raise NNMInputError(f"{where}: {key} = {value} is not finite")
    return float(value)


def _dof(row, prefix, n, dof_map, where):
    """0-based DOF of a spring end: '<prefix>' index or '<prefix>node' + direction; None if absent."""
    idx_key = "dof" if prefix == "" else "other"
    node_key = "node" if prefix == "" else "other_node"
    if idx_key in row and node_key in row:
        raise NNMInputError(f"{where}: give {idx_key} or {node_key}, not both")
    if idx_key in row:
        d = row[idx_key]
        if isinstance(d, bool) or not isinstance(d, int) or not 0 <= d < n:
            raise NNMInputError(f"{where}: {idx_key} = {d!r} is not a DOF of the model (0-based, 0..{n - 1})")
        return d
    if node_key in row:
        if dof_map is None:
            raise NNMInputError(f"{where}: springs by node need a DOF map; these matrix files have none: give "
                                f"{idx_key} = <0-based index>, or [matrices] dof_map = <file>")
        direction = row.get("other_direction", row.get("direction")) if prefix else row.get("direction")
        if direction is None:
            raise NNMInputError(f"{where}: {node_key} needs a direction (ux, uy, uz, rx, ry, rz)")
        return dof_map.index(row[node_key], direction, f"{where}: ")
    return None


def build_springs(rows, n, dof_map, units, where):
    rotations = dof_map.rotations() if dof_map is not None else np.zeros(n, bool)
    out = []
    for i, row in enumerate(rows, 1):
        w = f"{where} [[springs]] #{i}"
        if not isinstance(row, dict):
            raise NNMInputError(f"{w}: must be a table")
        kind = str(row.get("type", "cubic")).lower()
        if kind not in SPRING_TYPES:
            raise NNMInputError(f"{w}: unknown type {row.get('type')!r}; known: {', '.join(SPRING_TYPES)}")
        st = SPRING_TYPES[kind]
        if st.table is not None:
            out.append(st.table(row, n, dof_map, units, w))
            continue
        _unknown(row, LOCATION_KEYS | set(st.parameters) | set(st.optional), w)
        if "direction" in row:
            direction_name(row["direction"], f"{w}: ")
        dof = _dof(row, "", n, dof_map, w)
        if dof is None:
            raise NNMInputError(f"{w}: give dof = <0-based index> or node = <node> with direction = <ux..rz>")
        other = _dof(row, "other", n, dof_map, w)
        if other is not None and rotations[other] != rotations[dof]:
            raise NNMInputError(f"{w}: a relative spring joins a rotation and a translation")
        missing = [k for k in st.parameters if k not in row]
        if missing:
            raise NNMInputError(f"{w}: missing {', '.join(missing)} (a {kind} spring needs "
                                f"{', '.join(st.parameters)})")
        params = {k: st.parse(k, row[k], w) if st.parse else _number(row[k], k, w)
                  for k in (*st.parameters, *st.optional) if k in row}
        try:
            element = st.build(dof, other, params, units.coefficient_scale(bool(rotations[dof])))
        except (TypeError, ValueError) as exc:
            raise NNMInputError(f"{w}: {exc}") from None
        out.append(element)
    return out
