"""Issue 55's independent check, as an outside checker runs it: NNM 1 of the hinged beam built by the contract
function, ``continue_nnm`` with its defaults, against the closed-form backbone (benchmarks/bench_vk_beam.py times it).

Measured (8 elements, steel, 297 points, 449 s wall / 109 s CPU at load 5-8): every point is on the backbone, within
4.7e-5 of the closed form up to a = h and 6.8e-5 from 1.2 h to 2 h (2.7e-3 at 1.1-1.2 h, where the FE model's own
backbone bends into the tongue's entrance).  At a = 1.15 h the branch meets a 5:1 internal resonance with mode 3
(mode 3's frequency, raised by the membrane tension, is 5 times NNM 1's there: 1.0025 x 5 f at the entry orbit,
the axial DOFs condensed).  The default (``Follow()``, tongues up to 3:1 followed) jumps it and lists it in
branch.tongues; followed (``tongues="follow-all"``) the branch stays in that tongue past two thicknesses.
The closed form's sine family is invariant only in the continuum without axial inertia; in the FE model the axial
inertia and the discretisation couple it to mode 3, so the tongue is the model's own (docs/geometric.md)."""
import numpy as np
import pytest
import scipy.linalg as sl

import nnm_solver as nnm
import nnm_fem
from nnm_fem.vk_beam import hinged_backbone

L, H, B, E, RHO = 1.0, 0.01, 0.02, 210e9, 7800.0


def transverse_frequencies(model, x):
    """Frequencies (Hz) of the transverse motion about the orbit samples x (S, n): at each sample the tangent stiffness
    (nnm_fem.tangent_stiffness: the FE law, not the solver's) with the axial DOFs condensed statically (the axial modes
    lie above 2.5 kHz), averaged over the orbit (a Mathieu average), against the transverse mass.  (Averaging the
    tangent before condensing would keep the membrane coupling's square and put mode 3 16 % too high.)"""
    axial = [i for i, lab in enumerate(model.dof_labels) if lab.endswith(" ux")]
    w = [i for i in range(model.n) if i not in axial]
    Kc = np.zeros((len(w), len(w)))
    for xx in x:
        K = nnm_fem.tangent_stiffness(model, xx).toarray()
        Kc += K[np.ix_(w, w)] - K[np.ix_(w, axial)] @ np.linalg.solve(K[np.ix_(axial, axial)], K[np.ix_(axial, w)])
    M = model.M.toarray() if hasattr(model.M, "toarray") else np.asarray(model.M)
    return np.sqrt(sl.eigh(Kc / len(x), M[np.ix_(w, w)], eigvals_only=True)) / (2 * np.pi)


@pytest.mark.slow
def test_default_branch_of_the_hinged_beam_against_the_closed_form():
    N = 8
    model = nnm_fem.von_karman_beam(L, H, B, E, RHO, elements=N, ends="hinged")
    mid = model.dof_labels.index(f"node {N + 1} uz")
    energy_max = float(hinged_backbone(2 * H, L, H, E, RHO)[1]) * B
    branch = nnm.continue_nnm(model, 1, energy_max)
    assert branch.status == "done"
    a = np.abs(branch.x0[:, mid]) / H
    err = branch.frequency_hz / hinged_backbone(a * H, L, H, E, RHO)[0] - 1
    assert all(str(x) == "backbone" for x in branch.labels) and a.max() > 1.99
    assert np.abs(err[a <= 1.0]).max() < 2e-3                  # the targets; measured 4.7e-5
    assert np.abs(err).max() < 1e-2                            # measured 2.7e-3 (1.1-1.2 h), 6.8e-5 beyond
    assert np.abs(err[a <= 1.1]).max() < 1e-4
    assert np.abs(err[a >= 1.2]).max() < 1e-3
    # the 5:1 internal resonance with mode 3 jumped, listed; its claim is true: mode 3 (the second symmetric mode),
    # raised by the tension, at 5 times NNM 1's frequency at the entry orbit (measured 1.0025)
    (t,) = branch.tongues
    assert t.order == 5 and t.partner_mode == 3 and t.skipped and t.exit_energy > t.entry_energy
    i = t.entry_index
    assert 1.1 < a[i] < 1.2
    f = transverse_frequencies(model, branch.motion(i, 64)[1])
    assert abs(f[2] / (5 * branch.frequency_hz[i]) - 1) < 0.01
