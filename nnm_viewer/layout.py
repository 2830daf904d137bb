"""Layout of a tab: the controls (left), the 3D view (centre) and the tabbed panel (right).

``Layout`` creates and holds the viser handles of one tab (``h_*``); it has no view state and no
behaviour besides ``set`` (update a handle from Python without firing our callbacks) and
``connect`` (wire the handles to a session's callbacks).
"""
from __future__ import annotations

import threading

import numpy as np
import viser
from nnm_solver import INTEGRATORS
from nnm_solver.cli.defaults import TONGUE_CHOICES, solver_defaults
from nnm_solver.cli.modes import label_with_reference

from .help import HELP_MARKDOWN
from .model_info import elements_summary, model_markdown

#: widths (px) of the docked control panel (left) and information panel (right)
CONTROL_WIDTH = 340
PANEL_WIDTH = 500
#: modes listed in the Modes tab
MAX_MODES_TABLE = 200
#: handles that are buttons (wired on click)
BUTTONS = ("h_dismiss", "h_reset", "h_recompute", "h_start", "h_stop", "h_save", "h_csv_fep", "h_csv_orbit",
           "h_gif", "h_view", "h_show_linear", "h_compute_linear")
#: Compute tab: the methods offered -> (continue_nnm's method, condensed); the defaults of every field are the
#: solver's (nnm_solver.cli.defaults.solver_defaults), never copied here
METHODS = {"shooting": ("shooting", False), "harmonic balance": ("hb", False),
           "condensed harmonic balance": ("hb", True)}


def default_steps(integrator):
    """The solver's default time steps per period with ``integrator`` (each integrator's own, written once in
    nnm_solver/integrators/registry.py: e.g. gauss6 100, newmark 200)."""
    from nnm_solver.integrators.registry import get_integrator

    return int(get_integrator(str(integrator)).steps)


def steps_hint():
    """The Steps-per-period field's hint: every integrator's default, read from the solver."""
    each = ", ".join(f"{name} {default_steps(name)}" for name in INTEGRATORS)
    return (f"Time steps per period of the shooting. Choosing an integrator sets its default ({each}); more "
            "for high-order tongues")


def method_choice(method, condensed=False):
    """The Compute tab's method option of continue_nnm's ``method`` (and ``condensed``)."""
    return next(k for k, v in METHODS.items() if v == (("hb" if method == "harmonic_balance" else method),
                                                           bool(condensed)))
#: Modes tab: what "Compute its branch" says (viser 1.1 cannot switch a tab from the server)
SEE_COMPUTE_TAB = "the job's progress is in the **Compute** tab"
#: view presets of the camera (scene.preset_camera)
VIEW_PRESETS = ("Iso", "Top", "Side", "Front")

#: the caption under the panel FEP image, which cannot be clicked (viser 1.1 sends no clicks on panel images)
PANEL_FEP_CAPTION = ("*This picture is not clickable: pick points on the FEP board of the 3D view (click a "
                     "sphere) or with the Energy and Along branch sliders (left panel).*")


#: shown while the solver's kernels are being compiled (nnm_viewer/warmup.py)
SOLVER_PREPARING = ("**Preparing the solver** (compiling its kernels once after installing, then cached: the "
                    "stored orbits animate after ~15-25 s, the continuation ~10 s later) … The FEP can be browsed "
                    "meanwhile.")


#: JavaScript run once per page: arrow keys pressed on a focused slider (or another widget that uses
#: them: tabs, radio buttons, menus) stop at <body>, after the widget has handled them, so that
#: viser's keyboard camera controls (a listener on the document, skipped only for text fields) do not
#: also turn the camera.
KEY_GUARD_JS = ("if(!window.__nnmKeyGuard){window.__nnmKeyGuard=1;document.body.addEventListener('keydown',"
                "function(e){var t=e.target;if(e.key&&e.key.indexOf('Arrow')===0&&t&&t.closest&&t.closest("
                "'[role=slider],[role=tab],[role=radio],[role=option],[role=menuitem],[role=combobox]'))"
                "e.stopPropagation();});}")


def key_guard_html():
    """HTML that runs KEY_GUARD_JS when the page shows it (viser's add_html has no script hook: an
    image that fails to load runs its onerror handler)."""
    return f'<img alt="" src="data:," style="display:none" onerror="{KEY_GUARD_JS}">'


