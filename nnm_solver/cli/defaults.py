"""The solver's defaults as the front ends show them (``nnm-solve --help``, the viewer's Compute tab): read from
``continue_nnm``'s signature and the methods' option defaults (driver ``method_options``), never copied, so that
every front end offers what the API does."""
from __future__ import annotations

import inspect

__all__ = ["solver_defaults", "TONGUE_CHOICES"]

#: what a continuation does at an internal-resonance tongue (continue_nnm's ``tongues``)
TONGUE_CHOICES = ("follow", "skip")


def solver_defaults():
    """{keyword: default} of ``continue_nnm`` (method, max_points, tongues, steps_per_period, integrator, tol,
    ...) with the shooting and harmonic-balance options' defaults (steps_per_period, integrator, harmonics,
    condensed, ...)."""
    from ..driver.api import continue_nnm
    from ..driver.problems import method_options

    out = {}
    for name, p in inspect.signature(continue_nnm).parameters.items():
        if p.default is not inspect.Parameter.empty:
            out[name] = p.default
    for method in ("hb", "shooting"):                  # the shooting's own defaults last (steps_per_period, ...)
        out.update(method_options(method, {})[1])
    return out
