r"""Hill's multipliers by the structured route (hill.py explains the routes): shift-invert subspace iteration on
the Hill matrix, one small block per Floquet exponent, the springs' low-rank part by Woodbury (the operator, which
the secular route uses too; what else the routes share: hill_shared.py)."""
from __future__ import annotations

import numpy as np

from .hill_shared import (_classes, _exp_transform, _setup, _trivial_pair, central_pool, set_warm_start,
                          velocity_overlaps, warm_start)
from .settings import ORBITS


class _HillOperator:
    """The Hill matrix of one orbit in exp(i k theta) and modal coordinates, time in units of 1 / omega
    (exponents nu = lambda / omega, multipliers exp(2 pi nu)): products with L and shifted solves
    (L - sigma)^-1, for many shifts and blocks at once.  Vectors are stored (S, 2m, b): S shifts, b vectors,
    m = N_b n, the first half c[k, j] (k = -H..H, mode j), the second nu c."""

    def __init__(self, omega2, Bq, Cexp, H, w=1.0):
        self.w = w                                            # the orbit's omega (rad/s): the unit of time
        self.H = H
        self.nb = 2 * H + 1
        self.n = len(omega2)
        self.m = self.nb * self.n
        self.k = np.arange(-H, H + 1, dtype=float)
        self.omega2 = omega2                                  # (n,) in units of omega^2
        self.Bq = Bq                                          # (n_s, n)
        self.BqT = np.ascontiguousarray(Bq.T)
        self.Cexp = Cexp                                      # (n_s, N_b, N_b) in units of omega^2
        self.CexpT = np.swapaxes(Cexp, 0, 1)                  # (N_b, n_s, N_b)
        self.ns = Bq.shape[0]
        self.Kdiag = (-(self.k ** 2))[:, None] + omega2[None, :]       # (N_b, n): D^2 + Omega^2

    def _halves(self, X):
        S, _, b = X.shape
        return (X[:, :self.m].reshape(S, self.nb, self.n, b), X[:, self.m:].reshape(S, self.nb, self.n, b))

    def _couple(self, d):
        """f_ks = sum_l C_s[k, l] d_ls: the springs' Galerkin blocks on spring deformations d (S, N_b, n_s, b)
        (matrix products throughout: numpy's einsum is ~8x slower on these shapes)."""
        return np.swapaxes(self.Cexp[None] @ np.swapaxes(d, 1, 2), 1, 2)

    def _springs(self, x1):
        """U C U^T x1 for x1 (S, N_b, n, b)."""
        return self.BqT @ self._couple(self.Bq @ x1)

    def apply(self, X):
        """L X."""
        x1, x2 = self._halves(X)
        S, b = X.shape[0], X.shape[2]
        Kx = self.Kdiag[None, :, :, None] * x1 + self._springs(x1)
        y2 = -Kx - 2j * self.k[None, :, None, None] * x2
        return np.concatenate([x2.reshape(S, self.m, b), y2.reshape(S, self.m, b)], axis=1)

    def eigen_residual(self, c, nu):
        """||L X - nu X|| / ||X|| (S,) for X = lift(c, nu), c (S, N_b, n): the first half of L X - nu X vanishes
        (it is nu c - nu c), the second is -Q(nu) c, Q(nu) = diag((nu + i k)^2 + omega_j^2) + U C U^T; so only Q(nu) c
        is formed (half the work of apply)."""
        q0 = (nu[:, None, None] + 1j * self.k[None, :, None]) ** 2 + self.omega2[None, None, :]
        Qc = q0 * c + self._springs(c[..., None])[..., 0]
        nrm = np.sqrt((np.abs(c) ** 2).sum(axis=(1, 2)) * (1.0 + np.abs(nu) ** 2))
        return np.sqrt((np.abs(Qc) ** 2).sum(axis=(1, 2))) / np.maximum(nrm, 1e-300)

    def factor(self, sigma):
        """What the solves with shifts sigma (S,) need: 1 / Q0 (S, N_b, n) and the r x r Woodbury matrices."""
        q0 = (sigma[:, None, None] + 1j * self.k[None, :, None]) ** 2 + self.omega2[None, None, :]
        q0inv = 1.0 / q0
        W = (self.Bq * q0inv[:, :, None, :]) @ self.BqT                          # (S, N_b, n_s, n_s)
        CW = self.CexpT[None, :, :, :, None] * np.swapaxes(W, 1, 2)[:, None]     # (S, N_b, n_s, N_b, n_s)
        r = self.nb * self.ns
        Mw = CW.reshape(len(sigma), r, r) + np.eye(r)[None]
        return sigma, q0inv, Mw

    def solve(self, fac, Y):
        """(L - sigma)^-1 Y for each shift (Y (S, 2m, b))."""
        sigma, q0inv, Mw = fac
        y1, y2 = self._halves(Y)
        S, b = Y.shape[0], Y.shape[2]
        rhs = -(y2 + (2j * self.k[None, :, None, None] + sigma[:, None, None, None]) * y1)
        g = q0inv[..., None] * rhs
        f = self._couple(self.Bq @ g).reshape(S, self.nb * self.ns, b)
        z = np.linalg.solve(Mw, f).reshape(S, self.nb, self.ns, b)
        x1 = g - q0inv[..., None] * (self.BqT @ z)
        x2 = y1 + sigma[:, None, None, None] * x1
        return np.concatenate([x1.reshape(S, self.m, b), x2.reshape(S, self.m, b)], axis=1)

    def centroids(self, X):
        """Mean harmonic sum_k k |c_k|^2 / sum_k |c_k|^2 of each vector's first half (S, b)."""
        x1 = self._halves(X)[0]
        p = (np.abs(x1) ** 2).sum(axis=2)                                       # (S, N_b, b)
        return (self.k[None, :, None] * p).sum(axis=1) / np.maximum(p.sum(axis=1), 1e-300)

    def lift(self, c, nu):
        """Vectors [c; nu c] (S, 2m, b) from first halves c (S, N_b, n, b) and exponents nu (S,)."""
        S, b = c.shape[0], c.shape[3]
        return np.concatenate([c.reshape(S, self.m, b), (nu[:, None, None, None] * c).reshape(S, self.m, b)], axis=1)


