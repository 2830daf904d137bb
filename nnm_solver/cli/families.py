"""``nnm-solve FILE --tongue K`` and ``--switch K``: the families that start on a saved branch, and the lists
that number them for the user (1-based, as printed after every run).

--tongue K continues the K-th tongue of a saved backbone (``continue_tongue``; the backbone computed with
``--tongues skip`` lists its tongues); --switch K the family born at the K-th branch point or period doubling of
a saved branch (``switch_branch``).  The saved branch is ``--branch NAME`` (or its 1-based number in the file),
else the last branch of ``--mode N`` that has what is asked for.
"""
from __future__ import annotations

import shlex

from ..errors import NNMInputError
from .pick import numbered_names, pick_branch

__all__ = ["SWITCHABLE", "FAMILY_FLAGS", "unused_flags", "tongue_lines", "switch_events", "switch_lines",
           "saved_branch", "compute_family"]

#: events a family can be switched onto (driver/switching.py)
SWITCHABLE = ("branch_point", "period_doubling")
#: the options of a branch run that each family takes from the command line; the others are refused (they were
#: silently ignored: --integrator gauss6 with --switch still gave newmark), with what the family uses instead
FAMILY_FLAGS = {
    "--tongue": (("--integrator", "--steps-per-period"),
                 "the tongue is continued by shooting with its backbone's settings, of which --integrator and "
                 "--steps-per-period can be changed"),
    "--switch": ((), "the family is continued by shooting with its parent branch's integrator and steps per period "
                     "(nnm.switch_branch)"),
}


def unused_flags(args):
    """(the family's flag, the branch options given on the command line that it does not use, what it uses); the
    list is empty when every option given is used.  --max-points, --tol and --energy-max go with both."""
    from .defaults import solver_defaults

    flag = "--tongue" if args.tongue is not None else "--switch"
    given = {"--integrator": args.integrator, "--steps-per-period": args.steps_per_period, "--freq-tol": args.freq_tol,
             "--method": args.method if args.method != solver_defaults()["method"] else None,
             "--harmonics": args.harmonics, "--condensed": args.condensed or None, "--energy-min": args.energy_min,
             "--tongues": args.tongues, "--floquet": args.floquet or None}
    used, why = FAMILY_FLAGS[flag]
    return flag, [f for f, v in given.items() if v is not None and f not in used], why


def tongues_of(branch):
    """The tongues of ``branch`` that ``continue_tongue`` can start (not the records of the family's own end)."""
    return [t for t in getattr(branch, "tongues", None) or [] if not t.get("family_end") and "entry_x0" in t]


def tongue_lines(branch, out=None):
    """One line per tongue of ``branch`` that --tongue K continues, numbered from 1, with the command that does
    (``out``: the file the branch is saved in); [] if none."""
    where = shlex.quote(str(out)) if out is not None else "..."
    lines = []
    listed = tongues_of(branch)
    for k, t in enumerate(listed, 1):
        partner = f" with mode {t['partner_mode']}" if t.get("partner_mode") else ""
        how = _how(branch, t, last=k == len(listed))
        back = f", back on the backbone at {t['exit_energy']:.4g} J" if "exit_energy" in t else ""
        lines.append(f"  tongue {k}: {t.get('label', 'tongue')}{partner}, entered at E = {t['entry_energy']:.4g} J, "
                     f"f = {t['entry_frequency_hz']:.5f} Hz ({how}{back}; nnm-solve {where} --tongue {k} continues it)")
    return lines


def _how(branch, t, last):
    """What the branch did at tongue record t: jumped it (skip), ended at its entry (the last record of a branch
    that ended in a tongue, not jumped), or followed it through (follow)."""
    if t.get("skipped"):
        return "jumped"
    if last and branch.status == "tongue":
        return "not passed: the branch ends at its entry"
    return "followed through"


def switch_events(branch):
    """The located events of ``branch`` a family can be switched onto, in branch order."""
    return [e for e in branch.events if e.get("kind") in SWITCHABLE and "x0" in e]


