r"""The iteration over one branch's converged orbits: ``NNMIterator`` (created by ``iter_nnm``).

Each ``next()`` runs the pseudo-arclength engine (continuation.py) to the next converged orbit and
turns it into a ``Point``: energy, frequency, initial state, Floquet multipliers and stability
(floquet.py), harmonic label (tongue_skip.py).  Around it: a step that jumped onto another branch (its
mid-step point off the interpolant of its ends, locator.Locator.jumped) or whose events cannot be located is
refused (the engine halves it), the events between consecutive points are located (events.py), the branch is
cut exactly at energy_max, the stop reasons are checked (stops.py), and in ``tongues="skip"`` mode the
internal-resonance tongues are jumped over or traversed unseen.
"""
from __future__ import annotations


import numpy as np

from ..results.branch import Branch
from ..continuation.engine import REFUSE, ContinuationPoint, energy_slope, pseudo_arclength
from ..continuation.engine_driver import EngineDriver
from ..stability.events import Locator, locate_between
from ..stability.floquet import is_stable, sort_multipliers
from ..stability.settings import STABILITY
from ..stability.step_policy import event_rtol, mid_step_check
from ..backbone.jumps import find_landing, upward_tangent
from ..backbone.labels import Verdict
from ..backbone.settings import LabelSettings
from ..backbone.policy import Finish, FollowPolicy, Jump
from .candidate import record_candidate
from .stop_rules import closed_loop, stop_after_point, stop_on_failure, turning_ratio
from .refinement import HarmonicRefinement, StepRefinement, accuracy_note
from ..orbits.hb_basis import harmonics_in
from ..results.stops import LoopDetector
from ..results.tongues import continue_hint
from ..threads import blas_limited


__all__ = ["NNMIterator"]


