"""The methods' settings are one kind of object (issue 51): what a user asks for (``Shooting(...)``,
``HarmonicBalance(...)``) and what the branch records (``branch.settings``, every None resolved), so a branch's
settings passed back as ``method=`` compute it again the same way; a file round trip keeps them; the record's own
fields (energy_max, k3_factor, floquet) cannot be asked for as keywords."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.results.settings import settings_from_dict


def duffing_pair():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


@pytest.mark.parametrize("method", [nnm.Shooting(), nnm.HarmonicBalance(harmonics=5)])
def test_a_branch_records_the_request_resolved_and_computes_again_from_it(method, tmp_path):
    m = duffing_pair()
    b = nnm.continue_nnm(m, 1, 5.0, method)
    s = b.settings
    assert type(s) is type(method)
    if isinstance(s, nnm.Shooting):
        assert (s.steps_per_period, s.symmetric, s.reversible, s.freq_tol) == (100, True, True, 1e-4)
    else:
        assert (s.harmonics, s.basis, s.modal_basis) == (5, "odd", "full") and s.samples > 0
    assert s.energy_max == 5.0 and s.floquet is True
    again = nnm.continue_nnm(m, 1, 5.0, s)
    assert again.settings == s and np.array_equal(again.frequency_hz, b.frequency_hz)
    nnm.save_branch(tmp_path / "b.h5", b)
    assert nnm.load_branches(tmp_path / "b.h5")[-1].settings == s
    assert nnm.ShootingSettings is nnm.Shooting and nnm.HarmonicBalanceSettings is nnm.HarmonicBalance


def test_no_target_is_recorded_as_none_and_files_of_earlier_releases_read_as_computed():
    b = nnm.continue_nnm(duffing_pair(), 1, 5.0, nnm.Shooting(freq_tol=None))
    assert b.settings.freq_tol is None
    old = settings_from_dict({"method": "shooting", "steps_per_period": 200, "symmetric": True, "freq_tol": 0.0})
    assert (old.integrator, old.freq_tol, old.reversible) == ("newmark", None, True)
    assert settings_from_dict({"method": "shooting"}).symmetric is False             # first release: full period
    assert settings_from_dict({"method": "harmonic_balance", "harmonics": 9, "samples": None}).basis == "odd"


def test_the_record_fields_are_not_keywords():
    with pytest.raises(nnm.NNMInputError, match="k3_factor"):
        nnm.continue_nnm(duffing_pair(), 1, 5.0, k3_factor=2.0)