def _keep_off_lattice(sigma):
    """Shifts moved to at least ORBITS.structured_lattice_gap from the points i k (the trivial pair's copies, where Q is
    singular)."""
    k = np.round(sigma.imag)
    near = np.abs(sigma - 1j * k) < ORBITS.structured_lattice_gap
    if np.any(near):
        side = np.where(sigma.real[near] < 0, -1.0, 1.0)
        sigma = sigma.copy()
        sigma[near] = 1j * k[near] + side * ORBITS.structured_lattice_gap
    return sigma


def _rayleigh_ritz(op, V):
    """Orthonormalise each block and return (V, theta (S, b), X (S, 2m, b) Ritz vectors, residuals (S, b))."""
    V = np.linalg.qr(V)[0]
    LV = op.apply(V)
    Hm = np.conj(np.swapaxes(V, 1, 2)) @ LV
    theta, Y = np.linalg.eig(Hm)
    X = V @ Y
    R = LV @ Y - X * theta[:, None, :]
    # |X| = |Y| column by column (V orthonormal)
    res = np.sqrt((R.real ** 2 + R.imag ** 2).sum(axis=1)) / np.maximum(np.sqrt((np.abs(Y) ** 2).sum(axis=1)), 1e-300)
    return V, theta, X, res


def _structured(problem, A, w, bp, C):
    """Multipliers (2n,) by the structured route, or None when it cannot vouch for them (then: dense)."""
    n, H = problem.n, bp.harmonics
    Tinv, omega2, touched, Ah, vel = _setup(problem, A, w, bp)
    Cexp = np.einsum("ab,sbc,cd->sad", Tinv, C, _exp_transform(H)) / w ** 2
    Bq = problem.sys.Bq
    tm, beta2, Vbar, classes, nu_kept = _classes(omega2, Bq, Cexp, touched, Ah, H)
    if classes:
        op = _HillOperator(omega2, Bq, Cexp, H, w)
        found = _iterate(problem, op, tm, Vbar, beta2, classes, vel, warm=True)
        if found is None and warm_start(problem, "structured") is not None:
            found = _iterate(problem, op, tm, Vbar, beta2, classes, vel, warm=False)      # a cold start
        if found is None:
            return None
        nu_kept += list(found)
    if len(nu_kept) != 2 * n - 2:
        return None
    mu = np.concatenate([np.exp(2 * np.pi * np.asarray(nu_kept, dtype=complex)), [1.0, 1.0]])
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def _trivial_overlap(op, X, vel):
    """(largest |cos| (S, b) between each vector's first half and the orbit's velocity moved by p harmonics,
    p = -2H..2H: the trivial pair's eigenvector and its copies; the same for p = 0 alone: the trivial pair)."""
    S, _, b = X.shape
    x1 = np.moveaxis(X[:, :op.m].reshape(S, op.nb, op.n, b), 3, 1)          # (S, b, N_b, n)
    cos = velocity_overlaps(x1, vel)
    return cos.max(axis=-1), cos[..., op.nb - 1]


