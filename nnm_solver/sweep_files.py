"""The file side of sweeps: branch names ``<variant>:mode<N>``, the ``/sweeps`` group recording the
variants (docs/format.md), preparing an output file for a (re)run, and reading a sweep back.
"""
from __future__ import annotations

import json
import math
import re

import numpy as np

from .errors import NNMInputError
from .variants import Variant

__all__ = ["branch_name", "parse_branch_name", "prepare_file", "load_sweep"]

_NAME = re.compile(r"^(?P<variant>[^/:]+):mode(?P<mode>\d+)$")


def branch_name(variant, mode):
    """Name of a sweep's branch in its file: ``<variant>:mode<N>``."""
    return f"{variant.name if isinstance(variant, Variant) else variant}:mode{int(mode)}"


def parse_branch_name(name):
    """(variant name, mode) of a sweep branch name, or None for another name."""
    m = _NAME.match(str(name))
    return (m["variant"], int(m["mode"])) if m else None


def _same_model(a, b):
    def dense(A):
        return A.toarray() if hasattr(A, "toarray") else np.asarray(A)

    if a.n != b.n or len(a.springs) != len(b.springs):
        return False
    if any((s.dof, s.other) != (t.dof, t.other) for s, t in zip(a.springs, b.springs)):
        return False
    return (np.allclose(dense(a.M), dense(b.M), rtol=1e-12, atol=0) and np.allclose(dense(a.K), dense(b.K), rtol=1e-12,
                                                                                     atol=0)
            and np.allclose(a.k3, b.k3, rtol=1e-12, atol=0))


def _recorded_variants(f):
    if "sweeps" not in f:
        return {}
    return {k: Variant.from_dict(v) for k, v in json.loads(f["sweeps"].attrs.get("variants_json", "{}")).items()}


def prepare_file(out, model, variants, energy_max, names):
    """Create ``out`` with the base model, record the variants; return {name: Branch} of the sweep's saved branches."""
    from .h5file import atomic_h5, open_nnm
    from .io import load_branches, load_model, write_model_group

    wanted = {v.name: v.as_dict() for v in variants}
    if not out.exists():
        with atomic_h5(out) as f:
            write_model_group(f, model)
            f.create_group("sweeps").attrs["variants_json"] = json.dumps(wanted)
        return {}
    file_model = load_model(out)
    if not _same_model(file_model, model):
        raise NNMInputError(f"{out} holds another model ({file_model.n} DOFs, {len(file_model.springs)} springs) "
                            f"than the sweep's; write the sweep to another file")
    with open_nnm(out) as f:
        recorded = {k: v.as_dict() for k, v in _recorded_variants(f).items()}
        saved = {str(f["branches"][g].attrs.get("name", g)) for g in f["branches"]} if "branches" in f else set()
    for name, d in wanted.items():
        if name in recorded and recorded[name] != d:
            raise NNMInputError(f"{out} already defines variant {name!r} differently ({recorded[name]}); "
                                f"rename the variant or write to another file")
    if any(name not in recorded for name in wanted):
        with atomic_h5(out, copy_existing=True) as f:
            g = f.require_group("sweeps")
            g.attrs["variants_json"] = json.dumps({**recorded, **wanted})
    if not saved & set(names):
        return {}
    found = {b.name: b for b in load_branches(out, file_model) if b.name in names}
    for name, b in found.items():
        e = b.settings.energy_max
        if math.isfinite(e) and not math.isclose(e, energy_max, rel_tol=1e-9):
            raise NNMInputError(f"{out} already holds branch {name} computed up to energy_max = {e:g} J (this sweep: "
                                f"{energy_max:g} J); write this sweep to another file or remove that branch")
    return found


def with_variant_models(branches, model, f):
    """Give each sweep branch (name ``<variant>:mode<N>``) of the open nnm file ``f`` the model of its
    variant recorded in ``/sweeps`` (added stiffness, mass, spring factors applied to ``model``);
    other branches are left as they are.  Returns the sweep branches."""
    recorded = _recorded_variants(f)
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


def load_sweep(path):
    """The sweep branches (names ``<variant>:mode<N>``) of an nnm file, each with its variant's model
    (``load_branches`` gives them those models too; this keeps only the sweep's branches)."""
    from .io import load_branches

    return [b for b in load_branches(path) if parse_branch_name(b.name) is not None]
