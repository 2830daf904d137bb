"""Multipliers of Ritz orbits (issue 53, finding 11): harmonic balance on a sparse model above the Ritz threshold
(driver RITZ_MIN_DOF) with multipliers on gives a Branch (it used to raise 'cannot reshape array of size 560
into shape (10,4800)' in Branch.extend and lose the branch), whose ``floquet`` holds the 2r multipliers of the Ritz
system, says so (``multipliers_of``) and keeps it through a file; and those multipliers are the full model's (a
model where both bases run)."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.driver.problems import RITZ_MIN_DOF
from nnm_solver.model.ritz import ritz_system

from test_condensed_hb import sparse_cantilever

HB = dict(method="hb", harmonics=5, condensed=True, floquet=True)


def two_spring_beam(n_el):
    """The sparse cantilever with cubic springs at the tip and at mid-span (2 n_el DOFs)."""
    base = sparse_cantilever(n_el)
    return nnm.Model(base.M, base.K, [nnm.CubicSpring(dof=2 * n_el - 2, k3=1e7),
                                      nnm.CubicSpring(dof=n_el - 2, k3=1e7)], name=f"beam {n_el} el.")


def test_multipliers_on_a_sparse_model_above_the_ritz_threshold_give_a_branch(tmp_path):
    n_el = 1100
    model = two_spring_beam(n_el)
    assert model.n > RITZ_MIN_DOF
    b = nnm.continue_nnm(model, 1, 1e-4, max_points=8, **HB)
    assert isinstance(b, nnm.Branch) and len(b) == 8 and b.settings.modal_basis == "ritz"
    r = ritz_system(model, 1, 5).n
    assert b.multipliers_of == "ritz" and b.floquet.shape == (8, 2 * r) and 2 * r < 2 * model.n
    assert not np.isnan(b.floquet).any()
    # an undamped orbit's multipliers come in pairs (mu, 1/mu): low on the branch all on the unit circle
    assert np.allclose(np.abs(b.floquet), 1.0, atol=1e-6) and b.stable.all()
    assert (np.sum(np.abs(b.floquet - 1) < 1e-9, axis=1) >= 2).all()            # the trivial pair: 1, 1
    assert b.x0.shape == (8, model.n)                                          # orbits of the full model
    # through a file: the width and what the multipliers are of
    path = tmp_path / "beam.h5"
    nnm.save_model(path, model)
    nnm.save_branch(path, b)
    (back,) = nnm.load_branches(path)
    assert back.multipliers_of == "ritz" and back.floquet.shape == b.floquet.shape
    np.testing.assert_array_equal(back.floquet, b.floquet)
    # the rows of a running job (Branch.from_points, then extend) fit too
    grown = nnm.Branch.from_points(model, 1, [], settings=b.settings)
    grown.extend([b.point(i) for i in range(3)]).extend([b.point(i) for i in range(3, 8)])
    np.testing.assert_array_equal(grown.floquet, b.floquet)


def test_ritz_multipliers_are_the_full_models_where_both_bases_run():
    """A 40-element cantilever (80 DOFs): the Ritz system's multipliers of the modes below its cutoff equal the
    full model's (from Hill's method on all 80 coordinates) to 1e-6 beyond the turn the two orbits' period difference
    gives them, while the orbit has moved them by far more
    than that from their linear values; the stability flags agree."""
    model = sparse_cantilever(40)
    a = nnm.continue_nnm(model, 1, 5e-3, modal_basis="full", max_points=12, **HB)
    b = nnm.continue_nnm(model, 1, 5e-3, modal_basis="ritz", max_points=12, **HB)
    assert a.multipliers_of == "model" and a.floquet.shape[1] == 2 * model.n
    assert b.multipliers_of == "ritz" and b.floquet.shape[1] < a.floquet.shape[1]
    np.testing.assert_array_equal(a.stable, b.stable)
    system = ritz_system(model, 1, 5)
    j = len(b) - 1
    assert abs(b.frequency_hz[j] / a.frequency_hz[j] - 1) < 1e-9
    mu_full, mu_ritz = a.floquet[j], b.floquet[j]
    # every multiplier of the Ritz system's exact modes (two per mode below the cutoff) is one of the full model's
    # (to 1e-6 plus what the two orbits' period difference moves the multipliers by: exp(i w_k T) turns by w_k dT, the
    # highest exact mode's w_k T ~ 9,400: 1.4e-6 on one machine, whose two branches' frequencies differ by 1.5e-10)
    gap = np.sort([np.min(np.abs(mu_full - mu)) for mu in mu_ritz])
    w_top = np.sqrt(system.omega2[system.exact_modes - 1])
    drift = w_top * b.period[j] * abs(b.frequency_hz[j] / a.frequency_hz[j] - 1)
    assert gap[2 * system.exact_modes - 1] < 1e-6 + 2 * drift, gap[:2 * system.exact_modes]
    # ... which the orbit has moved from their linear values exp(+-i w_k T) by far more than that
    linear = np.exp(1j * np.sqrt(system.omega2) * b.period[j])
    linear = np.r_[linear, linear.conj()]
    assert max(np.min(np.abs(linear - mu)) for mu in mu_ritz) > 1e-4


def test_a_floquet_column_of_another_width_is_one_clear_error():
    model = sparse_cantilever(10)
    with pytest.raises(ValueError, match="columns per point"):
        nnm.Branch(model, 1, [1.0], [1.0], [1.0], np.zeros((1, model.n)), np.zeros((1, model.n)),
                   floquet=np.ones((1, 6)))
