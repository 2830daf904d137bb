"""What a sweep computes: its variants, its modes, and the TOML sweep file (docs/sweep.md)::

    modes = "10-24"            # optional: the command line's --modes wins
    energy_max = 100.0         # optional: --energy-max wins
    [options]                  # continue_nnm keywords
    max_points = 150
    [grid]                     # every combination (model.variants.variant_grid)
    spring_factor = [0.5, 1.0, 2.0]
    stiffness = [0.0, 1e6]     # N/m added to ground at each of stiffness_dofs
    stiffness_dofs = [12, 40]
    [[variant]]                # and/or variants one by one
    name = "heavy-tanks"
    mass_factor = 1.3
    mass_dofs = [3, 4]
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import NNMInputError, finite_number
from ..model.variants import Variant, variant_grid

__all__ = ["as_variants", "parse_modes", "SweepSpec", "load_sweep_file"]


def _finite(name, value):
    return finite_number(value, name)


def as_variants(variants):
    """None, a Variant, a dict (Variant keywords) or a sequence of those -> list of Variants, names unique."""
    if variants is None:
        out = [Variant()]
    elif isinstance(variants, (Variant, dict)):
        out = [variants]
    else:
        try:
            out = list(variants)
        except TypeError:
            raise NNMInputError(f"variants must be None, a Variant or a list of Variants, got "
                                f"{type(variants).__name__}") from None
    out = [Variant.from_dict(v) if isinstance(v, dict) else v for v in out]
    for v in out:
        if not isinstance(v, Variant):
            raise NNMInputError(f"variants must be nnm_solver.Variant objects (or dicts), got {type(v).__name__}")
    if not out:
        raise NNMInputError("variants is empty; give None for the model as it is")
    names = [v.name for v in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise NNMInputError(f"variant names must be unique; repeated: {dup} (give each variant a name)")
    return out


def parse_modes(modes):
    """1-based mode numbers from an int, a sequence of ints, or a string such as "10-24" or "1,3,5-7"."""
    if isinstance(modes, str):
        out = []
        for part in modes.replace(" ", "").split(","):
            if not part:
                continue
            lo, sep, hi = part.partition("-")
            try:
                a, b = int(lo), int(hi) if sep else int(lo)
            except ValueError:
                raise NNMInputError(f"modes {modes!r}: {part!r} is not a mode number or a range like 10-24") from None
            if b < a:
                raise NNMInputError(f"modes {modes!r}: the range {part!r} is empty (write low-high)")
            out.extend(range(a, b + 1))
    elif isinstance(modes, (int, np.integer)) and not isinstance(modes, bool):
        out = [int(modes)]
    else:
        try:
            out = list(modes)
        except TypeError:
            raise NNMInputError(f"modes must be mode numbers (a list, a range or a string like '10-24'), "
                                f"got {modes!r}") from None
        for m in out:
            if isinstance(m, bool) or not isinstance(m, (int, np.integer)):
                raise NNMInputError(f"modes must be integers (1-based), got {m!r}")
        out = [int(m) for m in out]
    if not out:
        raise NNMInputError("no mode to compute: modes is empty")
    dup = sorted({m for m in out if out.count(m) > 1})
    if dup:
        raise NNMInputError(f"modes repeats {dup}")
    return out


@dataclass
class SweepSpec:
    """A TOML sweep file: variants, and optional modes, energy_max and continuation options."""

    variants: list
    modes: list | None = None
    energy_max: float | None = None
    options: dict = field(default_factory=dict)


_GRID_KEYS = {"spring_factor", "stiffness", "stiffness_dofs", "mass_factor", "mass_dofs"}


def load_sweep_file(path):
    """Read a TOML sweep file (module docstring, docs/sweep.md) into a SweepSpec."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        try:
            import tomli as tomllib
        except ModuleNotFoundError:
            raise NNMInputError("reading a TOML sweep file needs Python >= 3.11 (tomllib) or `pip install tomli`") from None
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise NNMInputError(f"sweep file {path} does not exist") from None
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise NNMInputError(f"sweep file {path} is not valid TOML: {exc}") from None
    unknown = set(data) - {"modes", "energy_max", "options", "grid", "variant"}
    if unknown:
        raise NNMInputError(f"{path}: unknown key(s) {sorted(unknown)}; known: modes, energy_max, [options], [grid], "
                            f"[[variant]]")
    variants = []
    if "grid" in data:
        grid = data["grid"]
        if not isinstance(grid, dict) or set(grid) - _GRID_KEYS:
            raise NNMInputError(f"{path}: [grid] takes {sorted(_GRID_KEYS)}, got {sorted(grid) if isinstance(grid, dict) else grid!r}")
        variants += variant_grid(**grid)
    for i, v in enumerate(data.get("variant", [])):
        if not isinstance(v, dict):
            raise NNMInputError(f"{path}: [[variant]] {i + 1} must be a table")
        variants.append(Variant.from_dict(v, where=f"{path}: [[variant]] {i + 1}"))
    modes = parse_modes(data["modes"]) if "modes" in data else None
    energy_max = _finite(f"{path}: energy_max", data["energy_max"]) if "energy_max" in data else None
    options = data.get("options", {})
    if not isinstance(options, dict):
        raise NNMInputError(f"{path}: [options] must be a table of continue_nnm keywords")
    return SweepSpec(variants=as_variants(variants or None), modes=modes, energy_max=energy_max, options=dict(options))