#: under the stiffness slider of a model whose elements are not all pure cubic springs
NO_SCALING_LAW = ("the scaling law holds for cubic springs only: choosing a factor recomputes the selected "
                  "branch with every spring force x factor (background job)")


def k3_text(factor, law=True):
    """Label under the k3 slider: the factor applied to every k3 of the file, and how it is applied
    (``law``: the exact scaling law of pure cubic springs; else a recompute)."""
    same = abs(factor - 1.0) < 1e-9
    if law:
        return "k3 x 1 (as in the file)" if same else f"k3 x {factor:.3g} (scaling law)"
    return ("forces x 1 (as in the file)" if same else f"forces x {factor:.3g} (recomputed)") + f"  \n{NO_SCALING_LAW}"


def mode_label(model, linear_freqs, k, reference=None):
    """'k: f Hz label' of linear mode k (1-based), with the reference's name of it ({mode: name}) if any."""
    labels = model.mode_labels or []
    lab = label_with_reference(labels[k - 1] if k - 1 < len(labels) else "", (reference or {}).get(k, ""))
    return f"{k}: {linear_freqs[k - 1]:.4g} Hz" + (f" {lab}" if lab else "")


def modes_markdown(model, linear_freqs, reference=None):
    """Markdown table of the linear modes (at most MAX_MODES_TABLE rows); the reference's names ({mode: name},
    e.g. the paper's) in the label column next to the model's."""
    labels = model.mode_labels or []
    rows = ["| mode | f (Hz) | label |", "|---|---|---|"]
    for k in range(min(len(linear_freqs), MAX_MODES_TABLE)):
        lab = label_with_reference(labels[k] if k < len(labels) else "", (reference or {}).get(k + 1, ""))
        rows.append(f"| {k + 1} | {linear_freqs[k]:.5g} | {lab} |")
    more = (f"\n\n({model.n - MAX_MODES_TABLE} more modes not listed)" if model.n > MAX_MODES_TABLE else "")
    if len(linear_freqs) < min(model.n, MAX_MODES_TABLE):            # a large model: only its lowest modes computed
        more = f"\n\n(the lowest {len(linear_freqs)} of the model's {model.n} modes)"
    return "**Linear modes**\n\n" + "\n".join(rows) + more


