"""The file layer's settings: its tolerances and sizes, written once.

``FILES`` is the instance the code reads (``FILES.model_rtol``); ``MODEL_RTOL`` (branch_io) and ``RIBBON_WIDTH``
(importers/nastran_mesh) stay importable as aliases of its fields.  A file format's own numbers (versions, a field's
range) are the format's, not settings: they stay beside their readers.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["FileSettings", "FILES"]


@dataclass(frozen=True)
class FileSettings:
    """Tolerances and sizes of the file readers and writers."""

    #: relative tolerance of the comparison of a model with the one a file holds (a model read back from a file is
    #: bit-identical; a model built again from the same description is too, up to rounding)
    model_rtol: float = 1e-10
    #: ribbon width of line elements of an imported display mesh, as a fraction of the model's bounding box diagonal
    ribbon_width: float = 0.02
    #: longest wait, in seconds, for another process's update of the same file (h5file.file_lock) before a save
    #: gives up with a one-line error naming the file; an update holds the lock only while it copies, appends and
    #: renames (never while computing), so a wait this long means a stuck writer
    lock_timeout: float = 120.0
    #: interval, in seconds, between two attempts to take a file's lock while waiting for it
    lock_poll: float = 0.02


#: the file layer's settings (the defaults above, written once)
FILES = FileSettings()
