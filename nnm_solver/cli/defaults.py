"""The solver's defaults as the front ends show them (``nnm-solve --help``, the viewer's Compute tab): read from the
typed settings objects where each default is written once (driver/settings.py: ``Shooting``, ``HarmonicBalance``,
``Continuation``; backbone/settings.py: ``Follow``, ``Skip``), never copied, so that every front end offers what the
API does."""
from __future__ import annotations

from dataclasses import fields

__all__ = ["solver_defaults", "TONGUE_CHOICES"]

#: what a continuation does at an internal-resonance tongue (continue_nnm's ``tongues``)
TONGUE_CHOICES = ("follow", "follow-all", "skip")


def solver_defaults():
    """{keyword: default} of ``continue_nnm`` with no options: method, tongues, the continuation's fields
    (max_points, step, ...), harmonic balance's (harmonics, condensed, ...) and shooting's (integrator,
    steps_per_period: the integrator's own default, tol, ...), the shooting's last (its tol wins)."""
    from ..driver.settings import Continuation, HarmonicBalance, Shooting
    from ..integrators.registry import get_integrator

    out = {"method": Shooting.name, "tongues": "follow"}
    for obj in (Continuation(), HarmonicBalance(), Shooting()):
        out.update({f.name: getattr(obj, f.name) for f in fields(obj)})
    if out["steps_per_period"] is None:
        out["steps_per_period"] = get_integrator(out["integrator"]).steps
    return out