def switch_lines(branch, out=None):
    """One line per event --switch K starts from, numbered from 1, with the command that does (``out``: the file
    the branch is saved in); [] if none."""
    where = shlex.quote(str(out)) if out is not None else "..."
    return [f"  switch {k}: {e['kind'].replace('_', ' ')} near point {int(e['index']) + 1}, E = {e['energy']:.4g} J, "
            f"f = {e['frequency_hz']:.5f} Hz (nnm-solve {where} --switch {k} --energy-max E continues the family "
            f"born there)"
            for k, e in enumerate(switch_events(branch), 1)]


def saved_branch(path, model, name, mode, has, what):
    """The saved branch a family starts from: ``name`` (its name in the file, or its 1-based number), else the
    last branch of ``mode`` (any mode if None) for which ``has(branch)`` holds; one-line NNMInputError if none."""
    from ..files.branch_io import load_branches

    branches = load_branches(path, model=model)
    if not branches:
        raise NNMInputError(f"{path} holds no branch to start {what} from; compute one first (nnm-solve FILE --mode N "
                            f"--energy-max E --tongues skip)")
    if name is not None:
        return pick_branch(branches, name, path)
    fit = [b for b in branches if (mode is None or b.mode == mode) and has(b)]
    if not fit:
        where = f" of mode {mode}" if mode is not None else ""
        raise NNMInputError(f"{path} holds no branch{where} with {what} ({numbered_names(branches)}); compute one "
                            f"first or choose one with --branch NAME or number")
    return fit[-1]


def _number(k, count, flag, what, branch):
    if count == 0:
        raise NNMInputError(f"branch {branch.name or branch.mode} lists no {what}")
    if not 1 <= k <= count:
        raise NNMInputError(f"{flag} {k}: branch {branch.name or branch.mode} lists {count} {what} (1..{count})")
    return k - 1


def compute_family(args, model, options):
    """(the parent branch, the family computed from it, a title) for --tongue K or --switch K; ``options``: the
    continuation options given on the command line (max_points, tol, steps...)."""
    from ..driver.switching import switch_arguments, switch_branch
    from ..driver.tongue_branch import continue_tongue, tongue_arguments

    if args.tongue is not None:
        parent = saved_branch(args.file, model, args.branch, args.mode, lambda b: bool(tongues_of(b)), "tongues")
        i = _number(args.tongue, len(tongues_of(parent)), "--tongue", "tongues", parent)
        tongue = tongues_of(parent)[i]
        # the family's limits checked before anything is printed: bad input is the one error line
        limits = {k: v for k, v in options.items() if k in ("max_points", "tol", "steps_per_period", "integrator")}
        tongue_arguments(parent, tongue, args.energy_max, **limits)
        print(f"continuing tongue {args.tongue} ({tongue.get('label', 'tongue')}) of {parent.name or parent.mode}, "
              f"from E = {tongue['entry_energy']:.4g} J", flush=True)
        kw = {k: v for k, v in options.items() if k in ("max_points", "tol", "steps_per_period", "integrator")}
        family = continue_tongue(parent, tongue, energy_max=args.energy_max, **kw)
        return parent, family, f"tongue {args.tongue} of {parent.name or f'NNM {parent.mode}'}"
    if args.energy_max is None:
        raise NNMInputError("--switch K needs --energy-max E (where the new family's continuation stops)")
    parent = saved_branch(args.file, model, args.branch, args.mode, lambda b: bool(switch_events(b)),
                          "a located branch point or period doubling")
    i = _number(args.switch, len(switch_events(parent)), "--switch", "branch points or period doublings", parent)
    event = switch_events(parent)[i]
    kw = {k: v for k, v in options.items() if k in ("max_points", "tol")}
    switch_arguments(parent, event, args.energy_max, **kw)         # (as for --tongue: before anything is printed)
    print(f"switching at {event['kind'].replace('_', ' ')} {args.switch} of {parent.name or parent.mode} "
          f"(E = {event['energy']:.4g} J)", flush=True)
    family = switch_branch(parent, event, args.energy_max, **kw)
    return parent, family, f"family born at {event['kind'].replace('_', ' ')} {args.switch} of " \
                           f"{parent.name or f'NNM {parent.mode}'}"
