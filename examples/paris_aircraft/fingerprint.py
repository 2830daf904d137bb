"""Fingerprint of a build: what must not change for assets/paris.h5 to stay the builder's output.

``build_fingerprint(params, n_cb, k3)`` hashes (SHA-256) the builder version, every parameter of
``ParisParams``, the reduction size and the springs' k3, and the source text of the builder
(examples/paris_aircraft/*.py but the tuning scripts tuning*.py, and examples/build_paris.py).  build_paris.py stores it in the file
(model info ``builder_fingerprint``); tests/test_aircraft.py recomputes it from the code and fails
when the shipped file was built by other code or parameters (rebuild with build_paris.py then).
The FE kit (nnm_fem) and the solver are not hashed: their own tests cover them.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path

from .params import BUILDER_VERSION, ParisParams

PACKAGE = Path(__file__).resolve().parent
#: source files whose text enters the fingerprint: the builder, not the tuning scripts (tuning*.py choose the
#: parameters, whose values are hashed; their text does not change a build)
SOURCES = sorted(p for p in PACKAGE.glob("*.py") if not p.name.startswith("tuning")) + [PACKAGE.parent / "build_paris.py"]


def build_inputs(params: ParisParams, n_cb: int, k3: float) -> dict:
    """The numbers a build depends on (JSON-able)."""
    p = {k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(params).items()}
    return dict(builder_version=BUILDER_VERSION, params=p, n_fixed_interface_modes=int(n_cb), k3=float(k3))


def build_fingerprint(params: ParisParams, n_cb: int, k3: float) -> str:
    h = hashlib.sha256(json.dumps(build_inputs(params, n_cb, k3), sort_keys=True).encode())
    for path in SOURCES:
        h.update(path.name.encode())
        h.update(path.read_bytes().replace(b"\r\n", b"\n"))
    return h.hexdigest()
