"""The Campbell frequencies of the coupled rotor-stator system, written from the paper's
equations alone (eq. 11-14 and section 5.1.2), independently of rubdyn's C++ (src/analysis):
the fit in fit.py uses it, and tests/cases/paper_case.py checks rubdyn's `campbell` against it.

Coupled system (paper, 5.1.2): the stator moves with the rotor at R, so m_s adds to M22 and k_s
acts on (x_r, y_r). Isotropy lets each node be written as one complex coordinate z = x + i y; the
gyroscopic rows of G_T (eq. 14) then read -i Omega H S z' with S = [[1, -1], [-1, 1]], so
    M2 z'' - i Omega H S z' + K2 z = 0,   M2 = [[M11, M12], [M12, M22 + m_s]],  K2 = diag(k_b, k_s)
(undamped, as the paper's Fig. 8). A solution z = Z e^{i w t} whirls forward (with the spin) for
w > 0 and backward for w < 0: the 4 eigenvalues of the first-order form give 2 forward and 2
backward frequencies, no labelling heuristics needed."""
import numpy as np


def matrices(p):
    """M2, K2, H of a case dict (the TOML tables rotor, bearing, stator)."""
    r, b, s = p["rotor"], p["bearing"], p["stator"]
    ell = r["L"] - r["delta"]
    nu = r["d"] / ell
    m, jd = r["mass"], r["Jd"]
    m11 = (1 - nu) ** 2 * m + jd / ell ** 2
    m12 = nu * (1 - nu) * m - jd / ell ** 2
    m22 = nu ** 2 * m + jd / ell ** 2
    h = r["Jp"] / ell ** 2
    return (np.array([[m11, m12], [m12, m22 + s["mass"]]]), np.diag([b["k"], s["k"]]), h)


def frequencies(p, omega):
    """{'f1f', 'f2f', 'f1b', 'f2b'} [Hz] (all >= 0) at spin speed omega [rad/s] > = 0."""
    m2, k2, h = matrices(p)
    s = np.array([[1.0, -1.0], [-1.0, 1.0]])
    mi = np.linalg.inv(m2)
    a = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-mi @ k2, mi @ (1j * omega * h * s)]])
    w = np.linalg.eigvals(a).imag / (2 * np.pi)
    fw, bw = np.sort(w[w > 0]), np.sort(-w[w < 0])
    return {"f1f": fw[0], "f2f": fw[1], "f1b": bw[0], "f2b": bw[1]}
