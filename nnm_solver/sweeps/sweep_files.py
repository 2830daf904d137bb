"""The files of a sweep: preparing an output file for a (re)run (the base model, the variants recorded
in ``/sweeps``, the branches already saved), and reading a sweep back.  The schema's sweep groups and
branch names: ``files/sweep_groups.py``.
"""
from __future__ import annotations

import json
import math

import numpy as np

from ..errors import NNMInputError
from ..files.h5file import atomic_h5, open_nnm
from ..files.branch_io import load_branches
from ..files.io import load_model, write_model_group
from ..files.sweep_groups import parse_branch_name, recorded_variants

__all__ = ["prepare_file", "load_sweep"]


def _same_model(a, b):
    def dense(A):
        return A.toarray() if hasattr(A, "toarray") else np.asarray(A)

    if a.n != b.n or len(a.springs) != len(b.springs):
        return False
    if any(not _same_place(s, t) for s, t in zip(a.springs, b.springs)):
        return False
    return (np.allclose(dense(a.M), dense(b.M), rtol=1e-12, atol=0) and np.allclose(dense(a.K), dense(b.K), rtol=1e-12,
                                                                                     atol=0)
            and np.allclose(a.k3, b.k3, rtol=1e-12, atol=0))


def prepare_file(out, model, variants, energy_max, names):
    """Create ``out`` with the base model, record the variants; return {name: Branch} of the sweep's saved branches."""

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
        recorded = {k: v.as_dict() for k, v in recorded_variants(f).items()}
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


def load_sweep(path):
    """The sweep branches (names ``<variant>:mode<N>``) of an nnm file, each with its variant's model
    (``load_branches`` gives them those models too; this keeps only the sweep's branches)."""
    return [b for b in load_branches(path) if parse_branch_name(b.name) is not None]


def _same_place(s, t):
    """Do two elements act on the same coordinates (a spring's dof and other; an element in several coordinates,
    model/coupled.py: its dofs and directions, and its exponents)?"""
    if type(s) is not type(t):
        return False
    if hasattr(s, "dof"):
        return (s.dof, getattr(s, "other", None)) == (t.dof, getattr(t, "other", None))
    same = lambda x, y: (x is None and y is None) or (x is not None and y is not None and np.array_equal(x, y))
    return all(same(getattr(s, k, None), getattr(t, k, None)) for k in ("dofs", "directions", "exponents"))