def _cold_start(op, tm, Vbar, beta2, classes, vel):
    """(shifts (S,), first halves of the start vectors (S, N_b, n, ORBITS.structured_block)) of _iterate's blocks
    without a warm start: one per class at the averaged stiffness' frequency, its mode on the fundamental and its
    neighbours; one per point i k, k = 0..H, the trivial pair's copy there (the velocity moved by k harmonics)."""
    nc, b, nb, n, H = len(classes), ORBITS.structured_block, op.nb, op.n, op.H
    S = nc + H + 1
    sigma = np.concatenate([1j * np.sqrt(np.maximum(beta2[classes], 0.0)) + 1e-9,
                            1j * np.arange(H + 1) + ORBITS.zero_shift])
    c = np.zeros((S, nb, n, b), dtype=complex)
    rng = np.random.default_rng(12345)
    bell = np.exp(-0.5 * np.arange(-H, H + 1) ** 2)[:, None]
    for i, j in enumerate(classes):
        v = np.zeros(n)
        v[tm] = Vbar[:, j]
        c[i, H, :, 0] = v
        if H >= 1:
            c[i, H + 1, :, 1] = v
            c[i, H - 1, :, 2] = v
        c[i, :, :, 3] = rng.standard_normal((nb, n)) * bell
    for k in range(H + 1):                 # the trivial pair's copy at i k: the velocity moved by k harmonics
        i = nc + k
        c[i, :nb - k, :, 0] = vel[k:]
        c[i, :, :, 1] = np.roll(np.abs(c[i, :, :, 0]), 1, axis=0)
        for col in range(2, b):
            c[i, :, :, col] = rng.standard_normal((nb, n)) * np.roll(bell, -k, axis=0)
    return sigma, c


def warm_from_zeros(problem, op, tm, Vbar, beta2, classes, vel, nu_classes, zeros, vectors):
    """Store _iterate's warm start from eigenpairs found otherwise (hill_copies.py): each block starts from the
    eigenvectors of the zeros nearest its shift (the class's exponent nu_classes (units of omega), or i k), the cold
    start's vectors where fewer are known.  So the structured route, asked at a later orbit of the branch, starts
    from this orbit as it would from its own last answer.  zeros (Z,) and vectors (Z, N_b, n): the eigenpairs."""
    nc, b, nb, n, H = len(classes), ORBITS.structured_block, op.nb, op.n, op.H
    S = nc + H + 1
    sigma, c = _cold_start(op, tm, Vbar, beta2, classes, vel)
    sigma[:nc] = nu_classes
    lattice = 1j * np.arange(H + 1)
    for i in range(S):
        centre = sigma[i] if i < nc else lattice[i - nc]
        dist = np.abs(zeros - centre)
        near = np.argsort(dist, kind="stable")[:b]
        near = near[dist[near] < 0.5]                 # this point's, not the next lattice point's (1 apart)
        # the known eigenvectors first; at 0 the trivial pair's start (the velocity) stays in the first column
        first = 1 if i == nc else 0
        near = near[:b - first]
        c[i, :, :, first:first + len(near)] = np.moveaxis(vectors[near], 0, -1)
    shifts = sigma.copy()
    shifts[nc:] = lattice + ORBITS.zero_shift
    X = op.lift(c, shifts)
    set_warm_start(problem, "structured", ((nb, n, S), (shifts + 1e-9j * np.maximum(1.0, np.abs(shifts))) * op.w, X))


