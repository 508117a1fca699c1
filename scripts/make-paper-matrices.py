#!/usr/bin/python3
"""Writes the paper's rigid rotor (cases/reference.toml) as the matrices of a user's linear rotor
(cases/matrices-paper/, read by cases/matrices-paper.toml, [model] kind = "matrices").

The rotor's coordinates q = (x_b, y_b, x_r, y_r); the formulas are those of
include/rubdyn/model/rotor_stator_model.hpp (paper eq. 11-16), written here from them:
  l = L - delta, nu = d / l, M11 = (1-nu)^2 m + Jd/l^2, M12 = nu (1-nu) m - Jd/l^2,
  M22 = nu^2 m + Jd/l^2, H = Jp / l^2;
  M = [[M11, 0, M12, 0], [0, M11, 0, M12], [M12, 0, M22, 0], [0, M12, 0, M22]],
  G: theta' G q' with G(x_b, y_b) = H, G(x_b, y_r) = -H, G(y_b, x_r) = H, G(x_r, y_r) = H
     (and the skew-symmetric entries), C = diag(c_b, c_b, 0, 0), K = diag(k_b, k_b, 0, 0),
  f0 = (0, -(1-nu) m g, 0, -nu m g): the rotor's weight (the stator's is carried by its support,
  so the case sets loads.gravity = 0).
M and G go to .npy files (M in C order, G in Fortran order), C, K and f0 to CSV, every number
with 17 significant digits (round-trip exact).

    scripts/make-paper-matrices.py [--case cases/reference.toml] [--out cases/matrices-paper]

With --point P the first two coordinates are not the bearing's but the rotor's point at axial
distance P from B, z_P = (1 - s) z_b + s z_r with s = P / l (the paper's interpolation, eq. 9-10,
the point a second rub plane sees): q' = (x_P, y_P, x_r, y_r), q = T q' and the matrices
T^T M T, T^T C T, T^T K T, T^T G T, T^T f0, the same Lagrangian in other coordinates
(cases/matrices-two-plane.toml: cases/two-plane.toml's rotor with a contact node at each plane).

    scripts/make-paper-matrices.py --case cases/two-plane.toml --point 0.2 \
        --out cases/matrices-two-plane
"""
import argparse
import pathlib
import tomllib

import numpy as np


def matrices(case):
    r, b, g = case["rotor"], case["bearing"], case["loads"]["gravity"]
    m, Jd, Jp = r["mass"], r["Jd"], r["Jp"]
    l = r["L"] - r["delta"]
    nu = r["d"] / l
    jl = Jd / (l * l)
    M11 = (1.0 - nu) * (1.0 - nu) * m + jl
    M12 = nu * (1.0 - nu) * m - jl
    M22 = nu * nu * m + jl
    H = Jp / (l * l)
    XB, YB, XR, YR = range(4)
    M = np.zeros((4, 4))
    M[XB, XB] = M[YB, YB] = M11
    M[XR, XR] = M[YR, YR] = M22
    M[XB, XR] = M[XR, XB] = M[YB, YR] = M[YR, YB] = M12
    G = np.zeros((4, 4))
    for i, j, h in ((XB, YB, H), (XB, YR, -H), (YB, XR, H), (XR, YR, H)):
        G[i, j], G[j, i] = h, -h
    C = np.diag([b["c"], b["c"], 0.0, 0.0])
    K = np.diag([b["k"], b["k"], 0.0, 0.0])
    mg = m * g
    f0 = np.array([0.0, -(1.0 - nu) * mg, 0.0, -nu * mg])
    return M, C, K, G, f0


def write_csv(path, a):
    a = np.atleast_2d(a) if a.ndim == 2 else a.reshape(-1, 1)
    path.write_text("".join(",".join(repr(float(x)) for x in row) + "\n" for row in a))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    root = pathlib.Path(__file__).resolve().parent.parent
    ap.add_argument("--case", default=root / "cases" / "reference.toml", type=pathlib.Path)
    ap.add_argument("--out", default=root / "cases" / "matrices-paper", type=pathlib.Path)
    ap.add_argument("--point", type=float, default=None,
                    help="axial position [m] of the point that replaces the bearing's coordinates")
    a = ap.parse_args()
    case = tomllib.loads(a.case.read_text())
    M, C, K, G, f0 = matrices(case)
    if a.point is not None:
        l = case["rotor"]["L"] - case["rotor"]["delta"]
        s = a.point / l
        T = np.zeros((4, 4))  # q = T q'
        T[0, 0] = T[1, 1] = 1.0 / (1.0 - s)
        T[0, 2] = T[1, 3] = -s / (1.0 - s)
        T[2, 2] = T[3, 3] = 1.0
        M, C, K, G = (T.T @ X @ T for X in (M, C, K, G))
        f0 = T.T @ f0
        # symmetric and skew to the bit (the reader symmetrises; so does the product's round-off)
        M, C, K = (0.5 * (X + X.T) for X in (M, C, K))
        G = 0.5 * (G - G.T)
    a.out.mkdir(parents=True, exist_ok=True)
    np.save(a.out / "M.npy", np.ascontiguousarray(M, dtype="<f8"))
    np.save(a.out / "G.npy", np.asfortranarray(G, dtype="<f8"))
    write_csv(a.out / "C.csv", C)
    write_csv(a.out / "K.csv", K)
    write_csv(a.out / "f0.csv", f0)
    print(f"wrote {a.out}: M.npy, G.npy, C.csv, K.csv, f0.csv (n = {M.shape[0]})")


if __name__ == "__main__":
    main()
