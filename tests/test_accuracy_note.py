"""What a branch's message says of its points above the accuracy target (driver/refinement.accuracy_note): the
points the finer step did not fix, those of a harmonic balance whose harmonics were not raised (its truncation and
cap said), and those held back by the corrector's tolerance."""
import math

from nnm_solver.driver.refinement import accuracy_note

NAN = math.nan


def test_the_note_says_why_each_point_stays_above_the_target():
    assert accuracy_note([1e-5, 5e-5], [NAN, NAN], 1e-4, 1e-6) == ""
    shooting = accuracy_note([1e-5, 2e-4, 3e-4], [NAN, 3e-4, NAN], 1e-4, 1e-6)
    assert "1 points exceed freq_tol = 0.0001 (the finer step did not converge" in shooting
    assert "1 points exceed freq_tol = 0.0001 because of the corrector's tolerance: lower tol (now 1e-06)" in shooting
    hb = accuracy_note([1e-5, 2e-4, 3e-4], [NAN, NAN, NAN], 1e-4, 1e-8, harmonics=11, max_harmonics=31)
    assert "2 points exceed freq_tol = 0.0001 (harmonic balance, 11 harmonics at the end, at most 31" in hb
    assert "corrector" not in hb
