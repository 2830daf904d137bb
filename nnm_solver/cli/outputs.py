"""Where ``nnm-solve`` writes its results: --out, else the model's own file, never a shipped example or an unwritable
file (then ``<stem>_branches.h5`` in the current folder, with a notice)."""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path

__all__ = ["SHIPPED_EXAMPLES", "is_shipped_example", "default_out", "output_file", "check_plot_path"]


#: the example files shipped with the viewer (nnm_viewer/data), never written to by default
SHIPPED_EXAMPLES = ("paris.h5", "two_dof.h5")


def is_shipped_example(path):
    """True if ``path`` is one of the example files shipped in the nnm_viewer package (found
    without importing the viewer)."""
    try:
        spec = importlib.util.find_spec("nnm_viewer")
        p = Path(path).resolve()
    except (ImportError, ValueError, OSError):
        return False
    if spec is None or not spec.submodule_search_locations or p.name not in SHIPPED_EXAMPLES:
        return False
    return any(p == (Path(loc) / "data" / p.name).resolve() for loc in spec.submodule_search_locations)


def default_out(path):
    """(the file a branch computed on ``path`` is appended to, the reason it is not ``path`` or ''):
    ``path`` itself (FILE.h5 for a .mat file), unless it is a shipped example or cannot be written;
    then ``<stem>_branches.h5`` in the current folder."""
    from ..files.importers import is_import_path

    p = Path(path)
    out = p.with_suffix(".h5") if is_import_path(p) else p
    folder = out.parent if str(out.parent) else Path(".")
    if is_shipped_example(out):
        reason = f"{out.name} is a shipped example"
    elif not os.access(folder, os.W_OK) or (out.exists() and not os.access(out, os.W_OK)):
        reason = f"{out} is not writable"
    else:
        return out, ""
    return Path.cwd() / f"{p.stem}_branches.h5", reason


def output_file(args, notice):
    """The HDF5 file results go to: --out (an importable model path becomes <stem>.h5), else FILE, or
    ./<stem>_branches.h5 when FILE is a shipped example or cannot be written (``notice`` says so)."""
    from ..files.importers import is_import_path

    if args.out:
        out = Path(args.out)
        return out.with_suffix(".h5") if is_import_path(out) else out
    out, reason = default_out(args.file)
    if reason:
        print(f"nnm-solve: {reason}: " + notice.format(out=out), flush=True)
    return out


def check_plot_path(path):
    """NNMInputError (one line) if --plot PATH cannot be written: its folder missing, or a file type matplotlib does
    not write (from the suffix: .png, .pdf, .svg, ...; none: PNG); nothing for None.  Checked before anything is computed (an
    unknown suffix failed in matplotlib after the branch, with a traceback)."""
    from ..errors import NNMInputError

    if not path:
        return
    p = Path(path)
    if not p.resolve().parent.is_dir():
        raise NNMInputError(f"cannot write the plot: folder {p.parent} does not exist")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    kinds = FigureCanvasAgg(Figure()).get_supported_filetypes()
    suffix = p.suffix.lower().lstrip(".")
    if suffix and suffix not in kinds:              # (no suffix: matplotlib writes PNG, adding .png)
        raise NNMInputError(f"cannot write the plot {p.name}: give a file name ending in one of "
                            f"{', '.join('.' + k for k in sorted(kinds))}")
