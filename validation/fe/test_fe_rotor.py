#!/usr/bin/python3
"""The finite-element rotors of scripts/make-fe-rotor.py (docs/fe-rotors.md) against what is known
of them: the element matrices against the pinned-pinned uniform shaft's closed forms, the
gyroscopic matrix against the forward/backward split of a disc's closed form (and its whirl
direction), the rigid rotor's gyroscopic matrix, `rubdyn campbell` of a generated case against
eigenvalues computed here from the same files, and the reference scene's frequencies (issue 32's
own calculation, reproduced; they are not the paper's).

Run through ctest (tests/CMakeLists.txt names the CLI), or by hand:
    RUBDYN_CLI=build/rubdyn /usr/bin/python3 -m pytest validation/fe/test_fe_rotor.py
"""
import csv
import importlib.util
import math
import os
import subprocess
import tempfile
import tomllib

import numpy as np
import pytest
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
RUBDYN = os.environ.get("RUBDYN_CLI", os.path.join(ROOT, "build", "rubdyn"))
needs_cli = pytest.mark.skipif("RUBDYN_CLI" not in os.environ and not os.path.isfile(RUBDYN),
                               reason="no rubdyn CLI (set RUBDYN_CLI)")


def load_script(name, file):
    spec = importlib.util.spec_from_file_location(name, os.path.join(ROOT, "scripts", file))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


fe = load_script("make_fe_rotor", "make-fe-rotor.py")

E, RHO, D, L = 2.1e11, 7800.0, 0.05, 1.2
A = math.pi * D * D / 4.0
I = math.pi * D**4 / 64.0


def shaft_only(**extra):
    """A description of the bare steel shaft (one weak bearing and one seal, which the script
    requires; the tests use the shaft's own matrices)."""
    d = dict(shaft=dict(length=L, diameter=D, E=E, rho=RHO),
             bearing=[dict(z=0.0, k=1.0, c=0.0)],
             seal=[dict(z=0.0, radius=0.02, gap=1e-4, mu=0.1, stator_rigid=True)])
    d.update(extra)
    return d


def x_plane(r, drop):
    """The x-plane dofs (x, dx of every node) without those in drop."""
    return [i for i in range(r.n) if i % 4 in (0, 2) and i not in drop]


def pinned_frequencies(ne, rotary):
    """Bending frequencies [rad/s] of the pinned-pinned shaft of ne elements (x plane: the y plane
    is the same matrix): the end nodes' deflections removed, their slopes free."""
    r = fe.build(shaft_only(), ne)
    p = x_plane(r, drop=(0, r.n - 4))
    M = r.M_shaft + (r.M_rotary if rotary else 0.0)
    return np.sqrt(sl.eigh(r.K_shaft[np.ix_(p, p)], M[np.ix_(p, p)], eigvals_only=True))


def exact_pinned(n, rotary):
    """omega_n of the pinned-pinned uniform beam: Euler-Bernoulli (k = n pi / L)
    omega = k^2 sqrt(E I / (rho A)); with rotary inertia (Rayleigh beam, exact for simple
    supports) omega^2 = E I k^4 / (rho A (1 + k^2 I / A))."""
    k = n * math.pi / L
    w2 = E * I * k**4 / (RHO * A)
    return math.sqrt(w2 / (1.0 + k * k * I / A)) if rotary else math.sqrt(w2)


@pytest.mark.parametrize("rotary", [False, True], ids=["euler-bernoulli", "with rotary inertia"])
def test_pinned_shaft_converges_from_above_at_fourth_order(rotary):
    # Consistent-mass Hermite cubics are a conforming Rayleigh-Ritz method: every eigenvalue is an
    # upper bound (min-max principle), and its error is O(h^(2(p+1-m))) = O(h^4) for cubics
    # (p = 3) of a fourth-order problem (m = 2) (Strang & Fix, ch. 6), so halving the elements
    # divides each frequency's error by 2^4 = 16 once the mode is resolved. Measured ratios from
    # 8 -> 16 -> 32 elements: 15.2-16.0 (modes 1-3); [14, 17] leaves room for the pre-asymptotic
    # 15.2 and fails for a third- (8) or fifth-order (32) rate, or any lumped mass (from below).
    # 32 elements is the finest: at 64 the first mode's error (4e-9) meets eigh's round-off.
    errs = {}
    for ne in (8, 16, 32):
        w = pinned_frequencies(ne, rotary)
        errs[ne] = np.array([w[n - 1] / exact_pinned(n, rotary) - 1.0 for n in (1, 2, 3)])
        assert np.all(errs[ne] > 0.0), (ne, errs[ne])  # from above
    for a, b in ((8, 16), (16, 32)):
        ratio = errs[a] / errs[b]
        assert np.all((14.0 < ratio) & (ratio < 17.0)), (a, b, ratio)
    # and close: 32 elements on 3 half-waves, 5e-6 measured on the third
    assert np.all(errs[32] < 1e-5), errs[32]


