"""The files of a sweep: preparing an output file for a (re)run (the base model, the variants recorded
in ``/sweeps``, the branches already saved), and reading a sweep back.  The schema's sweep groups and
branch names: ``files/sweep_groups.py``.
"""
from __future__ import annotations

import dataclasses
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


def prepare_file(out, model, variants, energy_max, names, request=None):
    """Create ``out`` with the base model, record the variants; return {name: Branch} of the sweep's saved branches.
    request : optional (method settings, Continuation) the sweep asks for (driver/api.from_keywords): a saved branch
    computed otherwise (stale_reason) is refused in one line, as one computed to another energy_max is."""

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
        why = stale_reason(b, *request) if request is not None else ""
        if why:
            raise NNMInputError(f"{out} already holds branch {name} computed {why}; write this sweep to another file "
                                f"or remove that branch")
    return found


def stale_reason(branch, method, continuation):
    """Why a saved ``branch`` is not what a sweep asking for ``method`` (Shooting / HarmonicBalance settings, None
    fields: the solver resolves them) and ``continuation`` (Continuation settings) would compute, or '' (then a rerun
    keeps it): another method, a requested method field the branch recorded with another value, or a branch that
    stopped at fewer points (status 'max_points') than this sweep's max_points allows.  Fields a file written before
    they existed does not record are not compared, nor harmonic balance's harmonics and samples where its accuracy
    target (freq_tol) raises them (the branch records its end's)."""
    saved = branch.settings
    if saved is None:
        return ""
    if saved.method != method.method:
        return f"by {saved.method} (this sweep: {method.method})"
    refined = getattr(method, "freq_tol", None) is not None and getattr(method, "error_estimate", True)
    for f in dataclasses.fields(method):
        asked = getattr(method, f.name)
        if f.name in method.record_fields or asked is None or f.name not in saved:
            continue
        if f.name == "freq_tol" and not getattr(method, "error_estimate", True):
            continue                                # (no estimate, no target: the branch records None)
        if f.name in ("harmonics", "samples") and refined:
            continue                                # (harmonic balance's target raised them: the branch's end's)
        had = saved[f.name]
        if had != asked and not (isinstance(had, float) and isinstance(asked, float) and math.isclose(had, asked)):
            return f"with {f.name} = {had!r} (this sweep: {asked!r})"
    if branch.status == "max_points" and len(branch) < continuation.max_points:
        return (f"to max_points = {len(branch)} (stopped there; this sweep allows {continuation.max_points} points)")
    return ""


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
