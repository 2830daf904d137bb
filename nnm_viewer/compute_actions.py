"""What a tab's buttons compute (a mixin of ``controls.Session``): branches started from the Compute tab
and the Modes tab, the stiffness slider's recompute jobs (models that are not pure cubic, where the scaling
law does not hold), Stop, saving a branch to the file, and showing a linear mode."""
from __future__ import annotations

import threading

import numpy as np

from .layout import METHODS, SEE_COMPUTE_TAB
from .examples import branch_output
from .fep import energy_at, energy_to_s
from .fep_text import sweep_key
from .state import JobBusy, branch_label
from .worker import JobRunner, one_line


#: non-cubic model: seconds the stiffness slider must rest before its factor is computed (debounce;
#: tests with sync=True start at once)
RECOMPUTE_DELAY = 0.5


class ComputeActions:
    """Start / Stop / Save, stiffness recomputes and linear modes of one Session (uses its state, lock,
    layout and shared branch list)."""

    def _on_recompute(self, _):
        target = self._recompute_target()
        if target is None:
            raise ValueError("select a branch first")
        self._start(target[0], target[1], self.factor)

    def _recompute_target(self):
        """(mode, energy_max, uid) of a recompute at the slider's factor: the selected branch's mode
        up to its largest energy (at the factor in use); for a branch the slider computed, or while
        its job is being replaced, those of the branch the slider started from.  None: no branch."""
        e = self.selected_entry()
        with self.lock:
            base, slider_uids = self._slider_base, set(self._slider_uids)
        if base is not None and (e is None or e.uid in slider_uids):
            return base
        job = self.shared.running_job()
        if not self.scaling_law and e is not None and job is not None and job.entry is e:
            return job.mode, job.energy_max, e.uid        # a branch being computed: its job's range
        if e is None or not len(e):
            return None
        return int(e.mode), float(np.max(e.series(self.view_factor(e)).energy)), e.uid

    # ---- the stiffness slider
    def _on_k3(self, _):
        """The stiffness slider: pure cubic springs, the FEP and the orbit follow by the exact scaling
        law; otherwise nothing is scaled and the chosen factor is computed (``_slider_recompute``).
        A linear mode shown (Modes tab) gives way to the selected point, the one the factor changes."""
        _, old = self.change_view(lambda v: dict(factor_log=float(self.layout.h_k3.value), linear_mode=None))
        linear = old.linear_mode
        if self.scaling_law:
            self.request("branches", "point", "controls")
            return
        self.request("controls", "progress", "sliders", *(("point", "fep") if linear is not None else ()))
        self._slider_recompute()

    def _entry_at(self, mode, factor, prefer=None):
        """A complete branch of ``mode`` computed at ``factor`` on the file's model (not a sweep
        variant's), ``prefer`` (a uid) first; or None."""
        found = [e for e in self.shared.snapshot()
                 if len(e) and e.mode == mode and abs(e.k3_factor / factor - 1.0) < 1e-9
                 and e.source in ("file", "computed", "saved") and sweep_key(e) is None]
        return next((e for e in found if e.uid == prefer), found[0] if found else None)

    def _slider_recompute(self):
        """Non-cubic model: a background job (the Recompute button's path) for the selected branch's
        mode at the slider's factor, debounced: it starts once the slider has rested RECOMPUTE_DELAY s
        (at once with sync=True) and no job runs; a job the slider started for another factor is
        stopped and its branch dropped, so that one job runs, for the final value.  A complete branch
        already computed at that factor is selected instead."""
        factor = self.factor
        target = self._recompute_target()
        if target is None:
            self.show_status("select a branch: the stiffness slider recomputes the selected branch")
            return
        mode, emax, origin = target
        existing = self._entry_at(mode, factor, prefer=origin)
        with self.lock:
            self._slider_base = (mode, emax, origin)
            runner = self.slider_runner
            busy = runner is not None and runner.running and not runner.cancelled
            same = busy and abs(runner.k3_factor / factor - 1.0) < 1e-9
            self._pending = None if (existing is not None or same) else (mode, emax, factor)
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
        if busy and not same:
            self._supersede(runner, origin)
        if existing is not None:
            self._select_existing(existing)
            return
        if same:
            return
        if self.sync:
            self._start_pending()
        else:
            timer = threading.Timer(RECOMPUTE_DELAY, self._start_pending)
            timer.daemon = True
            with self.lock:
                self._timer = timer
            timer.start()
        with self.lock:
            slider_runner = self.slider_runner
        job = self.shared.running_job()
        if job is not None and job is not slider_runner:
            self.show_status(f"recompute at x {factor:.3g} queued: it starts when the running job ends")

    def _supersede(self, runner, origin):
        """Stop a slider job whose factor is no longer wanted and drop its branch; the branch the
        slider started from is selected meanwhile."""
        runner.cancel()
        self.shared.remove(runner.entry)
        back = self.shared.index_of(origin) is not None
        self.change_view(lambda v: dict(sel_uid=origin, s=0.0) if back and v.sel_uid == runner.entry.uid else {})
        self.request("branches", "point", "progress")

    def _select_existing(self, e):
        """Select ``e`` (a branch already computed at the slider's factor) near the energy shown."""
        cur = self.selected_entry()
        s = 0.0
        if cur is not None and len(cur) and cur.uid != e.uid:
            ser = cur.series(self.view_factor(cur))
            energy = energy_at(ser.energy, float(np.clip(self.view.s, 0, len(ser) - 1)))
            s = energy_to_s(e.series(e.k3_factor).energy, energy, 0.0)
        elif cur is not None and cur.uid == e.uid:
            return
        self._select_uid(e.uid, s)

    def _start_pending(self):
        """Start the recompute the slider asked for, unless a job is running (then ``_on_shared``
        starts it when that job ends)."""
        with self.lock:                      # taken: a second call (timer and job end at once) finds None
            pending = self._pending
            if pending is None or self.shared.running_job() is not None:
                return
            self._pending = None
        mode, emax, factor = pending
        try:                                 # outside the tab's lock: starting notifies the other tabs
            runner = self._start(mode, emax, factor)
        except JobBusy:                      # another tab's job came first: wait for its end again
            with self.lock:
                if self._pending is None:
                    self._pending = pending
            return
        except Exception as exc:
            self.show_error(one_line(exc))
            return
        with self.lock:
            self.slider_runner = runner
            self._slider_uids.add(runner.entry.uid)

    def _on_start(self, _):
        mode = int(str(self.layout.h_mode.value).split(":")[0])
        emin, emax = float(self.layout.h_emin.value), float(self.layout.h_emax.value)
        return self._start(mode, emax, self.factor, energy_min=emin if emin > 0 else None)

    def _start(self, mode, emax, factor, energy_min=None):
        """Start a job (one at a time for all tabs: the start is atomic, worker.JobRunner.start raises
        state.JobBusy if another tab's job runs) and select its branch."""
        opts = self.job_options()
        if energy_min is not None:
            opts["energy_min"] = float(energy_min)
        runner = JobRunner(self.shared, mode, emax, k3_factor=factor, start=self.start_job, **opts)
        runner.start()
        self.last_runner = runner
        self.layout.set(self.layout.h_save_msg, content="")     # a new job: the last save's message is old
        # the new branch is selected: its points replace the old animation
        self.set_view(sel_uid=runner.entry.uid, s=0.0, current_point=None, current_anim=None, current_uid=None,
                      current_of=None, linear_mode=None)
        self.request("branches", "point", "progress")
        return runner

    def job_options(self):
        """continue_nnm's keywords from the Compute tab: max points, tongues, the method and its options
        (shooting: integrator and steps per period; harmonic balance: harmonics, condensed)."""
        ui = self.layout
        method, condensed = METHODS[str(ui.h_method.value)]
        opts = {"max_points": int(ui.h_maxpts.value), "tongues": str(ui.h_tongues.value)}
        if method == "shooting":
            spp = int(round(float(ui.h_spp.value)))
            if spp < 8:
                raise ValueError(f"steps per period must be at least 8, got {spp}")
            opts.update(integrator=str(ui.h_integrator.value), steps_per_period=spp)
        else:
            opts.update(method=method, harmonics=int(round(float(ui.h_harmonics.value))), condensed=condensed)
        return opts

    # ---- the Modes tab
    def _linear_mode_choice(self):
        """Mode k (1-based) chosen in the Modes tab's dropdown."""
        return int(str(self.layout.h_lin_mode.value).split(":")[0])

    def show_linear_mode(self, k):
        """Animate linear mode ``k`` (1-based) instead of the selected point (``info.linear_mode_point``);
        the selection is kept: a pick, the sliders, a branch chosen or a new job show a point again."""
        k = int(k)
        freqs = self.shared.linear_freqs
        if not 1 <= k <= len(freqs):
            raise ValueError(f"linear mode {k} does not exist (valid: 1..{len(freqs)})")
        if not freqs[k - 1] > 1e-9 * max(float(np.max(np.abs(freqs))), 1e-300):
            raise ValueError(f"linear mode {k} is a rigid-body mode (0 Hz): nothing to animate")
        self.set_view(linear_mode=k)
        self.request("point", "readout")

    def _on_show_linear(self, _):
        self.show_linear_mode(self._linear_mode_choice())

    def _on_compute_linear(self, _):
        """'Compute its branch': that mode in the Compute tab's Mode list, then Start (as its button)."""
        k = self._linear_mode_choice()
        self.layout.set(self.layout.h_mode, value=self.layout.mode_options[k - 1])
        runner = self._on_start(None)
        self.show_status(f"started {runner.name}: {SEE_COMPUTE_TAB}")
        return runner

    def _on_stop(self, _):
        job = self.shared.running_job()
        if job is not None:
            job.cancel()

    def _on_save(self, _):
        """Save the selected branch; what happened (the file written, or why not) is said under the Save button,
        where the user looks (finding 4), and in the status line."""
        try:
            msg = self._save_selected()
        except Exception as exc:
            self.layout.set(self.layout.h_save_msg, content=f"**Not saved:** {one_line(exc)}")
            raise
        self.layout.set(self.layout.h_save_msg, content=f"**Saved:** {msg}")
        self.show_status(msg)

    def _save_selected(self):
        e = self.selected_entry()
        if e is None:
            raise ValueError("select a branch to save")
        if e.source == "running":
            raise ValueError("the branch is still being computed: stop it or wait, then save")
        if e.saved:
            raise ValueError("this branch is already in the file")
        name = branch_label(e.branch, e.k3_factor, source="file", model=self.model,
                            reference=self.shared.reference_names)
        if self.shared.path is not None:         # said at once: writing a large model file takes seconds
            self.layout.set(self.layout.h_save_msg, content=f"**Saving** {name}, {len(e)} points, to "
                                                            f"{branch_output(self.shared.path)[0]} \u2026")
        target, reason = self.shared.save(e)
        return (f"saved {name}, {len(e)} points, to {target}"
                + (f" ({reason}: it is left unchanged; open the new file with nnm-view {target})" if reason else ""))
