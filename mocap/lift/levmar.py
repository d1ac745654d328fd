"""Levenberg-Marquardt for the clip solve (``mocap.lift.problem``): soft-L1 rows by iteratively
reweighted least squares, each step one banded Cholesky factorisation (frames tie only to their
neighbours, so the normal equations are a band), the clip's lengths (tied to every frame) by
their Schur complement. Run single-threaded: the band is small, and BLAS threads fighting over a
busy machine's cores cost more than they gain."""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.linalg import cho_solve_banded, cholesky_banded
from threadpoolctl import threadpool_limits

# the solve stops when an iteration lowers the cost by less than this fraction of it
TOLERANCE = 1e-4
MAX_ITERATIONS = 30


def levenberg_marquardt(problem, x: np.ndarray, max_iter: int = MAX_ITERATIONS) -> np.ndarray:
    """The unknowns of a ``Problem`` solved from ``x``: Nielsen's damping update."""
    with threadpool_limits(1, user_api="blas"):
        r, jac = problem.residuals(x, True)
        cost, weight = robust_cost(problem, r)
        lam, grow = None, 2.0
        for _ in range(max_iter):
            wj = sparse.diags(weight) @ jac
            normal = (jac.T @ wj).tocsr()
            grad = wj.T @ r
            diag = np.maximum(normal.diagonal(), 1e-9)
            lam = 1e-4 * diag.max() if lam is None else lam
            step = solve_normal(normal, lam, -grad, problem.n_p)
            predicted = -(grad @ step) - 0.5 * step @ (normal @ step)
            cost_new, _ = robust_cost(problem, problem.residuals(x + step))
            gain = (cost - cost_new) / max(predicted, 1e-300)
            if gain <= 0:
                lam, grow = lam * grow, grow * 2.0
                continue
            done = cost - cost_new < TOLERANCE * cost
            x, cost = x + step, cost_new
            lam *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)
            grow = 2.0
            if done:
                break
            r, jac = problem.residuals(x, True)
            _, weight = robust_cost(problem, r)
    return x


def robust_cost(problem, r: np.ndarray) -> tuple[float, np.ndarray]:
    """(cost, each row's IRLS weight): soft-L1 at ``loss_scale`` on the problem's robust linear rows
    (2D, acceleration, person-model depth), squares elsewhere."""
    weight = np.ones(len(r))
    rho = r * r
    robust = np.flatnonzero(problem.robust)
    c2 = problem.w.loss_scale**2
    z = 1.0 + rho[robust] / c2
    rho[robust] = 2.0 * c2 * (np.sqrt(z) - 1.0)
    weight[robust] = 1.0 / np.sqrt(z)
    return 0.5 * float(rho.sum()), weight


def solve_normal(normal: sparse.csr_matrix, damping: float, rhs: np.ndarray, n_p: int) -> np.ndarray:
    """(normal + damping I)^-1 rhs: the first ``n_p`` unknowns (coordinates in frame order) by a
    banded Cholesky, the rest (the clip's lengths) by their Schur complement."""
    a = normal + damping * sparse.identity(normal.shape[0], format="csr")
    upper = sparse.triu(a[:n_p, :n_p]).tocoo()
    band = int((upper.col - upper.row).max()) if upper.nnz else 0
    ab = np.zeros((band + 1, n_p))
    ab[band + upper.row - upper.col, upper.col] = upper.data
    factor = (cholesky_banded(ab, lower=False, check_finite=False), False)
    if n_p == a.shape[0]:
        return cho_solve_banded(factor, rhs, check_finite=False)
    c = a[:n_p, n_p:].toarray()
    solved = cho_solve_banded(factor, np.column_stack([rhs[:n_p], c]), check_finite=False)
    schur = a[n_p:, n_p:].toarray() - c.T @ solved[:, 1:]
    last = np.linalg.solve(schur, rhs[n_p:] - c.T @ solved[:, 0])
    return np.concatenate([solved[:, 0] - solved[:, 1:] @ last, last])
