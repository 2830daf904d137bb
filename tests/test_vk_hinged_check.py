"""Issue 55's independent check, as an outside checker runs it: NNM 1 of the hinged beam built by the contract
function, ``continue_nnm`` with its defaults, against the closed-form backbone (benchmarks/bench_vk_beam.py times it).

Measured (8 elements, steel, 212 points, 290-590 s at load 5-10): the points labelled backbone are within 4.7e-5 of
the closed form up to a = h.  At a = 1.15 h the branch meets a 5:1 internal resonance with mode 3 (mode 3's
frequency, raised by the membrane tension, is 5 times NNM 1's) and the default continuation, which follows tongues,
follows it to energy_max: those points are labelled 'tongue 5:1', truly (mode 3's frequency about the orbit,
the axial DOFs condensed, is 5.01 f there).
The closed form's sine family is invariant only in the continuum without axial inertia; in the FE model the axial
inertia and the discretisation couple it to mode 3, so the tongue is the model's own.  Up to two thicknesses the
backbone is what tongues='skip' gives (docs/geometric.md)."""
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
    on = np.array([str(x) == "backbone" for x in branch.labels])
    assert on[:50].all()
    assert np.abs(err[on & (a <= 1.0)]).max() < 2e-3                  # the target; measured 4.7e-5
    assert np.abs(err[on & (a <= 1.1)]).max() < 1e-4
    off = np.flatnonzero(~on)
    assert off.size and on[:off[0]].all() and not on[off[0]:].any()   # one departure, followed to energy_max
    i = off[0]
    assert 1.1 < a[i] < 1.2 and branch.labels[i] == "tongue 5:1"
    assert "inside a 5:1 tongue" in branch.message
    # the claim is true: mode 3 (the second symmetric mode), raised by the tension, at 5 times NNM 1's frequency
    # (measured 5.013 at the first tongue point)
    f = transverse_frequencies(model, branch.motion(i, 64)[1])
    assert abs(f[2] / (5 * branch.frequency_hz[i]) - 1) < 0.01
