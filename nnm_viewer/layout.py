"""Layout of a tab: the controls (left), the 3D view (centre) and the tabbed panel (right).

``SessionLayout._build_gui`` creates the viser handles of a ``Session`` and wires them to its
callbacks (defined in controls.py); nothing here holds state.
"""
from __future__ import annotations

import numpy as np
import viser

#: widths (px) of the docked control panel (left) and information panel (right)
CONTROL_WIDTH = 340
PANEL_WIDTH = 500
#: modes offered in the Compute tab
MAX_MODES_LISTED = 60
#: modes listed in the Modes tab
MAX_MODES_TABLE = 200


class SessionLayout:
    """Mixin of Session: builds its GUI."""

    def _build_gui(self):
        gui = self.gui
        m = self.model
        name = m.name or "model"
        gui.configure_theme(control_width="large", dark_mode=False, show_logo=False)
        self.h_title = gui.add_markdown(f"**nnm-view** · {name} · {m.n} DOFs · {len(m.springs)} cubic springs")
        self.h_error = gui.add_markdown("", visible=False)
        self.h_dismiss = gui.add_button("Dismiss error", visible=False, color="red")
        self.h_dismiss.on_click(self._cb(self._dismiss_error))
        with gui.add_folder("Selection"):
            self.h_branch = gui.add_dropdown("Branch", options=("(none)",), initial_value="(none)")
            self.h_energy = gui.add_slider("Energy log10(J)", min=-3.0, max=3.0, step=0.01, initial_value=0.0,
                                           hint="Moves the selection along the branch (nearest crossing)")
            self.h_along = gui.add_slider("Along branch", min=0.0, max=1.0, step=0.01, initial_value=0.0,
                                          hint="Fractional point index: follows folds and tongues")
            self.h_sel = gui.add_markdown("no point selected")
        with gui.add_folder("Animation"):
            self.h_play = gui.add_checkbox("Play", initial_value=True)
            self.h_phase = gui.add_slider("Phase (t/T)", min=0.0, max=1.0, step=0.01, initial_value=0.0,
                                          visible=False)
            self.h_auto = gui.add_checkbox("Auto amplification", initial_value=True)
            self.h_amp = gui.add_slider("Amplification log10", min=-1.0, max=6.0, step=0.05, initial_value=0.0,
                                        disabled=True)
            self.h_speed = gui.add_slider("Speed (cycles/s)", min=0.05, max=3.0, step=0.05, initial_value=0.5)
            self.h_peak = gui.add_markdown("")
            self.h_board = gui.add_checkbox("Show FEP in scene", initial_value=True)
            self.h_zoom = gui.add_checkbox("FEP: zoom on selected branch", initial_value=False)
            self.h_reset = gui.add_button("Reset camera")
        with gui.add_folder("Nonlinear stiffness"):
            self.h_k3 = gui.add_slider("k3 factor log10", min=-2.0, max=2.0, step=0.05, initial_value=0.0,
                                       marks=((-2, "0.01x"), (-1, "0.1x"), (0, "1x"), (1, "10x"), (2, "100x")))
            self.h_k3_text = gui.add_markdown("k3 x 1 (as in the file)")
            self.h_recompute = gui.add_button("Recompute at this stiffness", disabled=True,
                                              hint="Background job on the scaled model, to confirm the scaling law")
        self.h_status = gui.add_markdown("")

        panel = gui.add_panel()
        self.panel = panel
        with panel.add_tab("FEP", viser.Icon.CHART_DOTS):
            self.h_fep = gui.add_image(np.full((350, 480, 3), 255, np.uint8), label=None, format="png")
            gui.add_markdown("Pick a point: click a sphere of the FEP in the 3D view "
                             "(blue: stable, red: unstable; the yellow sphere is the picked orbit).")
        self.tab_point = panel.add_tab("Point", viser.Icon.INFO_CIRCLE)
        with self.tab_point:
            self.h_info = gui.add_markdown("no point selected")
            self.h_dofs = gui.add_text("DOFs (0-based)", initial_value="auto",
                                       hint="comma-separated DOF indices, or 'auto'")
        with panel.add_tab("Compute", viser.Icon.PLAYER_PLAY):
            nmodes = min(m.n, MAX_MODES_LISTED)
            self._mode_options = tuple(self._mode_label(k) for k in range(1, nmodes + 1))
            self.h_mode = gui.add_dropdown("Mode", options=self._mode_options, initial_value=self._mode_options[0])
            self.h_emin = gui.add_number("Min energy (J), 0 = auto", initial_value=0.0, min=0.0, step=1e-6)
            self.h_emax = gui.add_number("Max energy (J)", initial_value=100.0, min=1e-12, step=1e-6)
            self.h_maxpts = gui.add_number("Max points", initial_value=80, min=2, max=5000, step=1)
            self.h_start = gui.add_button("Start", color="green")
            self.h_stop = gui.add_button("Stop (keep points)", disabled=True)
            self.h_save = gui.add_button("Save selected branch to file", disabled=True)
            self.h_progress = gui.add_progress_bar(0.0, animated=False)
            self.h_job = gui.add_markdown("no job running")
        with panel.add_tab("Modes", viser.Icon.LIST):
            gui.add_markdown(self._modes_markdown())
        panel.dock_right()
        panel.set_width(PANEL_WIDTH)
        main = gui.main_panel
        main.dock_left()
        main.set_width(CONTROL_WIDTH)

        self.h_branch.on_update(self._cb(self._on_branch))
        self.h_energy.on_update(self._cb(self._on_energy))
        self.h_along.on_update(self._cb(self._on_along))
        self.h_play.on_update(self._cb(self._on_play))
        self.h_phase.on_update(self._cb(self._on_phase))
        self.h_auto.on_update(self._cb(self._on_auto))
        self.h_amp.on_update(self._cb(self._on_amp))
        self.h_speed.on_update(self._cb(self._on_speed))
        self.h_board.on_update(self._cb(self._on_board))
        self.h_zoom.on_update(self._cb(self._on_zoom))
        self.h_reset.on_click(self._cb(self._on_reset_camera))
        self.h_k3.on_update(self._cb(self._on_k3))
        self.h_recompute.on_click(self._cb(self._on_recompute))
        self.h_dofs.on_update(self._cb(self._on_dofs))
        self.h_start.on_click(self._cb(self._on_start))
        self.h_stop.on_click(self._cb(self._on_stop))
        self.h_save.on_click(self._cb(self._on_save))

    def _mode_label(self, k):
        labels = self.model.mode_labels or []
        lab = f" {labels[k - 1]}" if k - 1 < len(labels) else ""
        return f"{k}: {self.shared.linear_freqs[k - 1]:.4g} Hz{lab}"

    def _modes_markdown(self):
        labels = self.model.mode_labels or []
        rows = ["| mode | f (Hz) | label |", "|---|---|---|"]
        for k in range(min(self.model.n, MAX_MODES_TABLE)):
            rows.append(f"| {k + 1} | {self.shared.linear_freqs[k]:.5g} | {labels[k] if k < len(labels) else ''} |")
        more = (f"\n\n({self.model.n - MAX_MODES_TABLE} more modes not listed)"
                if self.model.n > MAX_MODES_TABLE else "")
        return "**Linear modes**\n\n" + "\n".join(rows) + more

    # ================================================================== callbacks
