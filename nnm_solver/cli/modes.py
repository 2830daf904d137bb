"""``nnm-solve FILE --list-modes``: the table of a model's linear modes (1-based numbers, Hz), with the file's
reference frequencies and mode labels where it has them."""
from __future__ import annotations

import sys

import numpy as np

__all__ = ["list_modes", "list_modes_legend", "reference_mode_names", "label_with_reference"]


def reference_mode_names(reference):
    """{mode (1-based): the reference's name of it} from a file's /extra/reference/mode_names ('' entries and a
    missing dataset: none).  The reference numbers its modes as the model does (Table 2 of a paper, say) but may
    name them otherwise: the Paris model's 'wing torsion 2 (symmetric)' is the paper's first symmetric torsion."""
    names = (reference or {}).get("mode_names")
    if names is None:
        return {}
    return {k: str(n).strip() for k, n in enumerate(np.atleast_1d(names).tolist(), 1) if str(n).strip()}


def label_with_reference(label, name):
    """The model's label of a mode with the reference's name where the reference has one: 'wing torsion 2
    (symmetric); paper: first (symmetric) wing torsion'."""
    if not name:
        return label
    return f"{label}; paper: {name}" if label else f"paper: {name}"


def list_modes(model, reference=None, count=30, out=sys.stdout):
    from ..model import sparse_modes
    from ..model.settings import MODEL
    # a model too large for the dense eigensolution (a full FE model): its lowest modes by sparse Lanczos
    freqs = sparse_modes(model, count)[0] if model.n > MODEL.max_dense_dof else model.linear_modes()[0]
    labels = model.mode_labels or []
    named = reference_mode_names(reference)
    table = None
    if reference and "table2_hz" in reference:
        table = np.asarray(reference["table2_hz"], dtype=float)
    head = f"{'mode':>4}  {'freq (Hz)':>11}"
    if table is not None:
        head += f"  {'reference':>10}  {'diff':>7}"
    print(head + "  label", file=out)
    for k in range(min(count, model.n)):
        line = f"{k + 1:>4}  {freqs[k]:>11.4f}"
        if table is not None:
            if k < len(table):
                line += f"  {table[k]:>10.4f}  {100 * (freqs[k] / table[k] - 1):>+6.2f}%"
            else:
                line += " " * 21
        label = label_with_reference(labels[k] if k < len(labels) else "", named.get(k + 1, ""))
        print(line + ("  " + label if label else ""), file=out)
    source = str(reference.get("source", "")) if table is not None else ""
    print(list_modes_legend(table is not None, bool(labels) or bool(named), source), file=out)


def list_modes_legend(reference, labels, source=""):
    """The line under --list-modes' table saying what its columns are (reference, labels: whether the
    table has the reference and label columns; source: where the reference frequencies come from)."""
    words = ["mode: the number --mode takes (1-based)", "freq: linear natural frequency (Hz)"]
    if reference:
        words += [f"reference: the file's reference frequency of that mode (Hz; /extra/reference/table2_hz"
                  f"{', from the ' + source if source else ''})", "diff: freq / reference - 1"]
    if labels:
        words.append("label: the mode's description stored in the file (and the reference's name of it, "
                     "'paper: ...', from /extra/reference/mode_names)")
    return "columns: " + "; ".join(words)
