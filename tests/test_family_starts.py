"""The families started on a branch (switch_branch, continue_tongue; nnm-solve --switch K / --tongue K): their
limits are checked as continue_nnm checks them, energy_max must lie above where the family starts, both before any
computation; and a branch scaled by Branch.scaled starts them from orbits of the scaled model."""
import subprocess
import sys

import numpy as np
import pytest

import nnm_solver as nnm
from conftest import two_dof_model


@pytest.fixture(scope="module")
def backbone():
    """NNM 1 of the 2-DOF benchmark to 1e4 J with its tongues skipped: a branch point located at 41 J, the 3:1
    tongue entered at 1.8 kJ and jumped."""
    b = nnm.continue_nnm(two_dof_model(), 1, 1e4, tongues="skip")
    assert b.status == "done" and b.tongues and b.tongues[0]["entry_x0"]
    return b


def _branch_point(b):
    return next(k for k, e in enumerate(b.events) if e["kind"] == "branch_point" and "x0" in e)


def _refusal(call):
    with pytest.raises(nnm.NNMInputError) as info:
        call()
    return str(info.value)


@pytest.mark.parametrize("bad", [dict(max_points=0), dict(max_points=-3), dict(max_points=2.5), dict(tol=-1.0),
                                 dict(tol=0.0), dict(tol=float("nan"))])
def test_families_refuse_the_limits_continue_nnm_refuses_with_its_words(backbone, bad):
    """max_points=-3 once gave a 1-point family 'stopped at max_points = -3'; tol=-1 ran and advised a larger tol."""
    expected = _refusal(lambda: nnm.continue_nnm(backbone.model, 1, 100.0, **bad))
    assert _refusal(lambda: nnm.switch_branch(backbone, _branch_point(backbone), 100.0, **bad)) == expected
    assert _refusal(lambda: nnm.continue_tongue(backbone, 0, **bad)) == expected


def test_families_refuse_an_energy_max_not_above_their_start(backbone):
    """energy_max caps the continuation whichever way in energy the family goes (it may head down from a branch
    point or dip below a tongue's entry): one at or below the start once gave a 1-point branch 'reached energy_max'."""
    k = _branch_point(backbone)
    E_bp, E_in = backbone.events[k]["energy"], backbone.tongues[0]["entry_energy"]
    for energy_max in (10.0, E_bp):
        msg = _refusal(lambda: nnm.switch_branch(backbone, k, energy_max))
        assert f"energy_max = {energy_max:g} J" in msg and f"{E_bp:.6g} J" in msg and "\n" not in msg
    for energy_max in (100.0, E_in):
        msg = _refusal(lambda: nnm.continue_tongue(backbone, 0, energy_max=energy_max))
        assert f"energy_max = {energy_max:g} J" in msg and f"{E_in:.6g} J" in msg and "\n" not in msg
    # one just above the start is a request: the family is computed
    assert len(nnm.switch_branch(backbone, k, 1.2 * E_bp, max_points=3)) >= 1


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "nnm_solver.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=600)


def test_cli_families_refuse_bad_limits_in_one_line_before_anything(backbone, tmp_path):
    path = tmp_path / "b.h5"
    nnm.save_model(path, backbone.model)
    nnm.save_branch(path, backbone)
    for args, words in ((("--switch", 1, "--energy-max", 10), "is not above the family's start"),
                        (("--switch", 1, "--energy-max", 100, "--tol", -1), "tol must be a positive number"),
                        (("--switch", 1, "--energy-max", 100, "--max-points", -3), "max_points must be a positive"),
                        (("--tongue", 1, "--energy-max", 100), "is not above the family's start"),
                        (("--tongue", 1, "--max-points", 0), "max_points must be a positive"),
                        (("--tongue", 1, "--steps-per-period", 3), "steps_per_period=3 is too small"),
                        (("--tongue", 1, "--integrator", "rk4"), "integrator must be one of")):
        r = _cli(path, *args)
        assert r.returncode == 2 and words in r.stderr and len(r.stderr.splitlines()) == 1, (args, r.stderr)
        assert r.stdout == "", (args, r.stdout)                 # nothing printed, nothing computed
    assert len(nnm.load_branches(path)) == 1                    # nothing saved


def test_a_scaled_branch_scales_its_events_tongues_and_record(backbone):
    """Branch.scaled (every k3 x 4): amplitudes / 2, energies / 4 for every stored orbit, not only the points'."""
    b, s = backbone, backbone.scaled(4.0)
    assert len(s.events) == len(b.events)
    for e, es in zip(b.events, s.events):
        assert es["energy"] == pytest.approx(e["energy"] / 4, rel=1e-14)
        assert es["frequency_hz"] == e["frequency_hz"] and es["period"] == e["period"]
        if "x0" in e:
            assert np.allclose(es["x0"], np.asarray(e["x0"]) / 2, rtol=1e-14, atol=0)
            assert np.allclose(es["v0"], np.asarray(e["v0"]) / 2, rtol=1e-14, atol=0)
            # the event's orbit is one of the scaled model, at the event's energy
            assert s.model.energy(np.asarray(es["x0"]), np.asarray(es["v0"])) == pytest.approx(es["energy"], rel=1e-8)
    for t, ts in zip(b.tongues, s.tongues):
        for key in ("entry_x0", "entry_v0", "inside_x0", "inside_v0"):
            assert np.allclose(ts[key], np.asarray(t[key]) / 2, rtol=1e-14, atol=0)
        assert ts["entry_energy"] == pytest.approx(t["entry_energy"] / 4, rel=1e-14)
        assert ts["exit_energy"] == pytest.approx(t["exit_energy"] / 4, rel=1e-14)
        assert ts["entry_period"] == t["entry_period"] and ts["inside_period"] == t["inside_period"]
    assert s.settings.energy_max == pytest.approx(b.settings.energy_max / 4) and s.settings.k3_factor == 4.0
    # the message is the computed branch's, with a note that the branch was scaled since
    assert s.message.startswith(b.message) and "scaled: every k3 x 4" in s.message
    assert b.scaled(1.0 / 4.0).settings.energy_max == pytest.approx(4 * b.settings.energy_max)


def test_families_from_a_scaled_branch_start_at_the_scaled_orbits(backbone):
    """switch_branch once failed 'no convergence at the start' on a scaled branch (its event's orbit was the
    unscaled one); continue_tongue started at the unscaled entry (2436 J for 1836 / 4 = 459 J)."""
    b, s = backbone, backbone.scaled(4.0)
    k = _branch_point(b)
    fam, ref = nnm.switch_branch(s, k, 100.0, max_points=5), nnm.switch_branch(b, k, 400.0, max_points=5)
    assert len(fam) == 5 and fam.status == "max_points", fam.message
    assert np.allclose(fam.energy, ref.energy / 4, rtol=1e-6)
    assert np.allclose(fam.frequency_hz, ref.frequency_hz, rtol=1e-8)
    tongue, tref = nnm.continue_tongue(s, 0, max_points=5), nnm.continue_tongue(b, 0, max_points=5)
    assert len(tongue) == 5 and tongue.status == "max_points", tongue.message
    assert tongue.energy[0] == pytest.approx(b.tongues[0]["entry_energy"] / 4, rel=1e-6)
    assert np.allclose(tongue.energy, tref.energy / 4, rtol=1e-6)
    assert np.allclose(tongue.frequency_hz, tref.frequency_hz, rtol=1e-8)
