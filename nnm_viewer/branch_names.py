"""The names of branches in the viewer's lists and legends: 'NNM <k> (<the model's label of mode k>)', what the
stored name adds, the k3 factor and the branch's state in this session."""
from __future__ import annotations

import re


def mode_name(model, mode):
    """The model's label of linear mode ``mode`` (1-based), or ''."""
    labels = getattr(model, "mode_labels", None) or []
    try:
        k = int(mode)
    except (TypeError, ValueError):
        return ""
    return str(labels[k - 1]).strip() if 1 <= k <= len(labels) else ""


def name_remainder(name, mode):
    """What a branch's stored ``name`` adds to 'NNM <mode>': '' for 'NNM1', 'mode 14', a sweep's
    'variant <variant>' for a sweep's '<variant>:mode<N>'; 'paper mode 13' for
    'mode14 (paper mode 13)'; 'harmonic balance H15' for 'NNM1 harmonic balance H15'; 'run 2' for
    'mode1_2' (save_branch's name of a second branch of mode 1 in the same file)."""
    from nnm_solver.sweeps import parse_branch_name

    name = str(name or "").strip()
    swept = parse_branch_name(name)
    if swept is not None:
        return f"variant {swept[0]}"
    if not name:
        return ""
    m = re.match(rf"^\s*(?:nnm|mode)\s*{re.escape(str(mode))}(?![0-9])\s*(.*)$", name, flags=re.IGNORECASE)
    rest = m.group(1) if m else name
    run = re.match(r"^_(\d+)\b\s*(.*)$", rest) if m else None
    if run:                                       # 'mode1_2': the second branch of mode 1 saved to the file
        rest = f"run {run.group(1)}" + (f" {run.group(2)}" if run.group(2) else "")
    rest = rest.strip().strip(":,-;").strip()
    if rest.startswith("("):                      # '(paper mode 13): tongue 1 (5:1)' -> 'paper mode 13: ...'
        depth = 0
        for k, ch in enumerate(rest):
            depth += {"(": 1, ")": -1}.get(ch, 0)
            if depth == 0:
                rest = (rest[1:k] + rest[k + 1:]).strip()
                break
    return rest


def legend_label(label, width=42):
    """A branch label for the FEP legends: without the mode's label ('NNM 14 (fin bending 1) · paper
    mode 13' -> 'NNM 14 · paper mode 13'; the lists and the readout give it), at most ``width``
    characters."""
    text = str(label)
    m = re.match(r"^(NNM \S+) \(", text)
    if m:
        depth, start = 0, m.end() - 1
        for k in range(start, len(text)):
            depth += {"(": 1, ")": -1}.get(text[k], 0)
            if depth == 0:
                text = m.group(1) + text[k + 1:]
                break
    return text if len(text) <= width else text[:width - 1].rstrip() + "\u2026"


def branch_label(branch, k3_factor=1.0, source="file", model=None, reference=None):
    """The branch's name in every list and legend: 'NNM <k> (<the model's label of mode k>)', then
    what its stored name adds (' · harmonic balance H15'), the k3 factor if not 1 and, for a branch
    of this session, its state: 'NNM 2 (out-of-phase mode) (k3 x 10) [running]'.  ``model``: whose
    mode labels to use when the branch carries no model of its own; ``reference``: {mode: the file's reference
    name of it} (cli.modes.reference_mode_names), said with the model's label: 'NNM 19 (wing torsion 2
    (symmetric); paper: first (symmetric) wing torsion)'."""
    from nnm_solver.cli.modes import label_with_reference

    mode = getattr(branch, "mode", "?")
    label = mode_name(getattr(branch, "model", None) or model, mode) or mode_name(model, mode)
    try:
        label = label_with_reference(label, (reference or {}).get(int(mode), ""))
    except (TypeError, ValueError):
        pass
    text = f"NNM {mode}" + (f" ({label})" if label else "")
    extra = name_remainder(getattr(branch, "name", ""), mode)
    if extra:
        text += f" \u00b7 {extra}"
    if abs(k3_factor - 1.0) > 1e-12:
        text += f" (k3 x {k3_factor:.3g})"
    if source in ("running", "stopped", "failed"):
        text += f" [{source}]"
    elif source == "computed":
        text += " [new]"
    elif source == "saved":
        text += " [saved]"
    return text
