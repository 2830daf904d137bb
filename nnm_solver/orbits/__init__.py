r"""Periodic-orbit problems: the unknowns, residual and Jacobian of one NNM family, for the generic
pseudo-arclength engine (``continuation/engine.py``).

A problem provides (``continuation/engine.py`` lists the protocol)::

    residual(u), jacobian(u) -> (r, J), error(u, r), accept(u, J), max_step(u), check_step(u0, u1)

and, for the driver (``driver/api.py``), what a converged point is::

    pack / unpack / initial_state:  the orbit's initial state (modal q0, v0) and period from u
    multipliers(u)                 Floquet multipliers of the accepted point (2n,)

Implementations: ``shooting.ShootingProblem`` (Newmark shooting with the exact monodromy, the seed
paper's method) and ``harmonic_balance.HBProblem`` (Fourier series, AFT, on the basis of
``hb_basis.py``; multipliers by Hill's method, ``hill.py``).  Both work on a ``model.ModalSystem``.
``reference.py``: a converged orbit integrated by scipy's DOP853 (no compiled kernel; ``Branch.reference_motion``).

Layer: imports ``nnm_solver.stability``, ``continuation``, ``integrators``, ``model`` and the base modules.
"""
