"""The sweep side of the nnm HDF5 schema (docs/format.md): a sweep's branch names ``<variant>:mode<N>``,
the ``/sweeps`` group recording its variants, and the variant models its branches are read back with.
"""
from __future__ import annotations

import json
import re

from ..model.variants import Variant

__all__ = ["branch_name", "parse_branch_name", "recorded_variants", "with_variant_models"]

_NAME = re.compile(r"^(?P<variant>[^/:]+):mode(?P<mode>\d+)$")


def branch_name(variant, mode):
    """Name of a sweep's branch in its file: ``<variant>:mode<N>``."""
    return f"{variant.name if isinstance(variant, Variant) else variant}:mode{int(mode)}"


def parse_branch_name(name):
    """(variant name, mode) of a sweep branch name, or None for another name."""
    m = _NAME.match(str(name))
    return (m["variant"], int(m["mode"])) if m else None


def recorded_variants(f):
    if "sweeps" not in f:
        return {}
    return {k: Variant.from_dict(v) for k, v in json.loads(f["sweeps"].attrs.get("variants_json", "{}")).items()}


def with_variant_models(branches, model, f):
    """Give each sweep branch (name ``<variant>:mode<N>``) of the open nnm file ``f`` the model of its
    variant recorded in ``/sweeps`` (added stiffness, mass, spring factors applied to ``model``);
    other branches are left as they are.  Returns the sweep branches."""
    recorded = recorded_variants(f)
    cache, out = {}, []
    for b in branches:
        parsed = parse_branch_name(b.name)
        if parsed is None:
            continue
        vname = parsed[0]
        v = recorded.get(vname, Variant() if vname == "base" else None)
        if v is not None:
            if vname not in cache:
                cache[vname] = v.apply(model)
            b.model = cache[vname]
        b.sweep_info = {"variant": vname, "source": "file"}
        out.append(b)
    return out
