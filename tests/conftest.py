import sys
from pathlib import Path

import numpy as np
import pytest

import nnm_solver as nnm

# the example packages (paris_aircraft) live in examples/, like scripts there see them
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
if str(EXAMPLES) not in sys.path:
    sys.path.insert(0, str(EXAMPLES))


def two_dof_model(k3=0.5):
    """The 2-DOF benchmark of Kerschen et al. (2009): M = I, K = [[2,-1],[-1,2]], cubic spring on DOF 0."""
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=k3)],
                     name="2-DOF benchmark")


def duffing_model(k3=1.0):
    """x'' + x + k3 x^3 = 0."""
    return nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=k3)], name="Duffing")


@pytest.fixture(scope="session")
def two_dof():
    return two_dof_model()


@pytest.fixture(scope="session")
def two_dof_nnm1(two_dof):
    """NNM1 of the 2-DOF benchmark through the 3:1 tongue (computed once per test session)."""
    return nnm.continue_nnm(two_dof, mode=1, energy_max=1e4)
