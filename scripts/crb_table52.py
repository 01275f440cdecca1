#!/usr/bin/env python3
"""Cramér–Rao bound of the Table 5.2 frequencies with 15 % noise (issue 14).

The thesis's truth model (docs/src/design.md §2) is discretised by zero-order hold at
25 600 Hz and its 3 × 3 displacement FRFs taken at 1024 lines above 0 Hz, as
`era::sim::truth_model_frf`. `add_noise` gives each pair complex Gaussian noise with an
RMS of 15 % of the pair's RMS: variance sigma_k**2 = (0.15 rms_k)**2, half of it in each of
the real and imaginary parts.

For a pole-residue model in z (`R_r/(z - e^(s_r Ts)) + conj`, the form `era refine`
fits at the truth model's sample time) the Fisher information of every real parameter
is J^T W J, W = diag(2 / sigma_k**2), J the Jacobian of the stacked real and imaginary
parts. Its inverse bounds the covariance of any unbiased estimator. The script prints,
per mode, 0.674 sigma_f (the median |df| of a Gaussian estimate with that standard
deviation) for four residue structures: free 3 × 3 residues, symmetric ones, rank one,
and symmetric rank one (psi psi^T, the truth's own), each with and without the constant
and double-integrator residual terms.

Usage: python3 scripts/crb_table52.py   (needs numpy and scipy;
scripts/python_tests.sh's venv at target/python-venv has both)
"""
import numpy as np
import scipy.linalg as sl

M, K, C = 1e-3, 1e6, 2.0
FS, LINES, NOISE = 25_600.0, 1025, 0.15


def truth():
    k = np.diag([2 * K] * 3 + [K])
    c = np.diag([2 * C] * 4)
    for i in range(3):
        k[i, i + 1] = k[i + 1, i] = -K
        c[i, i + 1] = c[i + 1, i] = -C
    a = np.block([[np.zeros((4, 4)), np.eye(4)], [-k / M, -c / M]])
    b = np.zeros((8, 3))
    b[4:7, :] = np.eye(3) / M
    cm = np.zeros((3, 8))
    cm[:, :3] = np.eye(3)
    return a, b, cm


def main():
    a, b, cm = truth()
    ts = 1.0 / FS
    f = np.linspace(0.0, FS / 2, LINES)[1:]
    z = np.exp(2j * np.pi * f * ts)
    ad = sl.expm(a * ts)
    bd = np.linalg.solve(a, (ad - np.eye(8)) @ b)
    lam, v = np.linalg.eig(ad)
    w = np.linalg.inv(v)
    idx = sorted((i for i in range(8) if lam[i].imag > 0), key=lambda i: np.angle(lam[i]))
    s = np.log(lam[idx]) / ts
    res = [(cm @ v[:, [i]]) @ (w[[i], :] @ bd) for i in idx]
    g = sum(r[:, :, None] / (z - l) + r.conj()[:, :, None] / (z - np.conj(l))
            for r, l in zip(res, lam[idx]))
    sigma = NOISE * np.sqrt((abs(g) ** 2).mean(axis=2))
    # Real and imaginary parts each carry half the complex variance.
    std_real = sigma / np.sqrt(2.0)

    def bound(kind, residuals):
        cols, pole_cols = [], []
        for r, (sr, rr) in enumerate(zip(s, res)):
            l = np.exp(sr * ts)
            g1, g2 = 1 / (z - l), 1 / (z - np.conj(l))
            d1, d2 = ts * l * g1 ** 2, ts * np.conj(l) * g2 ** 2
            pole_cols.append(len(cols))
            # s = -sigma + j omega: d/dsigma and d/domega of R g1 + conj(R) g2.
            cols.append(-(rr[:, :, None] * d1 + rr.conj()[:, :, None] * d2))
            cols.append(1j * rr[:, :, None] * d1 - 1j * rr.conj()[:, :, None] * d2)

            def add(dr):
                cols.append(dr[:, :, None] * g1 + dr.conj()[:, :, None] * g2)

            unit = lambda i, j: np.eye(3)[:, [i]] @ np.eye(3)[[j], :]
            if kind == "free":
                for i in range(3):
                    for j in range(3):
                        add(unit(i, j) + 0j)
                        add(1j * unit(i, j))
            elif kind == "symmetric":
                for i in range(3):
                    for j in range(i, 3):
                        e = unit(i, j) + unit(j, i) * (i != j)
                        add(e + 0j)
                        add(1j * e)
            elif kind == "rank one":
                u, sv, vh = np.linalg.svd(rr)
                left, right = u[:, 0] * sv[0], vh[0]
                for k in range(3):
                    e = np.eye(3)[k]
                    add(np.outer(e, right))
                    add(1j * np.outer(e, right))
                for k in range(1, 3):
                    e = np.eye(3)[k]
                    add(np.outer(left, e))
                    add(1j * np.outer(left, e))
            else:  # symmetric rank one, psi psi^T
                ev, evec = np.linalg.eig(rr)
                top = np.argmax(abs(ev))
                psi = evec[:, top] * np.sqrt(ev[top] / (evec[:, top] @ evec[:, top]))
                for k in range(3):
                    e = np.eye(3)[k]
                    d = np.outer(e, psi) + np.outer(psi, e)
                    add(d)
                    add(1j * d)
        if residuals:
            h2 = ts ** 2 * (z + 1) / (2 * (z - 1) ** 2)
            for h in (np.ones_like(z), h2):
                for i in range(3):
                    for j in range(3):
                        e = np.zeros((3, 3))
                        e[i, j] = 1.0
                        cols.append(e[:, :, None] * h)
        jac = np.array([(col / std_real[:, :, None]).ravel() for col in cols]).T
        jac = np.vstack([jac.real, jac.imag])
        cov = np.linalg.inv(jac.T @ jac)
        out = []
        for r, sr in enumerate(s):
            p = pole_cols[r]
            grad = np.array([-sr.real, sr.imag]) / abs(sr) / (2 * np.pi)
            out.append(np.sqrt(grad @ cov[p:p + 2, p:p + 2] @ grad))
        return np.array(out)

    print("truth modes (Hz):", np.round(abs(s) / (2 * np.pi), 2))
    print("0.674 x Cramér-Rao standard deviation of f (Hz) = median |df| of an efficient estimate")
    for kind in ("free", "symmetric", "rank one", "symmetric rank one"):
        for residuals in (True, False):
            med = 0.674 * bound(kind, residuals)
            label = f"{kind}, {'with' if residuals else 'without'} residual terms"
            print(f"  {label:<45} " + "  ".join(f"{x:7.3f}" for x in med))


if __name__ == "__main__":
    main()
