#!/usr/bin/python3
"""Writes a flexible rotor's matrices (M, C, K, G, f0 as .npy) and a `kind = "matrices"` case file
from a short description: an Euler-Bernoulli shaft of beam elements, rigid discs, isotropic
bearings, seals (the contact nodes) and an unbalance. docs/fe-rotors.md describes the conventions
and the description format; cases/fe-runup/rotor.toml is an example.

    scripts/make-fe-rotor.py cases/fe-runup/rotor.toml                 # -> cases/fe-runup.toml
    scripts/make-fe-rotor.py cases/fe-runup/rotor.toml --elements 48 \\
        --case out/fe48/fe-runup-48.toml --matrices out/fe48/matrices   # the same rotor, finer

Coordinates: 4 per node, node by node from z = 0: q = (x_0, y_0, dx_0, dy_0, x_1, ...) with
dx = beta = dx/dz and dy = alpha = dy/dz (slopes, rad), so that the matrices are banded
(bandwidth 7). The element matrices of one bending plane, dofs (w1, w1', w2, w2'), are the
textbook Hermite-cubic ones (stiffness EI/L^3 [...], consistent mass rho A L / 420 [...], rotary
inertia rho I / (30 L) R); with slopes as the rotation dofs both planes use the same matrices.
The gyroscopic matrix follows rubdyn's convention (docs/models.md, section 5): the kinetic
energy contains -1/2 theta' q^T G q', i.e. G[dx, dy] = +Jp and G[dy, dx] = -Jp for a disc, and
for an element G[x-plane dofs, y-plane dofs] = rho Ip / (30 L) R, its negative transpose below
(Ip = 2 I). The motion is written about the static equilibrium (f0 = 0) unless the description
sets `gravity`, in which case f0 is the weight (the shaft's consistent load and the discs').

Importable (importlib) for tests: build(description, elements=None) returns a FeRotor.
"""
import argparse
import math
import os
import pathlib
import sys
import tomllib

import numpy as np

# ---- element and assembly ------------------------------------------------------------------