class Layout:
    """The GUI handles of one tab, built on ``gui`` (a tab's or the server's ``.gui``)."""

    def __init__(self, gui, model, linear_freqs, scaling_law=True, reference=None):
        self.gui = gui
        self._tl = threading.local()
        name = model.name or "model"
        gui.configure_theme(control_width="large", dark_mode=False, show_logo=False)
        self.h_title = gui.add_markdown(f"**nnm-view** · {name} · {model.n} DOFs · {elements_summary(model)}")
        self.h_solver = gui.add_markdown(SOLVER_PREPARING, visible=False)
        self.h_error = gui.add_markdown("", visible=False)
        self.h_dismiss = gui.add_button("Dismiss error", visible=False, color="red")
        with gui.add_folder("Selection"):
            self.h_branch = gui.add_dropdown("Branch", options=("(none)",), initial_value="(none)")
            self.h_energy = gui.add_slider("Energy log10(J)", min=-3.0, max=3.0, step=0.01, initial_value=0.0,
                                           hint="Moves the selection along the branch (nearest crossing)")
            self.h_along = gui.add_slider("Along branch (point)", min=1.0, max=2.0, step=0.01, initial_value=1.0,
                                          hint="The point's number (1 = the first computed point; fractional "
                                               "between two points): follows folds and tongues")
            self.h_sel = gui.add_markdown("no point selected")
            self.h_branch_info = gui.add_markdown("")
        with gui.add_folder("Animation"):
            self.h_play = gui.add_checkbox("Play", initial_value=True)
            self.h_phase = gui.add_slider("Phase (t/T)", min=0.0, max=1.0, step=0.01, initial_value=0.0,
                                          visible=False)
            self.h_auto = gui.add_checkbox("Auto amplification", initial_value=True)
            self.h_amp = gui.add_slider("Amplification log10", min=-1.0, max=6.0, step=0.05, initial_value=0.0,
                                        disabled=True)
            self.h_speed = gui.add_slider("Speed (cycles/s)", min=0.05, max=3.0, step=0.05, initial_value=0.5)
            self.h_peak = gui.add_markdown("")
            self.h_colorbar = gui.add_image(np.full((74, 320, 3), 255, np.uint8), label=None, format="png",
                                            visible=False)
            self.h_ghost = gui.add_checkbox("Show undeformed shape (ghost)", initial_value=False,
                                            hint="The structure at rest, translucent, behind the moving one")
            self.h_board = gui.add_checkbox("Show FEP in scene", initial_value=True)
            self.h_zoom = gui.add_checkbox("FEP: zoom on selected branch", initial_value=False,
                                           hint="On by default when the selected branch spans a small part "
                                                "of the frequency range")
            self.h_relative = gui.add_checkbox("FEP: relative frequency (f/f_lin - 1, %)", initial_value=False,
                                               hint="Frequency of each branch relative to its linear mode's")
            self.h_view = gui.add_button_group("View", options=VIEW_PRESETS,
                                               hint="Camera presets on the model: iso, from above (+z), "
                                                    "from the side (-y), from the front (-x)")
            self.h_reset = gui.add_button("Reset camera")
        with gui.add_folder("Nonlinear stiffness"):
            self.h_k3 = gui.add_slider("k3 factor log10" if scaling_law else "Spring force factor log10",
                                       min=-2.0, max=2.0, step=0.05, initial_value=0.0,
                                       marks=((-2, "0.01x"), (-1, "0.1x"), (0, "1x"), (1, "10x"), (2, "100x")),
                                       hint=("Every k3 x factor: the FEP and the orbit follow by the exact scaling "
                                             "law of cubic springs" if scaling_law else
                                             "The scaling law holds for cubic springs only: the chosen factor is "
                                             "computed (a background job for the selected branch's mode)"))
            self.h_k3_text = gui.add_markdown(k3_text(1.0, scaling_law))
            self.h_recompute = gui.add_button("Recompute at this stiffness", disabled=True,
                                              hint="Background job on the scaled model, to confirm the scaling law"
                                              if scaling_law else "Background job on the scaled model (the "
                                              "slider starts it too)")
        self.h_status = gui.add_markdown("")
        self.h_keys = gui.add_html(key_guard_html())

        panel = gui.add_panel()
        self.panel = panel
        with panel.add_tab("FEP", viser.Icon.CHART_DOTS):
            self.h_fep = gui.add_image(np.full((470, 480, 3), 255, np.uint8), label=None, format="png")
            # viser 1.1 sends the server no clicks on panel images: say so where the user clicks in vain
            self.h_fep_caption = gui.add_markdown(PANEL_FEP_CAPTION)
            self.h_readout = gui.add_markdown("no point picked")
            gui.add_markdown("Pick a point: click a sphere of the FEP in the 3D view (each branch in its "
                             "colour, pale spheres: unstable orbits, orange: off the backbone (in a tongue); the "
                             "yellow sphere is the picked orbit; the markers show the folds, bifurcations and where "
                             "a branch failed).")
        self.tab_point = panel.add_tab("Point", viser.Icon.INFO_CIRCLE)
        with self.tab_point:
            self.h_info = gui.add_markdown("no point selected")
            self.h_dofs = gui.add_text("DOFs (0-based)", initial_value="auto",
                                       hint="comma-separated DOF indices, or 'auto'")
            self.h_csv_fep = gui.add_button("Download branch FEP (CSV)", icon=viser.Icon.DOWNLOAD,
                                            hint="energy, frequency, period, stability and label of every "
                                                 "point of the selected branch, at the current k3 factor")
            self.h_csv_orbit = gui.add_button("Download orbit (CSV)", icon=viser.Icon.DOWNLOAD,
                                              hint="time (s) and the displacement of every DOF over one "
                                                   "period of the picked orbit")
            self.h_gif = gui.add_button("Download animation (GIF)", icon=viser.Icon.DOWNLOAD,
                                        hint="the deformed structure over one period, seen as in the 3D view, "
                                             "with its colour bar (a few seconds to draw)")
        # every mode (a large model's: the lowest ones computed, nnm_viewer.state.view_linear_modes)
        options = tuple(mode_label(model, linear_freqs, k, reference) for k in range(1, len(linear_freqs) + 1))
        self.mode_options = options
        D = solver_defaults()
        with panel.add_tab("Compute", viser.Icon.PLAYER_PLAY):
            self.h_mode = gui.add_dropdown("Mode", options=options, initial_value=options[0],
                                           hint="The linear mode whose NNM branch is computed (the selected "
                                                "branch's mode until you choose another)")
            self.h_emin = gui.add_number("Min energy (J), 0 = auto", initial_value=0.0, min=0.0, step=1e-6)
            self.h_emax = gui.add_number("Max energy (J)", initial_value=100.0, min=1e-12, step=1e-6)
            self.h_maxpts = gui.add_number("Max points", initial_value=int(D["max_points"]), min=2, max=5000, step=1,
                                           hint="The branch ends at Max points or Max energy, whichever comes first")
            self.h_method = gui.add_dropdown(
                "Method", options=tuple(METHODS), initial_value=method_choice(D["method"], D["condensed"]),
                hint="shooting (time integration, the seed paper's method), harmonic balance (Fourier series of "
                     "the orbit), or harmonic balance condensed onto the nonlinear elements (models of any size "
                     "whose nonlinearity is localized)")
            self.h_tongues = gui.add_dropdown(
                "Tongues", options=TONGUE_CHOICES, initial_value=str(D["tongues"]),
                hint="At an internal-resonance tongue: follow the branch through it (follow: tongues up to 3:1, "
                     "higher orders jumped; follow-all: every tongue), or skip it and compute the backbone (the "
                     "tongues jumped are listed with the branch; nnm-solve --tongue K continues one)")
            self.h_integrator = gui.add_dropdown(
                "Integrator", options=tuple(INTEGRATORS), initial_value=str(D["integrator"]),
                hint="Time integrator of the shooting: gauss6 or gauss4 (Gauss-Legendre, 6th / 4th order, 3 / 2 "
                     "stages per step), or newmark (2nd order, the seed paper's)")
            self.h_spp = gui.add_number(
                "Steps per period", initial_value=int(D["steps_per_period"]), min=8, max=20000, step=1,
                hint=steps_hint())
            self.h_harmonics = gui.add_number(
                "Harmonics", initial_value=int(D["harmonics"]), min=1, max=99, step=1, visible=False,
                hint="Harmonic balance: the highest harmonic of the Fourier series (more for strong higher "
                     "harmonics, e.g. inside a tongue)")
            self.h_start = gui.add_button("Start", color="green")
            self.h_stop = gui.add_button("Stop (keep points)", disabled=True)
            self.h_save = gui.add_button("Save selected branch to file", disabled=True)
            self.h_save_msg = gui.add_markdown("")          # what Save did, right under its button
            self.h_progress = gui.add_progress_bar(0.0, animated=False)
            self.h_job = gui.add_markdown("no job running")
        with panel.add_tab("Modes", viser.Icon.LIST):
            self.h_lin_mode = gui.add_dropdown("Linear mode", options=options, initial_value=options[0])
            self.h_show_linear = gui.add_button(
                "Show this linear mode", icon=viser.Icon.EYE,
                hint="Animates the linear mode shape x(t) = a φ cos(2π f t) on the structure (the Point tab "
                     "tells it); picking a FEP point shows that orbit again")
            self.h_compute_linear = gui.add_button(
                "Compute its branch", color="green", icon=viser.Icon.PLAYER_PLAY,
                hint="Selects this mode in the Compute tab and starts its branch, as Start does (with the "
                     "Compute tab's energies, points and integrator)")
            self.h_modes_job = gui.add_markdown("")
            self.h_model = gui.add_markdown(model_markdown(model))
            gui.add_markdown(modes_markdown(model, linear_freqs, reference))
        with panel.add_tab("Help", viser.Icon.HELP):
            self.h_help = gui.add_markdown(HELP_MARKDOWN)
        panel.dock_right()
        panel.set_width(PANEL_WIDTH)
        main = gui.main_panel
        main.dock_left()
        main.set_width(CONTROL_WIDTH)

    def connect(self, callbacks):
        """Wire the controls to ``callbacks`` (handle name -> callable(event)): buttons on click,
        the other controls on every update."""
        for name, fn in callbacks.items():
            handle = getattr(self, name)
            (handle.on_click if name in BUTTONS else handle.on_update)(fn)

    @property
    def programmatic(self):
        """True while ``set`` is changing a handle in this thread (our callbacks must ignore it)."""
        return getattr(self._tl, "programmatic", False)

    def set(self, handle, **props):
        """Set handle properties from Python without triggering our callbacks."""
        self._tl.programmatic = True
        try:
            for k, v in props.items():
                if k == "value":
                    if handle.value != v:
                        handle.value = v
                elif getattr(handle, k) != v:
                    setattr(handle, k, v)
        finally:
            self._tl.programmatic = False
