"""The virtual ground vibration test (examples/virtual_gvt.py, issue 54): its Newmark simulation against solve_ivp,
its --fast run end to end with the numbers docs/testlab.md quotes, and the backbone plot with measured points."""
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "testlab.md"


@pytest.fixture(scope="module")
def gvt():
    import importlib.util

    spec = importlib.util.spec_from_file_location("example_virtual_gvt", ROOT / "examples" / "virtual_gvt.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod                      # its dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def paris():
    return nnm.load_model(ROOT / "assets" / "paris.h5")


@pytest.mark.slow
def test_the_newmark_simulation_agrees_with_solve_ivp(gvt, paris):
    """0.25 s of a strong swept sine (600 N per shaker) from rest: the displacements and accelerations at the four
    measured DOFs against DOP853 (rtol 1e-9) on the same modal equations; second order in the step."""
    zeta = 0.01
    system = modal_system(paris)
    w2, Phi = system.omega2, system.Phi
    c = 2 * zeta * np.sqrt(w2)
    pattern = gvt.shaker_pattern(paris)
    p = Phi.T @ pattern
    plan = gvt.TestPlan(force=600.0)
    dofs = [paris.dof_labels.index(lab) for _, lab in gvt.POINTS]

    def rhs(t, y):
        q, v = y[:paris.n], y[paris.n:]
        d = system.Bq @ q
        return np.concatenate([v, gvt.sweep_force(plan, t) * p - c * v - w2 * q - system.Bq.T @ system.elements.force(d)])

    T = 0.25
    ref = solve_ivp(rhs, (0, T), np.zeros(2 * paris.n), method="DOP853", rtol=1e-9, atol=1e-15, dense_output=True)
    errors = []
    for rate in (4096, 8192):
        t, x, a, _, _ = gvt.simulate(paris, zeta, pattern, lambda s: gvt.sweep_force(plan, s), 1.0 / rate,
                                     int(T * rate), dofs)
        y = np.array([rhs(ti, ref.sol(ti)) for ti in t])[:, paris.n:]
        a_ref = y @ Phi[dofs].T
        x_ref = ref.sol(t)[:paris.n].T @ Phi[dofs].T
        rel = np.abs((x[:, 1] - x[:, 0]))
        errors.append((np.max(np.abs(x - x_ref)) / np.max(np.abs(x_ref)),
                       np.max(np.abs(a - a_ref)) / np.max(np.abs(a_ref))))
    assert np.max(rel) > 0.1e-3                                # the springs soften (0.1 mm: 2 % of k)
    assert errors[0][0] < 6e-3 and errors[0][1] < 1.5e-2        # measured 0.0040 and 0.0094
    assert 3.0 < errors[0][0] / errors[1][0] < 5.0            # second order: halving the step divides by ~4


def fast_run(tmp_path):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "virtual_gvt.py"), "--fast", "--out-dir",
                          str(tmp_path), "--plot", str(tmp_path / "gvt.png")], capture_output=True, text=True,
                         env=env, timeout=900, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    return run.stdout


@pytest.mark.slow
def test_the_fast_run_identifies_the_softening_and_the_page_says_so(tmp_path):
    out = fast_run(tmp_path)
    assert (tmp_path / "gvt_accelerations.uff").is_file() and (tmp_path / "gvt.png").is_file()
    k3 = [float(v) for v in re.findall(r"k3 = (-?[\d.]+e\+\d+) N/m\^3 \(", out)]
    assert len(k3) == 2 and all(-1.3e13 < v < -0.9e13 for v in k3)           # the softening, within 30 %
    factor = float(re.search(r"k3 factor ([\d.]+) \(95 % ([\d.]+)\.\.([\d.]+)\)", out).group(1))
    low, high = (float(v) for v in re.search(r"k3 factor [\d.]+ \(95 % ([\d.]+)\.\.([\d.]+)\)", out).groups())
    assert low < 1.0 < high and abs(factor - 1.0) < 0.1                       # the decay's backbone: the model's k3
    page = " ".join(DOC.read_text().split())
    block = DOC.read_text().split("<!-- virtual_gvt --fast -->")[1].split("```")[1]
    wanted = [line for line in block.splitlines()[1:] if line.strip() and not line.startswith("$ ")]
    assert len(wanted) >= 9
    printed = [" ".join(line.split()) for line in out.splitlines()]
    for line in wanted:                  # every line the page shows is printed, but times, loads and paths
        if re.search(r"load average|wall time| in [\d.]+ s|\d+\.\d s\)|/tmp/|: [\d.]+ s$", line):
            continue
        assert " ".join(line.split()) in printed, f"docs/testlab.md shows {line!r}; the run printed:\n{out}"
    assert "virtual_gvt.py --fast" in page


def test_plot_backbone_with_measured_points(tmp_path):
    from nnm_solver.identification.backbone_plot import energy_of_amplitude, plot_backbone

    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    b = nnm.continue_nnm(model, 1, 2.0, method="hb")
    bb = nnm.amplitude_backbone(b, 0)
    pick = slice(2, None, 4)
    e = energy_of_amplitude(b, 0, bb.amplitude[pick])
    np.testing.assert_allclose(e, b.energy[pick], rtol=1e-9)             # the branch's own points map to themselves
    assert np.isnan(energy_of_amplitude(b, 0, [10 * bb.amplitude.max()])[0])
    path = tmp_path / "bb.csv"
    np.savetxt(path, np.column_stack([bb.frequency_hz[pick], 1e3 * bb.amplitude[pick]]), delimiter=",",
               header="frequency (Hz), amplitude (mm)")
    for axis in ("amplitude", "energy"):
        ax = plot_backbone(b, 0, nnm.read_measured(path), axis=axis, path=tmp_path / f"{axis}.png")
        xs, ys = ax.lines[1].get_data()
        if axis == "amplitude":
            np.testing.assert_allclose(ys, bb.amplitude[pick], rtol=1e-12)
        else:
            np.testing.assert_allclose(xs, b.energy[pick], rtol=1e-9)
        assert (tmp_path / f"{axis}.png").stat().st_size > 1000
    with pytest.raises(nnm.NNMInputError, match="axis 'phase' is not one of"):
        plot_backbone(b, 0, axis="phase")


def test_a_branch_named_with_a_slash_is_saved_and_read_back(tmp_path):
    """Branch names carry units ("k3 = -1e13 N/m^3"): the '/' must not open an HDF5 sub-group."""
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    b = nnm.continue_nnm(model, 1, 0.5, method="hb")
    b.name = "NNM 1 (k3 = 0.5 N/m^3)"
    nnm.save_branch(tmp_path / "a.h5", b)
    back = nnm.load_branches(tmp_path / "a.h5")
    assert [x.name for x in back] == ["NNM 1 (k3 = 0.5 N/m^3)"]
    np.testing.assert_array_equal(back[0].energy, b.energy)
