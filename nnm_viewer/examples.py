"""The example files shipped with the package, and where branches computed on them are saved.

The examples (the Paris-like aircraft ``paris.h5`` and the 2-DOF teaching model ``two_dof.h5``) are
package data of ``nnm_viewer`` (``nnm_viewer/data/``; in the source tree that folder is a link to
``assets/``), so ``nnm-view paris.h5`` works from any folder after ``pip install .``.  A name given
to ``nnm-view`` that is not an existing file is looked up among them.

A shipped example is never written to: a branch saved from the viewer on one goes to
``<stem>_branches.h5`` in the current folder (the model and that branch), as does a branch saved
on a file that cannot be written.
"""
from __future__ import annotations

import os
from pathlib import Path

#: the shipped examples (file names in nnm_viewer/data)
SHIPPED = ("paris.h5", "two_dof.h5")
#: opened by ``nnm-view`` without an argument
DEFAULT_EXAMPLE = "paris.h5"


def data_dir():
    """The folder of the shipped examples (inside the installed package)."""
    return Path(__file__).resolve().parent / "data"


def shipped_examples():
    """{name: path} of the shipped examples present in the installation."""
    d = data_dir()
    return {name: d / name for name in SHIPPED if (d / name).is_file()}


def example_path(name):
    """Path of the shipped example called ``name`` ('paris.h5', 'paris', or any path ending so:
    'assets/paris.h5'), or None."""
    base = Path(str(name)).name
    examples = shipped_examples()
    for cand in (base, base + ".h5"):
        if cand in examples:
            return examples[cand]
    return None


def is_shipped(path):
    """True if ``path`` is one of the shipped example files."""
    try:
        p = Path(path).resolve()
    except OSError:
        return False
    return any(p == q.resolve() for q in shipped_examples().values())


class MissingFile(LookupError):
    """No such file and no shipped example of that name (the message lists the examples)."""


def resolve_file(name=None):
    """(path, shipped) of the file to open: ``name`` if it exists, else the shipped example of that
    name; the default example when ``name`` is None.  MissingFile otherwise."""
    if name is None:
        name = DEFAULT_EXAMPLE
    p = Path(str(name)).expanduser()
    if p.exists():
        return p, is_shipped(p)
    ex = example_path(name)
    if ex is not None:
        return ex, True
    names = ", ".join(shipped_examples()) or "none installed"
    raise MissingFile(f"{name}: no such file (shipped examples, opened by name from any folder: {names})")


def writable(path):
    """True if ``path`` can be replaced by an atomic write (the file, if it exists, and its folder)."""
    p = Path(path)
    folder = p.parent if str(p.parent) else Path(".")
    return os.access(folder, os.W_OK) and (not p.exists() or os.access(p, os.W_OK))


def branch_output(path):
    """(file the branches computed on ``path`` are saved to, reason or '').  The file itself, unless
    it is a shipped example or cannot be written: then ``<stem>_branches.h5`` in the current folder."""
    p = Path(path)
    if is_shipped(p):
        reason = f"{p.name} is a shipped example"
    elif not writable(p):
        reason = f"{p} is not writable"
    else:
        return p, ""
    return Path.cwd() / f"{p.stem}_branches.h5", reason
