"""The backbone: the NNM family followed past its internal-resonance tongues, as one algorithm.

Read top to bottom: ``settings`` (Follow / Skip and every threshold, with the measurement behind it), ``skeleton``
(the family by condensed harmonic balance stepped in the followed mode's modal amplitude: ``amplitude_family``,
its one-harmonic guide ``family_guide``, one orbit ``amplitude_orbit``), ``content`` (an orbit's harmonic content),
``labels`` (a point on the family or in a tongue, against the skeleton, within the errors both estimate),
``jumps`` (the family beyond a tongue, found by the branch's own method from the skeleton's orbits) and ``policy``
(the decision at each point: keep, jump, finish).  The branch iterator (driver/iterator.py) acts on the decisions.

Layer: imports ``nnm_solver.results``, ``orbits``, ``continuation``, ``analysis`` and the layers below them.
"""
from .labels import FamilyLabels, Verdict
from .policy import Finish, FollowPolicy, Jump, Keep, SkipPolicy, policy_for
from .settings import Follow, LabelSettings, SkeletonSettings, Skip
from .skeleton import Skeleton, compute_skeleton, skeleton, skeleton_of

__all__ = ["Follow", "Skip", "SkeletonSettings", "LabelSettings", "Skeleton", "skeleton", "skeleton_of",
           "compute_skeleton", "FamilyLabels", "Verdict", "Keep", "Jump", "Finish", "FollowPolicy", "SkipPolicy",
           "policy_for"]
