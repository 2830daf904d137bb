"""Exports of the Point tab offered to the browser as downloads (teaching, reports): the selected
branch's FEP (``nnm_solver.export_csv``) and the picked orbit over one period, as CSV bytes."""
from __future__ import annotations

import csv
import io
import re
import tempfile
from pathlib import Path

import numpy as np

import nnm_solver


def fep_csv(branch):
    """Bytes of ``nnm_solver.export_csv`` for ``branch`` (energy, frequency, period, stable, label)."""
    with tempfile.TemporaryDirectory(prefix="nnm-view-") as tmp:
        path = Path(tmp) / "fep.csv"
        nnm_solver.export_csv(path, branch)
        return path.read_bytes()


def orbit_columns(model):
    """Column names of the orbit CSV: t_s, then the model's DOF labels (x0..x{n-1} without them)."""
    labels = getattr(model, "dof_labels", None)
    if not labels or len(labels) != model.n:
        labels = [f"x{k}" for k in range(model.n)]
    return ["t_s", *labels]


def orbit_csv(point, model):
    """Bytes of the orbit ``point`` (info.PointData) as CSV: one row per time sample over one
    period, time (s) then the displacement (m or rad) of every DOF."""
    t = np.asarray(point.t, dtype=float)
    x = np.asarray(point.x, dtype=float).reshape(len(t), -1)
    if x.shape[1] != model.n:
        raise ValueError(f"the orbit has {x.shape[1]} DOFs, the model {model.n}")
    buf = io.StringIO(newline="")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(orbit_columns(model))
    for ti, xi in zip(t, x):
        w.writerow([repr(float(ti)), *(repr(float(v)) for v in xi)])
    return buf.getvalue().encode("utf-8")


def file_stem(text):
    """``text`` made safe as (part of) a file name."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(text)).strip("._") or "nnm"