class NNMIterator:
    """Iterator over the converged points of one NNM branch (create it with ``iter_nnm``).

    Each ``next()`` runs the continuation to the next converged orbit and returns its ``Point``.
    The iteration ends by itself at energy_max, at max_points, when the branch returns to low
    energy, escapes, closes a loop, or when the continuation cannot go on; ``status`` and ``message``
    then say why (stops.py lists the statuses).  ``cancel()`` (or a ``break`` followed by ``branch()``) ends it
    early ('cancelled' / 'stopped').  ``branch()`` returns the Branch of every point so far.
    """

    def __init__(self, model, mode, problem, system, engine, settings, energy_max, max_points, continuation=None,
                 tol=None, locate=True, error_estimate=True, freq_tol=None, labels=None, policy=None,
                 start_is_low=True, max_refusals=3, max_steps_per_period=20000, max_harmonics=0):
        self.model = model
        self.max_refusals = int(max_refusals)            # driver/settings.py: Continuation.max_refusals
        self._refinement = StepRefinement(freq_tol, error_estimate, max_steps_per_period)   # freq_tol, estimates
        self._harmonics = HarmonicRefinement(freq_tol, max_harmonics)      # freq_tol of harmonic balance
        self.freq_tol = self._refinement.freq_tol
        self.mode = int(mode)
        self.settings = settings
        self.energy_max = float(energy_max)
        self.max_points = int(max_points)
        self.points = []
        self._disc_errors = []         # the time discretisation's part of each kept point's freq_error
        self.status = "running"
        self.message = ""
        self._problem = problem
        self._system = system
        self._w_r = float(np.sqrt(system.omega2[mode - 1]))
        self._loops = LoopDetector(mirror=system.elements.odd)
        self._last = None
        self._prev = None              # (ContinuationPoint, Candidate, dE/ds) of the last point
        self._cs, self._tol = continuation, tol
        self.locate = bool(locate) and continuation is not None and hasattr(problem, "energy")
        self.events = []
        self._landed = False
        self._labels = labels          # FamilyLabels (backbone/labels.py): point labels against the skeleton, or None
        self._policy = policy if policy is not None else FollowPolicy()   # backbone/policy.py: keep, jump or finish
        self.tongues = []              # TongueRecords (results/tongues.py)
        self._start_is_low = bool(start_is_low)   # the branch starts at low energy (not a tongue from its entry)
        self._last_kept = None         # (ContinuationPoint, Candidate) of the last point kept
        self._run = []                 # (E, f) of the points kept on the family since the last jump
        self._run_length = (labels.settings if labels is not None else LabelSettings()).run_length
        self._refusals = 0             # steps refused in a row because an event in them was not located
        # the engine's next point, computed while the last point's multipliers are (in the worker thread)
        self._ahead = bool(settings.floquet and getattr(problem, "background_spectrum", False))
        self._engine = EngineDriver(engine, problem, continuation, tol, launch=(
            (lambda cp: self._problem.multipliers_later(cp.u, cp.tangent)) if self._ahead else None))

    def __iter__(self):
        return self

    def __next__(self):
        if self.status != "running":
            raise StopIteration
        N = len(self.points)
        with blas_limited():
            command = None
            while True:
                kind, cp = self._engine.next(command, self._prev[0] if self._prev else None)
                if kind == "stop":
                    self._failed(cp)
                    raise StopIteration
                command = None
                cand, (q0, v0, T) = self._record(cp, self._problem, later=self._ahead)
                finer = self._refinement.refine(self._problem, cp, cand, self._cs, self._tol)
                if finer is not None:           # the point again with a finer time step
                    self._engine.restart(finer)
                    self._prev = None           # no event is located across a change of time step
                    self._refusals = 0
                    continue
                if self._harmonics.freq_tol:
                    self._refinement.estimate(cand)
                    more = self._harmonics.refine(self._problem, cp, cand, self._cs, self._tol)
                    if more is not None:        # the point again with more harmonics
                        self._more_harmonics(*more)
                        continue
                decision = self._decide(cp, cand)
                if isinstance(decision, Jump):
                    decision = self._jump(cp, decision)
                    if decision is None:        # landed beyond the tongue: the continuation restarts there
                        continue
                if isinstance(decision, Finish):
                    self._apply(decision)
                    raise StopIteration
                if self._ahead:             # the next step runs while this point's eigenproblem does
                    self._engine.ahead()
                self._settle(cand)
                if not self.locate:
                    break
                located = self._locate(cp, cand, (q0, v0, T))
                if located is not None:
                    cand, (q0, v0, T) = located
                    break
                command = REFUSE                # an event could not be located: a shorter step
            point = cand.point
            self._last_kept = (cp, cand)
            if point.label == "backbone":       # the run of points on the family since the last jump (labels.py)
                self._run = self._run[-self._run_length:] + [(point.energy, point.frequency_hz)]
            else:
                self._run = []
            self._refinement.estimate(cand)
            cand.release()
        loop = self._loops.add(q0, v0, self._w_r, T, 2 * np.pi / self._w_r)
        if loop is not None:
            self._finish(*closed_loop(self.points, N, loop))
            raise StopIteration
        self.points.append(point)
        self._disc_errors.append(cand.disc_error)
        # (a lower bound over samples that include the turning point's, above the thresholds: its ratio is too)
        ratio = (cand.restoring if cand.restoring_bound
                 else min(turning_ratio(self._system, self._w_r, q0, v0), cand.restoring))
        stop = stop_after_point(self.points, ratio, self.energy_max, self.max_points, self._landed,
                                self._start_is_low, self._policy.note)
        if stop is not None:
            self._finish(stop.status, stop.message)
        self._last = (q0, v0)
        return point

    def _more_harmonics(self, problem, engine):
        """Go on with the harmonic-balance problem with more harmonics (HarmonicRefinement): the points so far get
        its basis (their higher harmonics zero, which they are at their truncation), the settings its harmonics."""
        old = self._problem.basis
        for p in self.points:
            p.coefficients = harmonics_in(problem.basis, old, p.coefficients)
        if self._last_kept is not None:        # its tangent orients a later jump's landing (upward_tangent)
            cp0, c0 = self._last_kept
            self._last_kept = (ContinuationPoint(self._problem.embedded(problem, cp0.u),
                                                 self._problem.embedded(problem, cp0.tangent), None,
                                                 cp0.iterations, cp0.step, cp0.error), c0)
        self._problem = self._engine.problem = problem
        self._engine.restart(engine)
        self.settings = self.settings.replace(harmonics=problem.basis.harmonics,
                                              samples=None if self.settings.samples is None else problem.basis.samples)
        self._prev = None                       # no event is located across a change of the truncation
        self._refusals = 0

    def _settle(self, cand):
        """Wait for the multipliers of a point recorded with later=True: its floquet, stable and collision."""
        if cand.spectrum is not None:
            mu, cand.collision = cand.spectrum()
            cand.point.floquet = sort_multipliers(mu)
            cand.point.stable = is_stable(cand.point.floquet, STABILITY.stability_tol)
            cand.spectrum = None

    def _failed(self, reason):
        """The continuation could not go on: escape next to a saddle, the family's end (the policy), else failed."""
        restoring = self._last_kept[1].restoring if self._last_kept else 1.0
        ratio = min(turning_ratio(self._system, self._w_r, *self._last), restoring) if self.points else 1.0
        stop = stop_on_failure(self.points, ratio, reason)
        if stop.status == "failed" and self.points and self._family_ends(reason):
            return
        self._finish(stop.status, stop.message)

    def _family_ends(self, reason):
        """The continuation failed where the backbone family itself ends (the policy's ``stopped``): finish there.
        True when the branch was finished."""
        end = self._policy.stopped(self.points[-1], reason, len(self.points) - 1)
        if end is None:
            return False
        self._apply(end)
        return True

    def _decide(self, cp, cand):
        """The point's label (against the skeleton, with its error estimated first) and the policy's decision."""
        point, obs = cand.point, cand.observed
        verdict = Verdict(obs[0].label)
        if self._labels is not None:
            self._refinement.estimate(cand)
            falling = bool(self.points) and point.energy < self.points[-1].energy * (1 - 1e-9)
            verdict = self._labels.verdict(point.energy, point.frequency_hz, obs[0], point.freq_error, self._run,
                                           falling=falling, steps=point.steps)
            point.label = verdict.text
            cand.distance = (verdict.dev, verdict.tolerance)
        return self._policy.decide(point, verdict, obs[0], obs[1], self._last_kept[1].point if self._last_kept else None,
                                   len(self.points), self.tongues)

    def _jump(self, cp, jump):
        """Try the jump's targets (backbone/jumps.py: ``find_landing``); restart the continuation at the first that
        lands on the family and record the tongue (None), or the policy's Finish when none lands."""
        prob, (bcp, bcand) = self._problem, self._last_kept
        bpoint = bcand.point
        landing, tried = find_landing(prob, self._system, self._policy, self._labels, jump, self._run, self._cs,
                                      self._tol)
        record = jump.record.replace(attempts=jump.record.attempts + len(tried))
        if landing is None:
            return self._policy.no_landing(bpoint, record, tuple(tried), jump.index)
        u, J, E, f = landing
        record = record.replace(skipped=True, exit_energy=E, exit_frequency_hz=f, landings=record.landings + (
            len(self.points),), jump=f"the skeleton's orbit at {tried[-1]:.4g} J")
        if self._policy.recorded(record):
            self._store(record, jump.index)
        self._engine.restart(pseudo_arclength(prob, u, upward_tangent(prob, u, J, bcp.tangent), self._cs, self._tol))
        self._prev = None          # no events are located across the jump
        self._refusals = 0
        self._run = []
        return None

    def _store(self, record, index):
        """Add a tongue record (index -1) or replace the one at ``index``."""
        if index is None or index < 0:
            self.tongues.append(record)
        else:
            self.tongues[index] = record

    def _apply(self, finish):
        """Finish the branch as the policy decided; a tongue it ends in is named as a user follows it (the API's
        0-based index into branch.tongues, nnm-solve's 1-based --tongue K: results/tongues.continue_hint)."""
        message = finish.message
        if finish.record is not None:
            self._store(finish.record, finish.index)
            if finish.status == "tongue":
                index = finish.index if finish.index >= 0 else len(self.tongues) - 1
                message += continue_hint(self.tongues, index, self.settings.method == "shooting")
        self._finish(finish.status, message)

    def _locate(self, cp, cand, state):
        """Locate the events between the previous point and this one (events.py); cut the branch at
        energy_max.  Returns the (possibly located) end point and its modal state, or None when an event
        could not be located and the step should be refused (at most Continuation.max_refusals times in a row)."""
        point = cand.point
        slope = energy_slope(self._problem, cp.u, cp.tangent)
        prev, self._prev = self._prev, (cp, cand, slope)
        if prev is None:
            return cand, state
        pcp, pcand, pslope = prev
        ppoint = pcand.point
        loc = Locator(self._problem, self._cs, self._tol, pcp.u, pcp.tangent, step=cp.step,
                      rtol=event_rtol(pcand.disc_error))
        loc.cache[0.0] = (pcp.u, pcp.jacobian, pcp.tangent)
        if self._ahead:                    # the engine went on to the next point: its copy's state at this one again
            loc.problem.accept(cp.u, cp.jacobian)
        if cp.factor is not None:          # the engine's factorisation of [J; (w^2 p_a)^T] at the new point
            loc.seed(cp.step, cp.u, cp.jacobian, cp.factor)
        for sigma, c in ((0.0, pcand), (cp.step, cand)) if self.settings.floquet else ():  # their multipliers are known
            if not np.isnan(c.point.floquet).any():                                           # too (NaN: floquet off)
                loc.spectra[float(sigma)] = (c.point.floquet, c.collision)
        if (self._refusals < self.max_refusals and cp.step > 4 * self._cs.step_min
                and mid_step_check(cp.step, (pcand.distance, cand.distance)) and loc.jumped()):
            # the step's corrector landed on another branch alongside (near a tongue): half the step
            self._refusals += 1
            self._prev = prev
            return None

        made = {}                          # id(Point) -> its Candidate, for the cut at energy_max

        def record(sigma):
            u, J, p = loc.at(sigma)
            loc.refresh(u, J)
            c = self._record(ContinuationPoint(u, p, J, 0, sigma, 0.0), loc.problem,
                             known=loc.spectra.get(float(sigma)))[0]
            if self._labels is not None:
                c.point.label = self._labels.verdict(c.point.energy, c.point.frequency_hz, c.observed[0],
                                                     steps=c.point.steps).text
            c.observed = None
            made[id(c.point)] = c
            if not np.isnan(c.point.floquet).any():     # its multipliers and Krein coordinates, for the locators
                loc.spectra.setdefault(float(sigma), (c.point.floquet, c.collision))
            return c.point

        events, end = locate_between(loc, cp.step, (ppoint, pslope), (point, slope), len(self.points), record,
                                     self.energy_max)
        if ((any(not e["located"] for e in events) or loc.strayed()) and self._refusals < self.max_refusals
                and cp.step > 4 * self._cs.step_min):
            # the corrector failed inside the step, or a point located in it lies off its ends' interpolant: it
            # jumped over a feature of the branch (e.g. a fold and a branch point, three folds next to each other, a
            # narrow tongue's entrance); the engine retries with a shorter step
            self._refusals += 1
            self._prev = prev
            return None
        self._refusals = 0
        self.events.extend(events)
        if end is not None:
            u, J, p = loc.at(end[0])
            ecand = made[id(end[1])]
            if J is None:                  # (not kept by the locator) the last point's error estimate needs it
                J = loc.problem.jacobian(u)[1]
                ecand.solution = (loc.problem, u, J, p, None)
            end[1].label = point.label          # the cut at energy_max is the decided point's orbit, moved back
            self._prev = (ContinuationPoint(u, p, J, 0, end[0], 0.0), ecand, slope)
            self._landed = True
            return ecand, self._problem.state(u)
        return cand, state

    def _record(self, cp, prob, known=None, later=False):
        """The Candidate of a converged ContinuationPoint and its modal state (candidate.record_candidate)."""
        return record_candidate(cp, prob, self._system, self.model, self.mode, self.settings.floquet, known, later)

    def _finish(self, status, message):
        self.status, self.message = status, message
        self._engine.close()

    def cancel(self, message=""):
        """End the iteration now (status 'cancelled'); the points so far are kept."""
        if self.status == "running":
            self._finish("cancelled", message or f"cancelled after {len(self.points)} points")

    def branch(self):
        """Branch of the points so far.  A running iteration left by ``break`` ends as 'stopped'."""
        if self.status == "running":
            self._finish("stopped", f"stopped by the caller after {len(self.points)} points")
        message = self.message
        if self.freq_tol:
            message += accuracy_note([p.freq_error for p in self.points], self._disc_errors, self.freq_tol, self._tol,
                                     getattr(getattr(self._problem, "basis", None), "harmonics", None),
                                     self._harmonics.max_harmonics if self._harmonics.freq_tol else None)
        if not self.settings.floquet and self.points:
            message += ("; stability was not computed (floquet off: the points are not known to be stable, and "
                        "stability changes and branch points are not detected; pass floquet=True, nnm-solve --floquet)")
        return Branch.from_points(self.model, self.mode, self.points, settings=self.settings,
                                  status=self.status, message=message,
                                  events=self.events if self.locate else None, tongues=self.tongues)
