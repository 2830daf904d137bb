r"""Hill's multipliers by the secular route (hill.py explains the routes): the Floquet exponents as the zeros of the
small determinant det(I + C~ W(nu)) of the springs' coordinates, by batched Newton warm-started at the previous
orbit's, each checked; a class next to the trivial pair's copies (inside an internal-resonance tongue) by its copies
(hill_copies.py); what neither can vouch for goes to the structured route (hill_structured.py)."""
from __future__ import annotations

import numpy as np

from .hill_copies import hard_copies
from .hill_shared import _classes, _exp_transform, _setup, set_warm_start, velocity_overlaps, warm_start
from .hill_structured import _HillOperator, _iterate, warm_from_zeros
from .settings import ORBITS


def _secular(problem, A, w, bp, C):
    """Multipliers (2n,) by the secular route, or None when it cannot vouch for them (then: structured, dense).

    Eliminating the modal blocks exactly (module docstring), lambda = nu omega is a Hill eigenvalue where the
    r x r matrix  M(nu) = I + C~ W(nu),  W(nu) = blockdiag_k Bq diag(1 / ((nu + i k)^2 + omega_j^2)) Bq^T  (units of
    omega) is singular (r = N_b n_s: 11 for one spring at H = 5, whatever n).  One exponent per class (the touched
    modes but the continued one's) by Newton on the characteristic polynomial p(nu) = det M(nu) prod q0(nu):
    p'/p = tr(M^-1 C~ W') + sum 2 (nu + i k) / q0, batched over the classes, warm-started at the previous call's
    exponents; each converged exponent is moved to its central copy (the dense route's choice: the eigenvector's
    mean harmonic below 1/2) and refined there.  Each class gives its pair nu, -nu (the matrix is Hamiltonian).
    Checked before use: the Hill residual of the eigenvector rebuilt from the null vector of M, the mean harmonic,
    no eigenvector on the orbit's velocity (or its copies), distinct pairs (a duplicate, or a collision in
    progress), no exponent near the trivial pair's copies i k (internal resonances, branch points).  The converged
    classes near those copies are found by their copies (hill_copies.py); what that declines, and anything else,
    goes to the structured route on those classes (then None: the whole structured route, then the dense one)."""
    n, H = problem.n, bp.harmonics
    nb = 2 * H + 1
    Tinv, omega2, touched, Ah, vel = _setup(problem, A, w, bp)
    Cexp = np.einsum("ab,sbc,cd->sad", Tinv, C, _exp_transform(H)) / w ** 2
    Bq = problem.sys.Bq
    tm, beta2, Vbar, classes, nu_kept = _classes(omega2, Bq, Cexp, touched, Ah, H)
    S = len(classes)
    if S:
        ns = Bq.shape[0]
        r = nb * ns
        kk = np.arange(-H, H + 1, dtype=float)
        B = Bq[:, tm]                                                        # (n_s, n_t)
        w2 = omega2[tm]
        Ct = np.zeros((r, r), dtype=complex)                                 # C~: rows (k, s), columns (l, s)
        for j in range(ns):
            Ct[j::ns, j::ns] = Cexp[j]
        key = (n, nb, S)
        warm = warm_start(problem, "secular")
        if warm is not None and warm[0] == key:
            nu = warm[1] / w
        else:
            nu = 1j * np.sqrt(np.maximum(beta2[classes], 0.0))
        nu = np.asarray(nu, dtype=complex) + 0j
        eye = np.eye(r)

        BB = (B[:, None, :] * B[None, :, :]).reshape(ns * ns, -1).T            # (n_t, n_s^2): Bq_sj Bq_s'j
        Ct3, Ct3T = Ct.reshape(r, nb, ns), Ct.reshape(nb, ns, r)

        def times_w(Wf):
            """C~ blockdiag_l W[l] (S, r, r) for the blocks Wf (S, N_b n_s^2) in (l, s, s') order, without forming
            the block diagonal: one column scaling for a single element."""
            if ns == 1:
                return Ct[None] * Wf[:, None, :]
            return np.einsum("ilt,kltu->kilu", Ct3, Wf.reshape(-1, nb, ns, ns)).reshape(-1, r, r)

        def w_times(Wf):
            """blockdiag_l W[l] C~ (S, r, r)."""
            if ns == 1:
                return Wf[:, :, None] * Ct[None]
            return np.einsum("kltu,lui->klti", Wf.reshape(-1, nb, ns, ns), Ct3T).reshape(-1, r, r)

        def parts(nu):
            sk = nu[:, None] + 1j * kk[None, :]                              # (S, N_b)
            q0 = sk[:, :, None] ** 2 + w2[None, None, :]                     # (S, N_b, n_t)
            inv = 1.0 / q0
            dinv = -2.0 * sk[:, :, None] * inv * inv
            S_ = len(nu)
            # W[l] = Bq diag(inv_l) Bq^T, as one product with the real BB (real and imaginary parts apart)
            W = (inv.real @ BB + 1j * (inv.imag @ BB)).reshape(S_, nb * ns * ns)
            dW = (dinv.real @ BB + 1j * (dinv.imag @ BB)).reshape(S_, nb * ns * ns)
            return sk, inv, W, dW

        def logderiv(nu):
            """p'/p at the points nu (S,)."""
            sk, inv, W, dW = parts(nu)
            G = np.linalg.solve(eye[None] + times_w(W), times_w(dW))
            return np.trace(G, axis1=1, axis2=2) + (2.0 * sk[:, :, None] * inv).sum(axis=(1, 2))

        def eigvecs(nu):
            """(c (S, N_b, n), mean harmonic (S,)): the eigenvectors at the exponents nu, c_kj = -(1 / q0_kj)
            sum_s Bq_sj (C~ z)_ks with z the null vector of I + W C~ (one step of inverse iteration)."""
            S_ = len(nu)
            _, inv, W, _ = parts(nu)
            Mz = eye[None] + w_times(W)
            z = np.linalg.solve(Mz, np.ones((S_, r, 1)) / np.sqrt(r))[..., 0]
            lost = ~np.all(np.isfinite(z), axis=1)
            if np.any(lost):        # M singular to round-off: its null vector; NaN where M is not finite (nu on a
                # pole 1 / q0 of an uncoupled mode: the class is then refused by its residual, not by the SVD failing)
                ok = lost & np.all(np.isfinite(Mz), axis=(1, 2))
                z[lost] = np.nan
                if np.any(ok):
                    z[ok] = np.linalg.svd(Mz[ok])[2][:, -1, :].conj()                  # (S, r)
            z /= np.linalg.norm(z, axis=1, keepdims=True)
            f = (z @ Ct.T).reshape(S_, nb, ns)                                     # (C~ z)_(k, s)
            c = np.zeros((S_, nb, n), dtype=complex)
            c[:, :, tm] = -inv * (f @ B)
            p = (np.abs(c) ** 2).sum(axis=2)
            return c, (kk[None] * p).sum(axis=1) / np.maximum(p.sum(axis=1), 1e-300)

        bad = np.zeros(S, dtype=bool)             # classes the secular route cannot vouch for: the structured route's
        with np.errstate(all="ignore"):
            recentred = np.zeros(S, dtype=int)
            fresh = np.ones(S, dtype=bool)          # the classes whose exponent is not converged where it is
            for _ in range(4):                      # Newton, then move to the central copies and refine
                conv = bad | ~fresh
                for it in range(ORBITS.secular_iter):
                    act = np.flatnonzero(~conv)
                    if not len(act):
                        break
                    step = -1.0 / logderiv(nu[act])
                    broken = ~np.isfinite(step)
                    bad[act[broken]] = conv[act[broken]] = True
                    step[broken] = 0.0
                    nu[act] += step
                    conv[act] |= np.abs(step) <= ORBITS.secular_tol * np.maximum(1.0, np.abs(nu[act]))
                bad |= ~conv
                # the eigenvectors: z = null vector of I + W C~, c_kj = -(1 / q0_kj) sum_s Bq_sj (C~ z)_ks
                nu[bad] = np.where(np.isfinite(nu[bad]), nu[bad], 1j)
                c, cent = eigvecs(nu)
                move = (np.abs(cent) > 0.5) & ~bad
                if not np.any(move):
                    break
                bad |= move & (recentred >= 3)
                move &= ~bad
                recentred[move] += 1
                nu[move] += 1j * np.round(cent[move])
                fresh = move                        # only the moved ones are refined in the next pass
            op = _HillOperator(omega2, Bq, Cexp, H, w)
            c = np.where(np.isfinite(c), c, 0.0)
            res = op.eigen_residual(c, nu) / np.maximum(1.0, np.abs(nu))          # of X = [c; nu c]
            bad |= ~(res < ORBITS.secular_residual) | (np.abs(cent) > 0.5)
            bad |= velocity_overlaps(c, vel).max(axis=-1) > 0.5
            lat = np.round(nu.imag)
            # (a class whose Newton did not converge may sit there too: hill_copies then finds its own exponent, or
            # declines when that is not a zero)
            near = (np.abs(lat) <= 2 * H + 1) & (np.abs(nu - 1j * lat) < ORBITS.secular_lattice_gap)
            bad |= near
            mu = np.exp(2 * np.pi * nu)
            close = (np.abs(mu[:, None] - mu[None, :]) < ORBITS.secular_distinct) | \
                (np.abs(mu[:, None] - 1.0 / mu[None, :]) < ORBITS.secular_distinct)
            close = np.triu(close, 1) & ~bad[:, None] & ~bad[None, :]
            bad |= close.any(axis=0) | close.any(axis=1)
        good = ~bad
        if np.any(bad):
            # the classes near the trivial pair's copies (internal resonances) by their copies, if all are; else (or
            # where the copies decline) the structured route on those classes alone (its blocks at the lattice i k
            # hold the hybrids the dense route may keep)
            if bad.sum() > ORBITS.secular_max_hard:
                return None

            def vectors(z):
                cz, centz = eigvecs(z)
                cz = np.where(np.isfinite(cz), cz, 0.0)
                resz = op.eigen_residual(cz, z) / np.maximum(1.0, np.abs(z))
                return centz, resz, velocity_overlaps(cz, vel)[:, nb - 1], cz

            hard = [classes[i] for i in np.flatnonzero(bad)]
            found = None
            if np.all(near[bad]):
                pairs = []
                found = hard_copies(nu[bad], H, logderiv, vectors, ORBITS.secular_tol, ORBITS.secular_residual, pairs)
                if found is not None:    # the structured route's warm start from this orbit, as if it had answered
                    warm_from_zeros(problem, op, tm, Vbar, beta2, hard, vel, nu[bad], *pairs[0])
            if found is None:
                found = _iterate(problem, op, tm, Vbar, beta2, hard, vel, warm=True)
            if found is None:
                found = _iterate(problem, op, tm, Vbar, beta2, hard, vel, warm=False)
            if found is None:
                return None
            mf = np.exp(2 * np.pi * np.asarray(found))
            mg = mu[good]
            if len(mg) and np.min(np.abs(mf[:, None] - mg[None, :])) < ORBITS.secular_distinct:
                return None                       # the structured blocks found a secular class's exponent again
            nu_kept += list(nu[good]) + list(-nu[good]) + list(found)
            last = warm_start(problem, "secular")
            if last is not None and last[0] == key:
                nu[bad] = last[1][bad] / w          # the hard classes: their last secular exponents
            else:
                nu[bad] = 1j * np.sqrt(np.maximum(beta2[classes], 0.0))[bad]
        else:
            nu_kept += list(nu) + list(-nu)
        set_warm_start(problem, "secular", (key, nu * w))
    if len(nu_kept) != 2 * n - 2:
        return None
    mu = np.concatenate([np.exp(2 * np.pi * np.asarray(nu_kept, dtype=complex)), [1.0, 1.0]])
    return mu[np.argsort(-np.abs(mu), kind="stable")]
