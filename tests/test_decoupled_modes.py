"""The multipliers' eigenproblem of the modes that see the nonlinear elements only (floquet.coupled_modes,
reversible_blocks): the same multipliers and flags as the full one, on a random block structure and on a chain
whose symmetric modes do not stretch its spring (exactly decoupled)."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.orbits import shooting_stability as ss
from nnm_solver.stability.floquet import (coupled_modes, deflate, is_stable, reversible_blocks,
                                          reversible_spectrum)


def _matched(a, b):
    """Largest distance between the eigenvalue lists a and b matched one to one (sorted pairing by nearest)."""
    from scipy.optimize import linear_sum_assignment
    D = np.abs(np.asarray(a)[:, None] - np.asarray(b)[None, :])
    r, c = linear_sum_assignment(D)
    return float(D[r, c].max())


def test_coupled_modes_by_the_element_matrix():
    Bq = np.array([[1.0, 0.0, 1e-17, 0.3], [0.0, 0.0, 0.0, 0.2]])
    assert coupled_modes(Bq).tolist() == [0, 3]
    assert coupled_modes(np.ones((2, 3))) is None
    assert coupled_modes(np.zeros((0, 3))) is None


def test_reversible_blocks_give_the_full_spectrum():
    """A11 with 5 of 12 modes decoupled (zero rows and columns off the diagonal), deflated by a family direction in
    the coupled modes: the coupled block's eigenvalues and the 5 diagonal entries are the full matrix's (to
    round-off), and the eigenproblem is 7 - 1 wide."""
    rng = np.random.default_rng(3)
    n, keep = 12, np.array([0, 2, 3, 6, 8, 9, 11])
    A = np.diag(np.cos(rng.uniform(0, 3, n)))
    A[np.ix_(keep, keep)] += 0.05 * rng.standard_normal((len(keep), len(keep)))
    family = np.zeros(n)
    family[keep] = rng.standard_normal(len(keep))
    C, deflated, fixed = reversible_blocks(A, family, keep)
    assert deflated and C.shape == (len(keep) - 1, len(keep) - 1) and len(fixed) == n - len(keep)
    full = np.linalg.eigvals(deflate(A, family[:, None]))
    assert _matched(np.concatenate([np.linalg.eigvals(C), fixed]), full) < 1e-12
    mu_full, c_full = reversible_spectrum(A, family)
    mu_red, c_red = reversible_spectrum(A, family, keep)
    assert _matched(mu_full, mu_red) < 1e-12 and is_stable(mu_full) == is_stable(mu_red)


def _chain_branch(reduced, monkeypatch):
    """NNM 4 of a fixed-fixed chain of 6 unit masses and springs with a cubic spring between its two end masses
    (d = x1 - x6): the symmetric modes (1, 3, 5) do not stretch it, so they are exactly decoupled."""
    with monkeypatch.context() as m:
        if not reduced:
            m.setattr(ss.ShootingStability, "coupled_modes", property(lambda self: None))
        n = 6
        K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
        model = nnm.Model(M=np.eye(n), K=K, springs=[nnm.CubicSpring(dof=0, other=n - 1, k3=5.0)])
        return nnm.continue_nnm(model, 4, 1e3, max_points=80)


def test_a_model_with_modes_that_do_not_see_the_spring(monkeypatch):
    """The chain's NNM 4 with the eigenproblem of its 3 coupled modes equals the one with all 6: the same points,
    flags at every point, multipliers to 1e-9 and events (two tori and a branch point)."""
    from nnm_solver.model.modal import ModalSystem
    n = 6
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    model = nnm.Model(M=np.eye(n), K=K, springs=[nnm.CubicSpring(dof=0, other=n - 1, k3=5.0)])
    assert coupled_modes(ModalSystem(model).Bq).tolist() == [1, 3, 5]
    reduced, full = _chain_branch(True, monkeypatch), _chain_branch(False, monkeypatch)
    assert len(reduced.energy) == len(full.energy) > 10
    assert np.array_equal(np.asarray(reduced.stable), np.asarray(full.stable))
    assert all(len(a) == len(b) == 2 * n for a, b in zip(reduced.floquet, full.floquet))
    assert max(_matched(a, b) for a, b in zip(reduced.floquet, full.floquet)) < 1e-9
    assert [e["kind"] for e in full.events] == ["torus", "torus", "branch_point"]
    assert [(e["kind"], e.get("stability_change")) for e in reduced.events] == \
        [(e["kind"], e.get("stability_change")) for e in full.events]
    assert np.allclose([e["energy"] for e in reduced.events], [e["energy"] for e in full.events], rtol=1e-9)
