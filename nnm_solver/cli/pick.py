"""Which saved branch a command means: ``--branch NAME`` (its name as listed) or its 1-based number in the file, the
same for every command that reads one (nnm-solve --tongue / --switch, nnm-solve export)."""
from __future__ import annotations

from ..errors import NNMInputError

__all__ = ["pick_branch", "numbered_names"]


def numbered_names(branches):
    """'1: name, 2: name, ...' of ``branches`` (their 1-based numbers and names, as --branch takes them)."""
    return ", ".join(f"{k}: {b.name}" for k, b in enumerate(branches, 1))


def pick_branch(branches, name, path):
    """The branch of ``branches`` (read from the file ``path``) that ``--branch name`` means: the one of that name,
    else the one of that 1-based number; one-line NNMInputError listing the numbered names if there is none."""
    names = [b.name for b in branches]
    if name in names:
        return branches[names.index(name)]
    if str(name).isdigit() and 1 <= int(name) <= len(branches):
        return branches[int(name) - 1]
    raise NNMInputError(f"--branch {name}: no such branch in {path} ({numbered_names(branches)}; a name or a number "
                        f"1..{len(branches)})")