def beam_stiffness(E, I, L):
    """Euler-Bernoulli bending stiffness of one plane, dofs (w1, w1', w2, w2')."""
    return E * I / L**3 * np.array([[12.0, 6 * L, -12.0, 6 * L],
                                    [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                                    [-12.0, -6 * L, 12.0, -6 * L],
                                    [6 * L, 2 * L * L, -6 * L, 4 * L * L]])


def beam_mass(rho, A, L):
    """Consistent (translational) mass of one plane, dofs (w1, w1', w2, w2')."""
    return rho * A * L / 420.0 * np.array([[156.0, 22 * L, 54.0, -13 * L],
                                           [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                           [54.0, 13 * L, 156.0, -22 * L],
                                           [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])


def beam_R(L):
    """30 L times the integral of N'^T N' over the element: the rotary-inertia and gyroscopic
    shape matrix, dofs (w1, w1', w2, w2')."""
    return np.array([[36.0, 3 * L, -36.0, 3 * L],
                     [3 * L, 4 * L * L, -3 * L, -L * L],
                     [-36.0, -3 * L, 36.0, -3 * L],
                     [3 * L, -L * L, -3 * L, 4 * L * L]])


def beam_weight(rho, A, L, g):
    """Consistent load of the element's weight rho A g along -Y, dofs (w1, w1', w2, w2')."""
    w = rho * A * g
    return -w * np.array([L / 2, L * L / 12, L / 2, -L * L / 12])


class FeRotor:
    """The assembled rotor: the matrices, the nodes' z, the contact nodes and the case's keys."""

    def __init__(self, n_nodes, z):
        self.nodes = n_nodes
        self.z = z
        n = 4 * n_nodes
        self.n = n
        self.M = np.zeros((n, n))
        self.C = np.zeros((n, n))
        self.K = np.zeros((n, n))
        self.G = np.zeros((n, n))
        self.f0 = np.zeros(n)
        # the shaft's own parts (tests: the beam alone, the discs alone)
        self.K_shaft = np.zeros((n, n))
        self.M_shaft = np.zeros((n, n))      # consistent translational mass
        self.M_rotary = np.zeros((n, n))     # rotary inertia
        self.G_shaft = np.zeros((n, n))
        self.Jp = 0.0          # the rotor's polar inertia: shaft + discs
        self.seals = []        # (node, seal table), the unbalance's seal first
        self.unbalance = None  # (node, value, phase)

    def names(self):
        return [f"{c}{i}" for i in range(self.nodes) for c in ("x", "y", "dx", "dy")]

    @staticmethod
    def dofs(node):
        """(x, y, dx, dy) of a node."""
        return 4 * node, 4 * node + 1, 4 * node + 2, 4 * node + 3


def _need(table, key, where, positive=True, allow_zero=False):
    if key not in table:
        sys.exit(f"make-fe-rotor: {where}.{key}: required")
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        sys.exit(f"make-fe-rotor: {where}.{key} = {v!r}: must be a finite number")
    if positive and not (v > 0 or (allow_zero and v == 0)):
        sys.exit(f"make-fe-rotor: {where}.{key} = {v!r}: must be {'>= 0' if allow_zero else '> 0'}")
    return float(v)


def _check_keys(table, allowed, where):
    for k in table:
        if k not in allowed:
            sys.exit(f"make-fe-rotor: {where}.{k}: unknown key (allowed: {', '.join(allowed)})")


def build(desc, elements=None):
    """The FeRotor of a description (the dict of a description file)."""
    _check_keys(desc, ("name", "title", "gravity", "shaft", "disc", "bearing", "seal",
                       "unbalance", "case"), "description")
    sh = desc.get("shaft")
    if not isinstance(sh, dict):
        sys.exit("make-fe-rotor: [shaft]: required")
    _check_keys(sh, ("length", "diameter", "inner_diameter", "E", "rho", "elements",
                     "stiffness_damping"), "shaft")
    Ls = _need(sh, "length", "shaft")
    D = _need(sh, "diameter", "shaft")
    d = float(sh.get("inner_diameter", 0.0))
    if not (0.0 <= d < D):
        sys.exit(f"make-fe-rotor: shaft.inner_diameter = {d!r}: must be in [0, diameter)")
    E = _need(sh, "E", "shaft")
    rho = _need(sh, "rho", "shaft")
    ne = int(elements if elements is not None else sh.get("elements", 12))
    if ne < 1:
        sys.exit(f"make-fe-rotor: elements = {ne}: must be >= 1")
    beta_k = _need(sh, "stiffness_damping", "shaft", allow_zero=True) \
        if "stiffness_damping" in sh else 0.0
    g = float(desc.get("gravity", 0.0))
    if not (g >= 0.0 and math.isfinite(g)):
        sys.exit(f"make-fe-rotor: gravity = {g!r}: must be >= 0")

    A = math.pi * (D * D - d * d) / 4.0
    I = math.pi * (D**4 - d**4) / 64.0
    le = Ls / ne
    r = FeRotor(ne + 1, np.linspace(0.0, Ls, ne + 1))
    ke, me = beam_stiffness(E, I, le), beam_mass(rho, A, le)
    R = beam_R(le)
    mr = rho * I / (30.0 * le) * R        # rotary inertia
    ge = rho * (2.0 * I) / (30.0 * le) * R  # gyroscopic: Ip = 2 I
    fe = beam_weight(rho, A, le, g)
    for e in range(ne):
        xp = [4 * e, 4 * e + 2, 4 * e + 4, 4 * e + 6]  # (x1, dx1, x2, dx2)
        yp = [4 * e + 1, 4 * e + 3, 4 * e + 5, 4 * e + 7]  # (y1, dy1, y2, dy2)
        for p in (xp, yp):
            r.K_shaft[np.ix_(p, p)] += ke
            r.M_shaft[np.ix_(p, p)] += me
            r.M_rotary[np.ix_(p, p)] += mr
        r.G_shaft[np.ix_(xp, yp)] += ge
        r.G_shaft[np.ix_(yp, xp)] -= ge.T
        r.f0[yp] += fe
    r.M += r.M_shaft + r.M_rotary
    r.G += r.G_shaft
    r.Jp = rho * 2.0 * I * Ls

    def node_at(z, where):
        k = z / le
        kr = round(k)
        if not (0 <= kr <= ne) or abs(k - kr) > 1e-9 * max(1.0, abs(k)):
            sys.exit(f"make-fe-rotor: {where}.z = {z!r}: not a node of {ne} elements of "
                     f"{le:g} m on [0, {Ls:g}] m (choose z or the number of elements so that it is)")
        return int(kr)

    for i, t in enumerate(desc.get("disc", [])):
        w = f"disc.{i + 1}"
        _check_keys(t, ("z", "mass", "Jp", "Jd"), w)
        k = node_at(_need(t, "z", w, positive=False), w)
        x, y, dx, dy = r.dofs(k)
        m, jp, jd = _need(t, "mass", w), _need(t, "Jp", w, allow_zero=True), \
            _need(t, "Jd", w, allow_zero=True)
        r.M[x, x] += m
        r.M[y, y] += m
        r.M[dx, dx] += jd
        r.M[dy, dy] += jd
        r.G[dx, dy] += jp
        r.G[dy, dx] -= jp
        r.f0[y] -= m * g
        r.Jp += jp
    bearings = desc.get("bearing", [])
    if not bearings:
        sys.exit("make-fe-rotor: [[bearing]]: at least one (a free rotor has no static equilibrium)")
    for i, t in enumerate(bearings):
        w = f"bearing.{i + 1}"
        _check_keys(t, ("z", "k", "c"), w)
        k = node_at(_need(t, "z", w, positive=False), w)
        x, y, _, _ = r.dofs(k)
        kb, cb = _need(t, "k", w), _need(t, "c", w, allow_zero=True)
        r.K[x, x] += kb
        r.K[y, y] += kb
        r.C[x, x] += cb
        r.C[y, y] += cb
    r.K += r.K_shaft
    r.C += beta_k * r.K_shaft

    seals = desc.get("seal", [])
    if not seals:
        sys.exit("make-fe-rotor: [[seal]]: at least one (a contact node)")
    seal_keys = ("z", "radius", "gap", "mu", "e_n", "e_t", "stator_mass", "stator_k",
                 "stator_c", "stator_rigid")
    taken = set()
    for i, t in enumerate(seals):
        w = f"seal.{i + 1}"
        _check_keys(t, seal_keys, w)
        k = node_at(_need(t, "z", w, positive=False), w)
        if k in taken:
            sys.exit(f"make-fe-rotor: {w}.z: a second seal at node {k}")
        taken.add(k)
        r.seals.append((k, t))
    ub = desc.get("unbalance")
    if ub is not None:
        _check_keys(ub, ("z", "value", "phase"), "unbalance")
        k = node_at(_need(ub, "z", "unbalance", positive=False), "unbalance")
        if k not in taken:
            sys.exit("make-fe-rotor: unbalance.z: must be a seal's node (rubdyn's matrices model "
                     "puts loads.unbalance at its first contact node)")
        r.unbalance = (k, _need(ub, "value", "unbalance", allow_zero=True),
                       float(ub.get("phase", 0.0)))
        r.seals.sort(key=lambda s: s[0] != k)  # the unbalance's seal first (stable otherwise)
    r.gravity = g
    # symmetric and skew to the bit (sums of symmetric blocks are; this only asserts it)
    assert np.array_equal(r.M, r.M.T) and np.array_equal(r.K, r.K.T)
    assert np.array_equal(r.C, r.C.T) and np.array_equal(r.G, -r.G.T)
    return r


# ---- the case file -------------------------------------------------------------------------


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    sys.exit(f"make-fe-rotor: case value {v!r}: only numbers, strings and booleans are copied")


def case_text(desc, r, name, rel, command):
    """The case file of rotor r, its matrices in the folder rel (relative to the case file)."""
    lines = [f"# {desc.get('title', name)}",
             "# Generated by scripts/make-fe-rotor.py (do not edit by hand; edit the description",
             f"# and rerun):  {command}",
             f"# {r.nodes - 1} Euler-Bernoulli elements, n = {r.n} coordinates (x, y, dx = dx/dz, "
             "dy = dy/dz per node,",
             "# node 0 at z = 0); conventions and the description format: docs/fe-rotors.md.",
             "", f'name = "{name}"', "", "[model]", 'kind = "matrices"', "", "[rotor]"]
    for k in ("M", "C", "K", "G", "f0"):
        lines.append(f'{k:2} = "{rel}/{k}.npy"')
    lines.append(f"Jp = {r.Jp!r}   # shaft rho Ip L + the discs' Jp [kg m^2]")
    lines.append(f'coordinates = "{", ".join(r.names())}"')
    lines.append('rotations = "dx*, dy*"   # the slopes (rad): their unit and error weight')
    several = len(r.seals) > 1
    for k, t in r.seals:
        x, y, _, _ = r.dofs(k)
        lines += ["", "[[contact_node]]" if several else "[contact_node]",
                  f"# the seal at node {k}, z = {r.z[k]:.6g} m",
                  f"x = {x}   # x{k}", f"y = {y}   # y{k}",
                  f"radius = {toml_value(float(t['radius']))}",
                  f"gap = {toml_value(float(t['gap']))}"]
        ring = [(key, t[key]) for key in ("stator_rigid", "stator_mass", "stator_k", "stator_c")
                if key in t]
        law = [(key, t[key]) for key in ("mu", "e_n", "e_t") if key in t]
        if several:
            lines += [f"{key} = {toml_value(v)}" for key, v in law + ring]
        else:
            lines += ["", "[stator]"]
            lines += [f"{key.removeprefix('stator_')} = {toml_value(v)}" for key, v in ring]
            lines += ["", "[contact]"] + [f"{key} = {toml_value(v)}" for key, v in law]
    case = dict(desc.get("case", {}))
    loads = dict(case.pop("loads", {}))
    for key in ("gravity", "unbalance", "unbalance_phase"):
        if key in loads:
            sys.exit(f"make-fe-rotor: case.loads.{key}: set by the description "
                     "(gravity, [unbalance]), not in [case.loads]")
    lines += ["", "[loads]",
              f"gravity = {r.gravity!r}   # weighs the rings (and the unbalance); the rotor's "
              "weight is f0" if r.gravity > 0 else
              "gravity = 0.0   # the motion about the static equilibrium: f0 = 0"]
    if r.unbalance is not None:
        lines.append(f"unbalance = {r.unbalance[1]!r}   # at node {r.unbalance[0]} (the first "
                     "contact node)")
        if r.unbalance[2] != 0.0:
            lines.append(f"unbalance_phase = {r.unbalance[2]!r}")
    lines += [f"{k} = {toml_value(v)}" for k, v in loads.items()]
    for sec in ("initial", "run", "solver", "output"):
        if sec in case:
            lines += ["", f"[{sec}]"] + [f"{k} = {toml_value(v)}" for k, v in case.pop(sec).items()]
    if case:
        sys.exit(f"make-fe-rotor: [case]: unknown sections {sorted(case)} (loads, initial, run, "
                 "solver, output)")
    return "\n".join(lines) + "\n"


def write(r, desc, case_path, mdir, name, command):
    mdir.mkdir(parents=True, exist_ok=True)
    case_path.parent.mkdir(parents=True, exist_ok=True)
    for k, a in (("M", r.M), ("C", r.C), ("K", r.K), ("G", r.G), ("f0", r.f0)):
        np.save(mdir / f"{k}.npy", np.ascontiguousarray(a, dtype="<f8"))
    rel = pathlib.Path(os.path.relpath(mdir.resolve(), case_path.parent.resolve())).as_posix()
    case_path.write_text(case_text(desc, r, name, rel, command))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("description", type=pathlib.Path, help="the rotor's description (TOML)")
    ap.add_argument("--elements", type=int, default=None,
                    help="number of shaft elements (default: the description's shaft.elements)")
    ap.add_argument("--case", type=pathlib.Path, default=None,
                    help="the case file to write (default: the description's folder + .toml, "
                         "e.g. cases/fe-runup/rotor.toml -> cases/fe-runup.toml)")
    ap.add_argument("--matrices", type=pathlib.Path, default=None,
                    help="the folder of the .npy files (default: the description's folder)")
    ap.add_argument("--name", default=None, help="the case's name (default: the description's)")
    a = ap.parse_args()
    desc = tomllib.loads(a.description.read_text())
    r = build(desc, a.elements)
    folder = a.description.parent
    case_path = a.case if a.case is not None else folder.parent / (folder.name + ".toml")
    mdir = a.matrices if a.matrices is not None else folder
    name = a.name or desc.get("name", case_path.stem)
    root = pathlib.Path(__file__).resolve().parent.parent

    def shown(p):
        p = p.resolve()
        return p.relative_to(root).as_posix() if p.is_relative_to(root) else str(p)
    cmd = "scripts/make-fe-rotor.py " + shown(a.description)
    if a.elements is not None:
        cmd += f" --elements {a.elements}"
    if a.case is not None:
        cmd += f" --case {shown(a.case)}"
    if a.matrices is not None:
        cmd += f" --matrices {shown(a.matrices)}"
    if a.name is not None:
        cmd += f" --name {a.name}"
    write(r, desc, case_path, mdir, name, cmd)
    print(f"wrote {case_path} and {mdir}/{{M,C,K,G,f0}}.npy: {r.nodes - 1} elements, "
          f"n = {r.n}, {len(r.seals)} contact node(s)")


if __name__ == "__main__":
    main()