def test_rotary_inertia_lowers_the_frequencies_by_the_rayleigh_factor():
    # the rotary-inertia matrix is what separates the two closed forms: with 32 elements the
    # computed drop of the 5th mode matches 1 / sqrt(1 + k^2 I / A) to the discretisation error
    # (1e-5 relative on each frequency, above): the drop itself is 1.7e-3
    w_eb, w_r = pinned_frequencies(32, False)[4], pinned_frequencies(32, True)[4]
    drop = 1.0 - w_r / w_eb
    k = 5 * math.pi / L
    exact = 1.0 - 1.0 / math.sqrt(1.0 + k * k * I / A)
    assert abs(drop / exact - 1.0) < 1e-2, (drop, exact)


def disc_scene(ne, kb=5e7):
    m, Jp, Jd = 22.0, 0.2475, 0.1267
    d = shaft_only(disc=[dict(z=L / 2, mass=m, Jp=Jp, Jd=Jd)],
                   bearing=[dict(z=0.0, k=kb, c=0.0), dict(z=L, k=kb, c=0.0)])
    return fe.build(d, ne), m, Jp, Jd, kb


@pytest.mark.parametrize("ne", [2, 6])
def test_gyroscopic_split_of_a_mid_span_disc(ne):
    # A disc (mass m, inertias Jp, Jd) at mid-span of a massless shaft on two bearings k_b: by
    # symmetry its tilt decouples from its deflection, with tilt stiffness
    #   1 / k_t = L / (12 E I) (a moment at mid-span of a simply supported beam)
    #           + 2 / (k_b L^2)  (the bearings' reactions +-M/L tilt the supports' line),
    # and phi = beta + i alpha obeys Jd phi'' - i Omega Jp phi' + k_t phi = 0 (rubdyn's
    # convention, G[dx, dy] = +Jp), so phi = e^{i w t} with
    #   w_f = (Omega Jp + sqrt(Omega^2 Jp^2 + 4 Jd k_t)) / (2 Jd)   forward (with the spin),
    #   w_b = (-Omega Jp + sqrt(...)) / (2 Jd)                      backward,
    # w_f -> Omega Jp / Jd and w_b -> 0 as Omega grows. The script's matrices with the shaft's
    # mass left out are condensed on the disc's node (static condensation, exact for a massless
    # shaft: the Hermite cubics are the exact static solution), so only round-off is left:
    # 1e-15 measured, 1e-12 allowed. The frequencies alone do not see the sign of G (G -> -G
    # swaps the directions, not the values): the whirl direction of each mode's eigenvector is
    # checked too.
    r, m, Jp, Jd, kb = disc_scene(ne)
    kt = 1.0 / (L / (12 * E * I) + 2.0 / (kb * L * L))
    master = list(r.dofs(ne // 2))
    slave = [i for i in range(r.n) if i not in master]
    K = r.K
    Kc = K[np.ix_(master, master)] - K[np.ix_(master, slave)] @ np.linalg.solve(
        K[np.ix_(slave, slave)], K[np.ix_(slave, master)])
    assert abs(Kc[2, 2] / kt - 1.0) < 1e-12 and abs(Kc[0, 2]) < 1e-9 * kt
    Md = (r.M - r.M_shaft - r.M_rotary)[np.ix_(master, master)]
    Gd = (r.G - r.G_shaft)[np.ix_(master, master)]
    for Om in (0.0, 500.0, 5000.0, 5e5):
        root = math.sqrt((Om * Jp) ** 2 + 4 * Jd * kt)
        wf, wb = (Om * Jp + root) / (2 * Jd), (-Om * Jp + root) / (2 * Jd)
        Z = np.zeros((4, 4))
        lam, V = np.linalg.eig(np.block([[Z, np.eye(4)],
                                         [-np.linalg.solve(Md, Kc), -Om * np.linalg.solve(Md, Gd)]]))
        tilt = [(l.imag, v) for l, v in zip(lam, V.T)
                if l.imag > 0 and abs(v[0]) + abs(v[1]) < 1e-9 * (abs(v[2]) + abs(v[3]))]
        if Om == 0.0:
            assert len(tilt) == 2 and all(abs(w / wf - 1) < 1e-12 for w, _ in tilt)
            continue
        assert len(tilt) == 2
        for w, v in tilt:
            forward = abs(v[2] + 1j * v[3]) > abs(v[2] - 1j * v[3])
            assert abs(w / (wf if forward else wb) - 1.0) < 1e-12, (Om, w, wf, wb, forward)
        # one of each, the forward one above
        (w1, v1), (w2, v2) = sorted(tilt, key=lambda t: t[0])
        assert abs(v2[2] + 1j * v2[3]) > abs(v2[2] - 1j * v2[3]) > 0
        assert abs(v1[2] - 1j * v1[3]) > abs(v1[2] + 1j * v1[3])
    # the limits: at 5e5 rad/s, w_f within 1e-3 of Omega Jp / Jd (the term 4 Jd k_t / (Om Jp)^2
    # left is 8e-4 there, measured from the closed form itself)
    Om = 5e5
    wf = (Om * Jp + math.sqrt((Om * Jp) ** 2 + 4 * Jd * kt)) / (2 * Jd)
    assert abs(wf / (Om * Jp / Jd) - 1.0) < 1e-3


def test_the_disc_convention_reproduces_the_rigid_rotor_gyroscopic_matrix():
    # rubdyn's rigid rotor (docs/models.md, 5.1; scripts/make-paper-matrices.py) in coordinates
    # (x_b, y_b, x_r, y_r) has G(x_b, y_b) = H, G(x_b, y_r) = -H, G(y_b, x_r) = H,
    # G(x_r, y_r) = H with H = Jp / l^2. A disc Jp in (x, y, beta, alpha) with
    # G[beta, alpha] = +Jp, beta = (x_r - x_b) / l, alpha = (y_r - y_b) / l, written in those
    # coordinates (T^T G T) must be that matrix exactly (the same numbers, one rounding each).
    mp = load_script("make_paper_matrices", "make-paper-matrices.py")
    with open(os.path.join(ROOT, "cases", "reference.toml"), "rb") as f:
        case = tomllib.load(f)
    _, _, _, G_rigid, _ = mp.matrices(case)
    Jp = case["rotor"]["Jp"]
    l = case["rotor"]["L"] - case["rotor"]["delta"]
    Gd = np.zeros((4, 4))  # (x, y, beta, alpha) at any point of the rigid rotor
    Gd[2, 3], Gd[3, 2] = Jp, -Jp
    T = np.zeros((4, 4))  # (x, y, beta, alpha) = T (x_b, y_b, x_r, y_r), x, y those of B
    T[0, 0] = T[1, 1] = 1.0
    T[2, 0], T[2, 2] = -1.0 / l, 1.0 / l
    T[3, 1], T[3, 3] = -1.0 / l, 1.0 / l
    np.testing.assert_allclose(T.T @ Gd @ T, G_rigid, rtol=1e-14, atol=0.0)
    # and the sign matters: the opposite convention is not it
    assert not np.allclose(-T.T @ Gd @ T, G_rigid)


def test_element_gyroscopic_matrix_is_the_rotary_inertia_pattern_times_two():
    # G[x-plane dofs, y-plane dofs] = rho Ip / (30 L) R with Ip = 2 I: the element's x-y block of G
    # is twice its rotary-inertia block (the same shape integral of N'^T N'), the y-x block its
    # negative, and nothing within a plane
    r = fe.build(shaft_only(), 3)
    xp = [i for i in range(r.n) if i % 4 in (0, 2)]
    yp = [i for i in range(r.n) if i % 4 in (1, 3)]
    np.testing.assert_allclose(r.G_shaft[np.ix_(xp, yp)], 2.0 * r.M_rotary[np.ix_(xp, xp)],
                               rtol=1e-15, atol=0.0)
    np.testing.assert_array_equal(r.G_shaft[np.ix_(yp, xp)], -r.G_shaft[np.ix_(xp, yp)])
    assert not r.G_shaft[np.ix_(xp, xp)].any() and not r.G_shaft[np.ix_(yp, yp)].any()


# ---- the reference scene ---------------------------------------------------------------------

def scene(ne=None):
    with open(os.path.join(ROOT, "cases", "fe-runup", "rotor.toml"), "rb") as f:
        return fe.build(tomllib.load(f), ne)


def test_reference_scene_reproduces_the_issues_frequencies():
    # Issue 32's own calculation (not the paper's): the rotor at rest, without its seal ring,
    # first two critical speeds about 35 and 136 Hz; highest mode about 42, 109 and 244 kHz with
    # 12, 24 and 48 elements. The issue gives them rounded to the unit shown, so each must lie
    # within half that unit (0.5 Hz, 0.5 kHz). Measured: 35.005, 135.820 Hz; 41.67, 109.05,
    # 244.23 kHz (505.6 kHz with 96 elements).
    for ne, n, top_khz in ((12, 52, 42.0), (24, 100, 109.0), (48, 196, 244.0), (96, 388, None)):
        r = scene(ne)
        assert r.n == n
        f, _ = whirl_frequencies(r.M, r.G, r.K, 0.0)  # (isotropic: each mode is double)
        assert abs(f[0] - 35.0) < 0.5 and abs(f[1] - 136.0) < 0.5, (ne, f[:4])
        if top_khz is not None:
            assert abs(f[-1] / 1e3 - top_khz) < 0.5, (ne, f[-1])


def test_committed_matrices_are_the_scripts_and_banded():
    # cases/fe-runup/*.npy and cases/fe-two-seal/*.npy are what the script writes today (a
    # change of the script without regenerating them fails here), with bandwidth 7
    for name in ("fe-runup", "fe-two-seal"):
        folder = os.path.join(ROOT, "cases", name)
        with open(os.path.join(folder, "rotor.toml"), "rb") as f:
            r = fe.build(tomllib.load(f))
        for k, a in (("M", r.M), ("C", r.C), ("K", r.K), ("G", r.G), ("f0", r.f0)):
            np.testing.assert_array_equal(np.load(os.path.join(folder, k + ".npy")), a,
                                          err_msg=f"{name}/{k}.npy")
        rows, cols = np.nonzero(np.abs(r.M) + np.abs(r.C) + np.abs(r.K) + np.abs(r.G))
        assert np.max(np.abs(rows - cols)) == 7


# ---- rubdyn campbell against the eigenvalues of the same files ---------------------------------

def whirl_frequencies(M, G, K, omega):
    """Forward and backward frequencies [Hz] of an isotropic rotor whose coordinates pair as
    (x-plane, y-plane) = (even, odd) indices: with z = x + i y the system is
    Mp z'' - i Omega Gp z' + Kp z = 0 (Mp, Kp the x-plane blocks, Gp = G[x, y]), so
    z = Z e^{i w t}, (Kp + w Omega Gp - w^2 Mp) Z = 0: w > 0 forward (with the spin), w < 0
    backward. A method of its own (half the size, the direction from the sign of w): rubdyn
    labels the real first-order form's modes by their whirl energies. Solved as the standard
    eigenproblem of [[0, I], [Mp^-1 Kp, Omega Mp^-1 Gp]] on (Z, w Z), which LAPACK balances: the
    generalised form (scipy.linalg.eigvals(A, B)) is not balanced and loses 1e-7 of the lowest
    frequency to the spread of the slopes' and deflections' scales here."""
    x, y = np.arange(0, M.shape[0], 2), np.arange(1, M.shape[0], 2)
    Mp, Kp, Gp = M[np.ix_(x, x)], K[np.ix_(x, x)], G[np.ix_(x, y)]
    # the same plane blocks in y (isotropy), and no x-y coupling but G's
    assert np.array_equal(M[np.ix_(y, y)], Mp) and np.array_equal(K[np.ix_(y, y)], Kp)
    assert not M[np.ix_(x, y)].any() and not K[np.ix_(x, y)].any()
    assert np.array_equal(G[np.ix_(y, x)], -Gp.T)
    m = len(x)
    w = np.linalg.eigvals(np.block([[np.zeros((m, m)), np.eye(m)],
                                    [np.linalg.solve(Mp, Kp), omega * np.linalg.solve(Mp, Gp)]]))
    assert np.all(np.abs(w.imag) <= 1e-9 * np.abs(w)), "undamped: real frequencies"
    w = w.real
    return np.sort(w[w > 0]) / (2 * math.pi), np.sort(-w[w < 0]) / (2 * math.pi)


@needs_cli
def test_rubdyn_campbell_matches_the_eigenvalues_of_the_files():
    # `rubdyn campbell cases/fe-runup.toml` (the stator ring tied to the seal node: its mass and
    # spring added on x6, y6; undamped) against whirl_frequencies() of the same .npy files with
    # the same ring added, at 6 speeds from 0 to 10x omega_lim (so that the gyroscopic split is
    # large), all 26 forward and 26 backward modes. Both sides solve non-symmetric eigenproblems
    # whose eigenvalues spread over 35 Hz to 42 kHz: round-off ~1e-16 of the largest, i.e.
    # 1e-16 * 42e3 / 35 ~ 1e-13 relative on the lowest, times the conditioning of the
    # (non-normal) first-order forms; measured 1.2e-12 at most, 1e-10 allowed. A label swapped
    # between directions (a sign error in G or in the labels) is off by the split, 1e-3 to 1
    # relative; a matrix read or tied differently, by far more than 1e-10.
    case = os.path.join(ROOT, "cases", "fe-runup.toml")
    with open(case, "rb") as f:
        c = tomllib.load(f)
    folder = os.path.join(ROOT, "cases")
    M, G, K = (np.load(os.path.join(folder, c["rotor"][k])) for k in ("M", "G", "K"))
    ix, iy = c["contact_node"]["x"], c["contact_node"]["y"]
    for i in (ix, iy):
        M[i, i] += c["stator"]["mass"]
        K[i, i] += c["stator"]["k"]
    omax = 10 * c["run"]["omega_lim"]
    with tempfile.TemporaryDirectory() as out:
        p = subprocess.run([RUBDYN, "campbell", case, "--out", out, "--points", "6",
                            "--omega-max", repr(omax)], capture_output=True, text=True)
        assert p.returncode == 0, p.stdout + p.stderr
        with open(os.path.join(out, "campbell.csv")) as f:
            rows = list(csv.DictReader(f))
    assert len(rows) == 6
    nn = M.shape[0] // 2
    worst = 0.0
    for row in rows:
        om = float(row["omega_rad_s"])
        fw, bw = whirl_frequencies(M, G, K, om)
        assert len(fw) == nn and len(bw) == nn
        for k in range(nn):
            for lab, ref in ((f"f{k + 1}f", fw[k]), (f"f{k + 1}b", bw[k])):
                err = abs(float(row[lab]) / ref - 1.0)
                worst = max(worst, err)
                assert err < 1e-10, (om, lab, float(row[lab]), ref)
    # the gyroscopic split is there to be seen: the first pair at 10 omega_lim
    fw, bw = whirl_frequencies(M, G, K, omax)
    assert fw[0] / bw[0] - 1.0 > 1e-3
    print(f"largest relative difference {worst:.2e}")


# ---- the committed cases run with both solver families -----------------------------------------

def seal_orbit(folder, node, dt=1e-4):
    """t and the seal node's (x, y) on the output grid k dt (the event solver also writes rows at
    its events; of two rows at one time, the last: after the event)."""
    d = np.genfromtxt(os.path.join(folder, "timeseries.csv"), delimiter=",", names=True)
    keep = np.r_[d["t"][1:] != d["t"][:-1], True]
    keep &= np.abs(d["t"] / dt - np.round(d["t"] / dt)) < 1e-6
    d = d[keep]
    return d["t"], d[f"x{node}"], d[f"y{node}"]


def events(folder):
    with open(os.path.join(folder, "events.csv")) as f:
        return list(csv.DictReader(f))


def run(case, out, *args):
    p = subprocess.run([RUBDYN, "run", case, "--out", out, "--quiet", *args],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr
    with open(os.path.join(out, "summary.json")) as f:
        assert '"complete": true' in f.read()


@needs_cli
@pytest.mark.parametrize("name,t_end,impacts,first", [
    # the run-up (0.2 s, measured: impacts at 0.10708, 0.14485, 0.15353 s, two lift-offs)
    ("fe-runup", 0.2, {"1": 3}, 0.107079),
    # two seals, up to the first impacts at both (0.10717 s at seal 1, 0.11536 s at seal 2)
    ("fe-two-seal", 0.12, {"1": 1, "2": 2}, 0.107170)])
def test_committed_case_runs_with_event_and_moreau_jean(name, t_end, impacts, first):
    # The case as committed (event solver, BDF, rtol 1e-8, atol 1e-13) and Moreau-Jean at
    # h = 1e-5: both complete; the event run's impacts per seal and its first impact time are
    # those measured when the case was made (an event sequence is decided by the contact law and
    # the tolerances: a change of either shows here; the first impact time to 1e-6 s, the rtol
    # 1e-8 and 1e-10 runs agree on it to 1e-12 s), and Moreau-Jean's seal orbit stays within
    # 5e-5 m of the event run's (first order in h: measured 1.3e-5 m at h = 1e-5 and 1.4e-6 m at
    # 1e-6 on fe-runup over 0.2 s; a third of the gap). Rubbing with the wrong sign of a contact
    # force or a wrong seal node is off by the gap itself, 1.5e-4 m.
    case = os.path.join(ROOT, "cases", name + ".toml")
    with open(case, "rb") as f:
        c = tomllib.load(f)
    node = (c["contact_node"][0] if isinstance(c["contact_node"], list) else c["contact_node"])["x"] // 4
    with tempfile.TemporaryDirectory() as tmp:
        ev, mj = os.path.join(tmp, "event"), os.path.join(tmp, "mj")
        run(case, ev, "--t-end", repr(t_end))
        run(case, mj, "--t-end", repr(t_end), "--solver", "mj", "--h", "1e-5")
        evs = events(ev)
        hits = [e for e in evs if e["kind"] == "impact"]
        per = {}
        for e in hits:
            k = e.get("contact", "1") or "1"
            per[k] = per.get(k, 0) + 1
        assert per == impacts, per
        assert abs(float(hits[0]["t"]) - first) < 1e-6, hits[0]["t"]
        te, xe, ye = seal_orbit(ev, node)
        tm, xm, ym = seal_orbit(mj, node)
        assert np.allclose(te, tm, rtol=0, atol=1e-9)
        err = np.max(np.hypot(xe - xm, ye - ym))
        assert 0.0 < err < 5e-5, err


# ---- [reduction] through the CLI ---------------------------------------------------------------

@needs_cli
def test_a_reduced_run_writes_its_model_and_bad_input_exits_2():
    # rubdyn run with a Craig-Bampton reduction (20 modes) of cases/fe-runup.toml: the output
    # folder holds the reduced matrices, the basis and the modes; the reduced matrices are
    # T^T A T of the case's files (1e-14 of the largest entry: one product's round-off), G_r
    # skew-symmetric to the bit, T's rows at the seal unit rows, timeseries.csv's columns the
    # reduced coordinates, summary.json's "model" says what was reduced. Bad [reduction] values
    # exit 2 naming their key, nothing written. A run without reduction into the same folder
    # removes the reduced files (they would describe another model).
    import json
    case = os.path.join(ROOT, "cases", "fe-runup.toml")
    with open(case, "rb") as f:
        c = tomllib.load(f)
    folder = os.path.join(ROOT, "cases")
    full = {k: np.load(os.path.join(folder, c["rotor"][k])) for k in ("M", "C", "K", "G", "f0")}
    sets = ["--set", "reduction.method=craig-bampton", "--set", "reduction.modes=20"]
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run")
        run(case, out, "--t-end", "0.01", *sets)
        T = np.load(os.path.join(out, "reduced_T.npy"))
        assert T.shape == (52, 22)
        for k in ("M", "C", "K", "G"):
            r = np.load(os.path.join(out, f"reduced_{k}.npy"))
            np.testing.assert_allclose(r, T.T @ full[k] @ T, rtol=0,
                                       atol=1e-14 * np.abs(r).max() if r.any() else 0.0)
        np.testing.assert_array_equal(np.load(os.path.join(out, "reduced_G.npy")),
                                      -np.load(os.path.join(out, "reduced_G.npy")).T)
        assert np.array_equal(T[24], np.eye(22)[0]) and np.array_equal(T[25], np.eye(22)[1])
        assert np.load(os.path.join(out, "reduced_modes.npy")).shape == (52, 20)
        with open(os.path.join(out, "reduction.json")) as f:
            red = json.load(f)
        assert red["method"] == "craig-bampton" and red["reduced_size"] == 22
        assert red["physical"] == {"x6": 24, "y6": 25} and len(red["modes_hz"]) == 20
        with open(os.path.join(out, "timeseries.csv")) as f:
            header = f.readline().strip().split(",")
        assert header[1:23] == red["coordinates"]
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        assert summary["model"].startswith("Craig-Bampton reduction to 20 modes: 52 -> 22")
        # bad input: exit 2, the key named, nothing written
        bad = os.path.join(tmp, "bad")
        for value, key in (("reduction.modes=60", "reduction.modes"),
                           ("reduction.cutoff=100", "reduction.cutoff")):
            p = subprocess.run([RUBDYN, "run", case, "--out", bad, "--set",
                                "reduction.method=craig-bampton", "--set", value],
                               capture_output=True, text=True)
            assert p.returncode == 2 and key in p.stderr, p.stderr
            assert not os.path.exists(bad)
        # the unreduced model into the same folder: the reduced files go
        run(case, out, "--t-end", "0.01")
        assert not any(n.startswith("reduced_") or n == "reduction.json" for n in os.listdir(out))


# ---- output.modes: the rotor's modal coordinates as output columns -----------------------------

def plane_modes(M, K):
    """An isotropic rotor's free modes computed here, independently of rubdyn: scipy's eigh of
    each plane's (K, M) (x: even coordinates, y: odd), mass-normalised by eigh, each with its
    largest entry positive; n x n shapes in rubdyn's order (the x-plane then the y-plane mode of
    each pair) and their frequencies [Hz]."""
    n = M.shape[0]
    x = np.arange(0, n, 2)
    w2, V = sl.eigh(K[np.ix_(x, x)], M[np.ix_(x, x)])
    shapes, f = np.zeros((n, n)), np.repeat(np.sqrt(w2) / (2 * math.pi), 2)
    for j in range(V.shape[1]):
        v = V[:, j] * np.sign(V[np.argmax(np.abs(V[:, j])), j])
        shapes[x, 2 * j] = v
        shapes[x + 1, 2 * j + 1] = v
    return shapes, f


def case_rotor(case):
    """A committed matrices case's M, K (from its files) and coordinate names."""
    with open(case, "rb") as f:
        c = tomllib.load(f)
    folder = os.path.dirname(case)
    M, K = (np.load(os.path.join(folder, c["rotor"][k])) for k in ("M", "K"))
    return M, K, [s.strip() for s in c["rotor"]["coordinates"].split(",")]


def check_modes_files(folder, M, K, count):
    """output_modes.json's frequencies and output_modes.npy's shapes of a run against scipy's
    (plane_modes of M, K): 1e-9 relative for the frequencies (two eigensolvers of a
    symmetric-definite pencil agree to about eps times the spread of its eigenvalues, 1e-7 Hz^2 /
    f^2 of the lowest: measured 1.5e-11), 1e-10 of the largest entry for the shapes
    (eigenvectors are determined to eps ||A|| / gap, the first pairs' gaps are wide: measured
    1e-12). Returns output_modes.json and the written shapes."""
    import json
    with open(os.path.join(folder, "output_modes.json")) as fj:
        om = json.load(fj)
    written = np.load(os.path.join(folder, "output_modes.npy"))
    shapes, f = plane_modes(M, K)
    assert om["count"] == count and written.shape == (M.shape[0], count)
    np.testing.assert_allclose(om["frequencies_hz"], f[:count], rtol=1e-9, atol=0)
    np.testing.assert_allclose(written, shapes[:, :count], rtol=0,
                               atol=1e-10 * np.abs(shapes[:, :count]).max())
    return om, written


def read_columns(folder):
    """timeseries.csv's header and its rows as text (the bytes each column wrote)."""
    with open(os.path.join(folder, "timeseries.csv")) as f:
        rows = [line.rstrip("\n").split(",") for line in f]
    return rows[0], rows[1:]


def check_modal_columns(folder, names, Mq, shapes, count):
    """mode<k> and vmode<k> of timeseries.csv against phi_k^T M q and phi_k^T M v of the
    coordinates q (names: q's column names, in q's order; Mq: the M of q) written beside them,
    with the shapes given. The coordinates are written exactly (the shortest text that reads back
    to the same double), so the only difference is the order of the n-term sums: each within
    n eps sum_i |(M phi)_i q_i| (the rounding bound of a sum of n products), the tolerance used
    (times 2: rubdyn rounds its sum, numpy its own)."""
    header, rows = read_columns(folder)
    num = [j for j, h in enumerate(header) if not h.startswith("phase")]  # (words: free, ...)
    data = np.full((len(rows), len(header)), np.nan)
    data[:, num] = [[float(r[j]) for j in num] for r in rows]
    col = {h: i for i, h in enumerate(header)}
    q = data[:, [col[nm] for nm in names]]
    v = data[:, [col["v" + nm] for nm in names]]
    Mphi = Mq @ shapes[:, :count]
    eps = np.finfo(float).eps
    for k in range(count):
        for pre, x in (("mode", q), ("vmode", v)):
            got = data[:, col[f"{pre}{k + 1}"]]
            ref = x @ Mphi[:, k]
            bound = 2 * len(names) * eps * (np.abs(x) @ np.abs(Mphi[:, k]))
            assert np.all(np.abs(got - ref) <= bound), (pre, k, np.max(np.abs(got - ref)))
    return header, rows, data, col


@needs_cli
def test_output_modes_writes_the_rotors_modal_amplitudes():
    # cases/fe-runup.toml (52 coordinates, isotropic, prescribed spin) over 0.15 s (its first
    # impact at 0.10708 s, so the rub is in the run) with output.modes = 4: the files' frequencies
    # and shapes are scipy's (check_modes_files), the columns are the written shapes' amplitudes
    # of the written coordinates (check_modal_columns) and scipy's shapes' to 1e-10 of the
    # largest sum of |terms| (measured 7e-13), and every column of the run without output.modes
    # is the same text with it: the modes are output only.
    case = os.path.join(ROOT, "cases", "fe-runup.toml")
    M, K, names = case_rotor(case)
    shapes, _ = plane_modes(M, K)
    base = ["--t-end", "0.15", "--set", "output.coordinates=\"all\""]
    with tempfile.TemporaryDirectory() as tmp:
        plain, modal = os.path.join(tmp, "plain"), os.path.join(tmp, "modal")
        run(case, plain, *base)
        run(case, modal, *base, "--set", "output.modes=4")
        om, written = check_modes_files(modal, M, K, 4)
        assert om["model"] == "full" and om["size"] == 52
        assert om["planes"] == ["x", "y", "x", "y"]
        header, rows, data, col = check_modal_columns(modal, names, M, written, 4)
        # against scipy's own shapes too
        for k in range(4):
            ref = data[:, [col[nm] for nm in names]] @ (M @ shapes[:, k])
            scale = np.abs(data[:, [col[nm] for nm in names]]) @ np.abs(M @ shapes[:, k])
            assert np.all(np.abs(data[:, col[f"mode{k + 1}"]] - ref) <= 1e-10 * scale.max())
        # after the coordinates' rates and the prescribed spin's observables, before the contacts
        i = header.index("drive_torque")
        assert header[i - 2:i + 9] == ["theta", "omega", "drive_torque", "mode1", "mode2",
                                       "mode3", "mode4", "vmode1", "vmode2", "vmode3", "vmode4"]
        assert any(e["kind"] == "impact" for e in events(modal))  # (the rub is in the run)
        ph, prows = read_columns(plain)
        assert [h for h in header if not h.startswith(("mode", "vmode"))] == ph
        keep = [j for j, h in enumerate(header) if not h.startswith(("mode", "vmode"))]
        assert len(prows) == len(rows)
        for a, b in zip(prows, rows):
            assert a == [b[j] for j in keep]
        for name in ("events.csv", "case.resolved.toml"):
            with open(os.path.join(plain, name)) as fa, open(os.path.join(modal, name)) as fb:
                a, b = fa.read(), fb.read()
            if name == "events.csv":
                assert a == b
            else:  # the key's one line (and the folders' names)
                a, b = (x.replace(d, "D") for x, d in ((a, plain), (b, modal)))
                assert b.replace("modes = 4\n", "") == a.replace("modes = 0\n", "")
                assert "\nmodes = 4\n" in b and "\nmodes = 0\n" in a
        # a run without modes into the same folder removes the modes' files
        run(case, modal, *base)
        assert not any(n.startswith("output_modes") for n in os.listdir(modal))


@needs_cli
def test_output_modes_of_a_reduced_and_of_a_torque_driven_rotor():
    # A Craig-Bampton reduced fe-runup (8 modes, 10 coordinates p) with output.modes = 4: the
    # modes are the reduced rotor's (of its M_r, K_r: the files say "reduced", size 10), their
    # frequencies the full rotor's from above (Rayleigh-Ritz: a subspace's), within 1e-4 relative
    # (measured 2.2e-5: the static constraint modes carry the seal's flexibility), the reduced
    # rotor's own modes are scipy's of reduced_M, reduced_K (check_modes_files), and the columns
    # the written shapes' amplitudes of the reduced coordinates p with M_r.
    # cases/fe-two-seal.toml (torque-driven: the columns come from the matrices model itself, no
    # prescribed spin) with output.modes = 2 the same against its M.
    import json
    case = os.path.join(ROOT, "cases", "fe-runup.toml")
    M, K, _ = case_rotor(case)
    _, f_full = plane_modes(M, K)
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cb")
        run(case, out, "--t-end", "0.05", "--set", "reduction.method=\"craig-bampton\"",
            "--set", "reduction.modes=8", "--set", "output.modes=4")
        Mr, Kr = (np.load(os.path.join(out, f"reduced_{k}.npy")) for k in ("M", "K"))
        om, written = check_modes_files(out, Mr, Kr, 4)
        with open(os.path.join(out, "reduction.json")) as fj:
            red = json.load(fj)
        assert om["model"] == "reduced" and om["size"] == 10
        rel = np.abs(np.array(om["frequencies_hz"]) / f_full[:4] - 1.0)
        print(f"reduced (CB 8) against full frequencies: relative {rel.max():.2e}")
        assert np.all(np.array(om["frequencies_hz"]) >= f_full[:4] * (1 - 1e-12))
        assert rel.max() < 1e-4, rel
        check_modal_columns(out, red["coordinates"], Mr, written, 4)
        # the torque-driven two-seal rotor
        case2 = os.path.join(ROOT, "cases", "fe-two-seal.toml")
        M2, _, names2 = case_rotor(case2)
        out2 = os.path.join(tmp, "two")
        run(case2, out2, "--t-end", "0.02", "--set", "output.modes=2")
        header, _, _, _ = check_modal_columns(out2, names2, M2,
                                              np.load(os.path.join(out2, "output_modes.npy")), 2)
        # right after the coordinates' rates (t, N coordinates, N rates): no other observables
        i = header.index("mode1")
        assert i % 2 == 1 and header[(i - 1) // 2 + 1] == "v" + header[1]
        assert header[i:i + 4] == ["mode1", "mode2", "vmode1", "vmode2"]


@needs_cli
def test_output_modes_bad_input_exits_2_naming_the_key():
    # Each refusal exits 2 with output.modes and its rule in the message, and writes nothing:
    # negative; more than the model's coordinates (52 full, 10 reduced); odd for an isotropic
    # rotor; on a model that is not "matrices".
    case = os.path.join(ROOT, "cases", "fe-runup.toml")
    cb = ["--set", "reduction.method=\"craig-bampton\"", "--set", "reduction.modes=8"]
    with tempfile.TemporaryDirectory() as tmp:
        bad = os.path.join(tmp, "bad")
        for sets, rule in ((["output.modes=-2"], "must be >= 0"),
                           (["output.modes=54"], "at most n = 52"),
                           (["output.modes=3"], "must be even"),
                           (cb[1::2] + ["output.modes=12"], "at most n = 10")):
            args = [a for s in sets for a in ("--set", s)]
            p = subprocess.run([RUBDYN, "run", case, "--out", bad, *args],
                               capture_output=True, text=True)
            assert p.returncode == 2 and "output.modes" in p.stderr and rule in p.stderr, \
                (sets, p.stderr)
            assert "fe-runup.toml" in p.stderr or "--set" in p.stderr, p.stderr
            assert not os.path.exists(bad)
        p = subprocess.run([RUBDYN, "run", os.path.join(ROOT, "cases", "jeffcott.toml"), "--out",
                            bad, "--set", "output.modes=2"], capture_output=True, text=True)
        assert p.returncode == 2 and "output.modes" in p.stderr and "matrices" in p.stderr, \
            p.stderr
        assert not os.path.exists(bad)
