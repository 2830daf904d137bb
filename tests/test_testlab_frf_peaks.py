"""FRFs at several force levels as fit data (issue 54): the peaks of lightly damped forced responses (harmonic
balance, nnm.forced_response) of a model with k3 x 1.7 give the factor back through fit_backbone."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.errors import NNMInputError
from nnm_solver.identification import frf_peaks

M = np.diag([1.0, 1.0])
K = np.array([[2.0, -1.0], [-1.0, 2.0]])
CUBIC = nnm.Model(M, K, [nnm.CubicSpring(dof=0, k3=0.5), nnm.CubicSpring(dof=1, other=0, k3=0.2)])
LEVELS = [0.002, 0.006, 0.016]


@pytest.fixture(scope="module")
def responses():
    truth = CUBIC.scaled(1.7)
    return [nnm.forced_response(truth, np.array([F, 0.0]), (0.14, 0.26), 0.002, harmonics=5) for F in LEVELS]


def test_peaks_of_stepped_sine_files_give_the_factor(responses, tmp_path):
    records = []
    for F, r in zip(LEVELS, responses):
        path = tmp_path / f"{F}.csv"
        np.savetxt(path, np.column_stack([r.frequency_hz, 1e3 * r.amplitude(1)]), delimiter=",", fmt="%.17g",
                   header="frequency (Hz), node 2 uz (mm)")
        records.append(nnm.read_measured(path))
    a, f = frf_peaks(records, "node 2 uz")
    exact = [r.peak(1) for r in responses]
    np.testing.assert_allclose(a, [p["amplitude"] for p in exact], rtol=2e-3)
    np.testing.assert_allclose(f, [p["frequency_hz"] for p in exact], rtol=1e-3)
    fit = nnm.fit_backbone(CUBIC, 1, 1, a, f)
    assert fit.k3_factor == pytest.approx(1.7, rel=5e-3)            # zeta 0.2 %: the peaks sit near the backbone


def test_receptances_need_their_levels(responses):
    recs = [nnm.Measurement(kind="frequency", axis=r.frequency_hz, data=(r.amplitude(1) / F)[:, None],
                            labels=("node 2 uz",), quantities=("receptance",), units=("m/N",), file_units=("m/N",),
                            nodes=(2,), directions=("uz",), references=("node 1 uz",), sampling=0.0,
                            source=f"{F} N") for F, r in zip(LEVELS, responses)]
    a, _ = frf_peaks(recs, 0, LEVELS)
    np.testing.assert_allclose(a, [r.peak(1)["amplitude"] for r in responses], rtol=2e-3)
    with pytest.raises(NNMInputError, match="give the force levels"):
        frf_peaks(recs, 0)
    with pytest.raises(NNMInputError, match="2 force levels for 3 records"):
        frf_peaks(recs, 0, LEVELS[:2])