def _iterate(problem, op, tm, Vbar, beta2, classes, vel, warm=True):
    """The 2 len(classes) kept exponents nu (units of omega) of the touched modes, or None.

    One block per class (its shift at the class's exponent), and one around each i k, k = 0..H, where the
    trivial pair and its copies lie: at internal resonances other eigenvalues with eigenvectors centred on the
    fundamental gather there (the hybrids of those copies and another mode's), which the dense route keeps when
    they are more central than a class's exponent; so they join the pool too."""
    nc = len(classes)
    b, nb, n, H = ORBITS.structured_block, op.nb, op.n, op.H
    S = nc + H + 1
    lattice = 1j * np.arange(H + 1) + ORBITS.zero_shift                      # the last H + 1 blocks' shifts
    is_lat = np.arange(S) >= nc
    warm = warm_start(problem, "structured") if warm else None
    if warm is not None and warm[0] == (nb, n, S):
        sigma = warm[1] / op.w                 # the exponents in rad/s, in units of this orbit's omega
        V = op.lift(warm[2][:, :op.m].reshape(S, nb, n, b), sigma)
    else:
        sigma, c = _cold_start(op, tm, Vbar, beta2, classes, vel)
        V = op.lift(c, sigma)
    sigma[is_lat] = lattice
    sigma = _keep_off_lattice(sigma)
    done = np.zeros(S, dtype=bool)
    frozen = np.zeros(S, dtype=bool)
    recentred = np.zeros(S, dtype=int)
    theta = np.zeros((S, b), dtype=complex)
    X = np.zeros_like(V)
    res = np.full((S, b), np.inf)
    cent = np.zeros((S, b))
    triv = np.zeros((S, b))
    triv0 = np.zeros((S, b))
    gave_up = np.zeros(S, dtype=bool)         # lattice blocks stopped with central eigenpairs unconverged (the one at
    #                                          0 makes the route decline; at i k, k >= 1, their copies' hybrids)
    with np.errstate(all="ignore"):
        for sweep in range(ORBITS.structured_max_sweeps):
            act = np.flatnonzero(~done)
            if not len(act):
                break
            fac = op.factor(sigma[act])
            Va = op.solve(fac, V[act])
            if not np.all(np.isfinite(Va)):
                return None
            Va, th, Xa, ra = _rayleigh_ritz(op, Va)
            ca, (tr, tr0) = op.centroids(Xa), _trivial_overlap(op, Xa, vel)
            V[act], theta[act], X[act], res[act], cent[act], triv[act], triv0[act] = Va, th, Xa, ra, ca, tr, tr0
            rel_all = ra / np.maximum(1.0, np.abs(th))
            for ii, i in enumerate(act):
                if is_lat[i]:                  # fixed shift; done when its central eigenpairs converged
                    # (the block at 0 waits for its trivial pair too: told apart from the others only once
                    # converged, _trivial_pair; excluded while iterating, the pairs nearest the velocity were
                    # whatever the first sweeps gave, and a block could stop before anything converged: from a
                    # cold start at example 09's unstable orbits past the 5:1 tongue, a real pair +-1.2e-4 missed)
                    want = np.abs(ca[ii]) <= ORBITS.centroid_max
                    if np.all(rel_all[ii][want] < ORBITS.structured_residual_tol):
                        done[i] = True
                    elif sweep >= ORBITS.zero_sweeps:
                        done[i] = gave_up[i] = True
                    continue
                cand = np.flatnonzero(tr[ii] <= 0.5)
                if not len(cand):              # only the trivial pair's copies or hybrids of them: the lattice
                    if (np.all(rel_all[ii] < ORBITS.structured_residual_tol)
                            or sweep >= ORBITS.zero_sweeps):   # blocks hold those
                        done[i] = True
                    continue
                t = cand[int(np.argmin(np.abs(th[ii, cand] - sigma[i])))]   # the block's eigenvalue nearest its shift
                rel = rel_all[ii, t]
                ct = ca[ii, t]
                if rel < 1e-6 and abs(ct) > 0.5 and recentred[i] < 4:
                    # centred on another harmonic: a copy; move the shift and the block by round(ct) harmonics
                    p = int(np.round(ct))
                    recentred[i] += 1
                    x1 = np.roll(op._halves(V[i:i + 1])[0][0], -p, axis=0)
                    if p > 0:
                        x1[nb - p:] = 0.0
                    elif p < 0:
                        x1[:-p] = 0.0
                    sigma[i] = th[ii, t] + 1j * p
                    frozen[i] = False
                    V[i] = op.lift(x1[None], np.array([sigma[i]]))[0]
                    continue
                if rel < ORBITS.structured_residual_tol:
                    done[i] = True
                elif rel < 1e-8:
                    frozen[i] = True
                elif not frozen[i] and sweep >= 1:
                    sigma[i] = th[ii, t]
            sigma[is_lat] = lattice
            sigma = _keep_off_lattice(sigma)
        else:
            if not np.all(done):
                return None
    if gave_up[nc]:
        return None        # the block at 0 did not converge: what lies there (a pair through +1?) is not known
    # the pool: converged eigenpairs but the trivial pair, their conjugates and Hamiltonian partners -conj (exact
    # eigenvalues too: the Hill matrix is that of a gyroscopic system), ordered by |mean harmonic| as the dense route
    rel = res / np.maximum(1.0, np.abs(theta))
    # the trivial pair is left out of the pool: in the trivial block the two exponents nearest 0 among the vectors
    # near the velocity; in the others the vectors on the velocity (ORBITS.trivial_cos) but, within
    # ORBITS.structured_lattice_gap of 0, those that are not the two nearest 0 (next to a fold the pair through +1 lies
    # on the velocity too)
    ok = rel < 1e3 * ORBITS.structured_residual_tol
    on_vel = triv0 > ORBITS.trivial_cos
    trivial = _trivial_pair(triv0[nc], theta[nc])
    if trivial.sum() != 2 or not np.all(ok[nc][trivial]) or np.any(np.abs(theta[nc][trivial]) > ORBITS.trivial_nu):
        return None        # the block at 0 does not hold the trivial pair: what else it holds is not known either
    for i in range(S):
        if i == nc:
            ok[i] &= ~trivial
        elif np.any(on_vel[i]):
            ok[i] &= ~on_vel[i] | ((np.abs(theta[i]) < ORBITS.structured_lattice_gap)
                                   & ~_trivial_pair(np.where(on_vel[i], 1.0, 0.0), theta[i]))
    kept = central_pool(theta[ok], np.abs(cent[ok]), 2 * nc)
    if kept is None:
        return None
    # warm start for the next orbit of this problem: the shifts at the kept exponents of each block
    t = np.argmin(np.abs(theta - sigma[:, None]) + 1e9 * (triv > 0.5), axis=1)
    nu_t = theta[np.arange(S), t]
    nu_t[is_lat] = lattice
    set_warm_start(problem, "structured", ((nb, n, S), (nu_t + 1e-9j * np.maximum(1.0, np.abs(nu_t))) * op.w, X.copy()))
    return kept
