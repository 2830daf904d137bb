"""What ``nnm-solve`` prints after a branch (summary, events, the points off the backbone, tongues and branch points
numbered from 1 for --tongue K / --switch K, accuracy) and what it writes (the branch, the plot, the exports)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["ACCURACY_ADVICE", "accuracy_line", "report_and_save"]


#: what to change when a shooting branch's error exceeds 1e-4, by what computed it (the options it takes)
ACCURACY_ADVICE = {"branch": "raise --steps-per-period, or use --integrator gauss6 or --freq-tol",
                   "tongue": "raise --steps-per-period, or use --integrator gauss6",
                   "switch": "the family takes its parent branch's time steps: recompute the parent with more "
                             "--steps-per-period or --integrator gauss6"}


def accuracy_line(branch, made_by="branch"):
    """One line on the branch's estimated frequency errors (branch.freq_error) and its integrator; ``made_by``
    ('branch', 'tongue' for --tongue K, 'switch' for --switch K) chooses the advice (ACCURACY_ADVICE)."""
    s = branch.settings
    err = np.asarray(getattr(branch, "freq_error", []), dtype=float)
    if np.isnan(err).all():
        return "  accuracy: no per-point error estimate"
    if s.method != "shooting":                 # harmonic balance: the truncation of the harmonics (hb_error.py)
        fin = np.isfinite(err)
        unresolved = int(np.sum(np.isinf(err)))
        if not fin.any():
            return (f"  accuracy: harmonic balance, {s.harmonics} harmonics; the truncation does not resolve any point "
                    f"(raise --harmonics)")
        i = int(np.flatnonzero(fin)[np.argmax(err[fin])])
        more = " (raise --harmonics)" if err[i] > 1e-4 or unresolved else ""
        text = (f"  accuracy: harmonic balance, {s.harmonics} harmonics; estimated frequency error (truncation) "
                f"median {np.median(err[fin]):.1e}, max {err[i]:.1e} at point {i + 1} (E = {branch.energy[i]:.4g} J)")
        if unresolved:
            text += f"; {unresolved} points not resolved by the truncation (no orbit with two harmonics more near them)"
        return text + more
    ok = np.isfinite(err)
    if not ok.any():
        return "  accuracy: no per-point error estimate"
    i = int(np.flatnonzero(ok)[np.argmax(err[ok])])
    steps = sorted({int(x) for x in getattr(branch, "steps", []) if x}) or [s.steps_per_period]
    more = f" ({ACCURACY_ADVICE[made_by]})" if err[i] > 1e-4 else ""
    return (f"  accuracy: {s.integrator}, {'/'.join(map(str, steps))} steps per period; estimated frequency error "
            f"median {np.median(err[ok]):.1e}, max {err[i]:.1e} at point {i + 1} (E = {branch.energy[i]:.4g} J){more}")


def report_and_save(args, model, branch, out, what, title, dt):
    """Print the branch's summary, events (points numbered from 1), tongues and accuracy; save it to ``out``; write
    the plot and the exports asked for; the exit code (1 for a failed branch)."""
    from . import exchange as cli_exchange
    from ..files.branch_io import save_branch
    from .families import switch_lines, tongue_lines

    print(f"{what}: {len(branch)} points in {dt:.1f} s, energy {branch.energy.min():.3e}.."
          f"{branch.energy.max():.3e} J, frequency {branch.frequency_hz[0]:.5f} -> {branch.frequency_hz[-1]:.5f} Hz; "
          f"{branch.status}: {branch.message}" if len(branch) else f"no point converged: {branch.message}")
    for e in branch.events:
        print(f"  {e['kind']:<12} near point {int(e['index']) + 1:>4}: E = {e['energy']:.4e} J, "
              f"f = {e['frequency_hz']:.5f} Hz  ({e['detail']}"
              + (f"; {e['stability_change']} of stability" if e.get("kind") == "fold" and e.get("stability_change")
                 else "") + (f"; {e['note']}" if e.get("note") else "") + ")")
    off = [str(x) for x in dict.fromkeys(branch.labels) if str(x) != "backbone"]
    if off:
        print(f"  points off the backbone: {', '.join(off)} ({int(sum(str(x) != 'backbone' for x in branch.labels))} "
              f"of {len(branch)}; marked on the plot)")
    for line in tongue_lines(branch, out) + switch_lines(branch, out):
        print(line)
    made_by = "tongue" if getattr(args, "tongue", None) is not None else \
        "switch" if getattr(args, "switch", None) is not None else "branch"
    print(accuracy_line(branch, made_by))
    if len(branch):
        name = save_branch(out, branch)
        print(f"saved as /branches/{name} in {out}")
        if args.plot:
            from ..results.plotting import plot_fep
            plot_fep(branch, path=args.plot, title=f"{model.name or Path(args.file).stem}: {title}")
            print(f"FEP written to {args.plot}")
        cli_exchange.write_exports(args, branch)
    # a branch that ends by its own physics (escape to a saddle, a closed loop) is a result, not an error
    return 1 if branch.status == "failed" else 0
