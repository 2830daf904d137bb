"""Which truncation the skeleton that labels a branch and guides its skips has (driver/api.skeleton_harmonics): the
skeleton's own 9 harmonics for shooting and for harmonic balance whose accuracy target raises its harmonics, the
branch's own for harmonic balance at fixed harmonics (the same truncation on both sides of a landing)."""
import nnm_solver as nnm
from nnm_solver.driver.api import skeleton_harmonics


def test_the_skeleton_has_the_branch_truncation_or_its_own():
    assert skeleton_harmonics(nnm.Shooting(), 9, refined=True) == 9
    assert skeleton_harmonics(nnm.Shooting(), 9, refined=False) == 9
    assert skeleton_harmonics(nnm.HarmonicBalance(harmonics=3), 9, refined=True) == 9      # raised by its target
    assert skeleton_harmonics(nnm.HarmonicBalance(harmonics=13), 9, refined=True) == 13
    assert skeleton_harmonics(nnm.HarmonicBalance(harmonics=3), 9, refined=False) == 3     # fixed: the same
    assert skeleton_harmonics(nnm.HarmonicBalance(harmonics=13), 9, refined=False) == 13
