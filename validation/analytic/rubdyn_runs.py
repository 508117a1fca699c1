#!/usr/bin/python3
"""rubdyn against the closed forms of docs/closed-forms.md: the cases, the runs and the
measurements on their output folders, shared by run.py (table.md, approach.png) and by the
ctests of test_runs.py, so that the table and the tests measure the same things the same way.

Every comparison runs `rubdyn run` (the event-driven solver) on cases/jeffcott.toml with the
closed form's parameters written over it into a case text in a scratch folder (the rigid stator
and the prescribed spin drop keys, which --set cannot), started on or near the steady state that
closed_forms.py gives, and reads back timeseries.csv (17 significant digits), events.csv and
summary.json. The parameter sets are those of test_closed_forms.py (RIGID, BLACK_ROLL,
BLACK_WHIP, UNB), where the closed forms themselves are checked.

What is measured, from the samples only:
  Omega      the `omega` column;
  w          the whirl speed phi' of r = z_r - z_s (x_s = y_s = 0 for a rigid stator), from the
             sampled positions and velocities: phi' = Im(conj(r) r') / |r|^2 (every sample), and
             from the polar angle alone: the slope of the unwrapped phi = arg r over a window of
             the output grid (needs |w| dt < pi: checked);
  N, F_T     the `F_N`, `F_T` columns (the contact force of the stator on the rotor, -F_N n +
             F_T t, docs/models.md section 4);
  zeta       the stator's position in the frame of the contact direction, z_s e^{-i phi};
  delta      the angle psi - phi from the contact direction to the unbalance (psi = theta + phi_u);
  powers     drive tau(Omega) Omega, dampers -c_r |z_r'|^2 - c_s |z_s'|^2, friction F_T v_t.
"""
import json
import math
import os
import subprocess
import sys
import time
import tomllib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import closed_forms as cf  # noqa: E402
from test_closed_forms import BLACK_ROLL, BLACK_WHIP, OMEGA_U, RIGID, UNB  # noqa: E402,F401

JEFFCOTT = os.path.join(ROOT, "cases", "jeffcott.toml")
REFERENCE = os.path.join(ROOT, "cases", "reference.toml")

# The solver settings of the comparisons (event-driven, CVODES Adams in every phase): rtol 1e-12
# and atol 1e-15 m on positions (1e-12 m/s on velocities). run.py measures what the default
# (rtol 1e-10, atol 1e-12) and this setting give; the positions are O(1e-4 m), so an atol of
# 1e-14 m or more would dominate rtol |q| there.
TIGHT = {"rtol": 1e-12, "atol": 1e-15}
DEFAULT = {"rtol": 1e-10, "atol": 1e-12}
DT = 1e-4                       # output grid [s] (the cases' own)

# Extra --set overrides of the runs, from the environment: the tests' way of checking that they
# can fail (README.md). RUBDYN_ANALYTIC_PERTURB="key=value;..." applies to every run,
# "NAME:key=value" only to the runs of the case file NAME.toml (e.g. "black_roll_low:...").
PERTURB = [s for s in os.environ.get("RUBDYN_ANALYTIC_PERTURB", "").split(";") if s]


def _perturbations(case):
    name = os.path.splitext(os.path.basename(case))[0]
    out = []
    for s in PERTURB:
        head, _, rest = s.partition(":")
        if rest and "=" not in head:
            if name == head:
                out.append(rest)
        else:
            out.append(s)
    return out


# ---- case texts ---------------------------------------------------------------------------------
def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, int):
        return str(v)
    return repr(float(v))


def case_text(params, name):
    """cases/jeffcott.toml with the case keys of `params` ("section.key": value) written over it.
    A rigid stator drops stator.mass, .k, .c; a prescribed spin drops the torque keys; keys of
    params that are not case keys of a section of the file (none in the sets used) are refused."""
    with open(JEFFCOTT, "rb") as f:
        case = tomllib.load(f)
    case["name"] = name
    for key, val in params.items():
        sec, _, k = key.partition(".")
        if sec not in case:
            case[sec] = {}
        case[sec][k] = val
    if case["stator"].get("rigid"):
        for k in ("mass", "k", "c"):
            case["stator"].pop(k, None)
    if case["loads"].get("spin") == "prescribed":
        for k in ("torque", "torque_law", "torque_free_speed"):
            case["loads"].pop(k, None)
    lines = ["name = %s" % json.dumps(name)]
    for sec, keys in case.items():
        if not isinstance(keys, dict):
            continue
        lines.append("")
        lines.append("[%s]" % sec)
        for k, v in keys.items():
            lines.append("%s = %s" % (k, _toml_value(v)))
    return "\n".join(lines) + "\n"


def write_case(folder, params, name):
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, name + ".toml")
    with open(path, "w") as f:
        f.write(case_text(params, name))
    return path


# ---- runs and their output ---------------------------------------------------------------------
class Output:
    """An output folder read back: summary, columns as float arrays, phases, events."""

    def __init__(self, folder, cmd=None, wall=None, rc=0, stderr=""):
        self.folder, self.cmd, self.process_wall, self.rc, self.stderr = \
            folder, cmd, wall, rc, stderr
        with open(os.path.join(folder, "summary.json")) as f:
            self.summary = json.load(f)
        path = os.path.join(folder, "timeseries.csv")
        with open(path) as f:
            self.names = f.readline().strip().split(",")
        ncol = len(self.names)
        data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=range(ncol - 1), ndmin=2)
        self.col = {n: data[:, i] for i, n in enumerate(self.names[:-1])}
        self.phase = np.loadtxt(path, delimiter=",", skiprows=1, usecols=[ncol - 1], dtype=str,
                                ndmin=1)
        self.t = self.col["t"]
        self.events = []
        with open(os.path.join(folder, "events.csv")) as f:
            head = f.readline().strip().split(",")
            for line in f:
                parts = line.rstrip("\n").split(",")
                self.events.append({"t": float(parts[0]), "kind": parts[1],
                                    "phase_before": parts[2], "phase_after": parts[3]})
        self.head = head
        with open(os.path.join(folder, "case.resolved.toml"), "rb") as f:
            self.case = tomllib.load(f)

    @property
    def wall(self):
        return self.summary.get("wall_seconds", self.process_wall)

    def has(self, name):
        return name in self.col

    def z_r(self):
        return self.col["x_r"] + 1j * self.col["y_r"]

    def v_r(self):
        return self.col["vx_r"] + 1j * self.col["vy_r"]

    def z_s(self):
        if self.has("x_s"):
            return self.col["x_s"] + 1j * self.col["y_s"]
        return np.zeros_like(self.t, dtype=complex)

    def v_s(self):
        if self.has("vx_s"):
            return self.col["vx_s"] + 1j * self.col["vy_s"]
        return np.zeros_like(self.t, dtype=complex)

    def polar(self):
        """phi = arg r and phi' = Im(conj(r) r') / |r|^2, r = z_r - z_s, at every sample."""
        r = self.z_r() - self.z_s()
        rd = self.v_r() - self.v_s()
        with np.errstate(invalid="ignore", divide="ignore"):   # r = 0: a centred start
            return np.angle(r), (np.conj(r) * rd).imag / np.abs(r) ** 2

    def grid(self, dt=DT):
        """Indices of the rows on the output grid t = t_start + k dt (the first row at a time:
        an event on a grid time adds a second row)."""
        t0 = self.t[0]
        k = np.round((self.t - t0) / dt)
        on = np.abs(self.t - t0 - k * dt) <= 1e-9 * dt + 1e-12
        first = np.concatenate([[True], np.diff(self.t) > 0])
        return np.where(on & first)[0]

    def first_event(self, kind, after=-math.inf):
        for e in self.events:
            if e["kind"] == kind and e["t"] > after:
                return e
        return None


def run(rubdyn, case, out, sets=(), t_end=None, rtol=None, atol=None, extra=(), check=True):
    """`rubdyn run case --out out --quiet` with the settings; returns its Output (None with
    check=False when nothing was written)."""
    pert = _perturbations(case)
    for p in list(pert):       # the run options --rtol, --atol win over --set solver.rtol, .atol
        key, _, val = p.partition("=")
        if key in ("solver.rtol", "solver.atol"):
            pert.remove(p)
            if key == "solver.rtol":
                rtol = float(val)
            else:
                atol = float(val)
    cmd = [rubdyn, "run", case, "--out", out, "--quiet"]
    if t_end is not None:
        cmd += ["--t-end", repr(float(t_end))]
    if rtol is not None:
        cmd += ["--rtol", repr(float(rtol))]
    if atol is not None:
        cmd += ["--atol", repr(float(atol))]
    for s in list(sets) + pert:
        cmd += ["--set", s]
    cmd += list(extra)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    if p.returncode not in (0, 3):
        if check:
            raise RuntimeError("%s: exit code %d: %s" % (" ".join(cmd), p.returncode, p.stderr))
        return None
    return Output(out, cmd, wall, p.returncode, p.stderr)


def initial_sets(keys):
    """--set arguments for the initial.* keys of closed_forms (all 17 digits)."""
    return ["%s=%r" % (k, float(v)) for k, v in keys.items()]


def settings(o):
    """The solver settings of a run, as a short text."""
    opt = o.summary["options"]
    return "rtol %g, atol %g, %s / %s" % (opt["rtol"], opt["atol"], opt["free_flight"],
                                            opt["contact_phases"])


# ---- measures ----------------------------------------------------------------------------------
def rel(x, ref):
    return np.abs(np.asarray(x) - ref) / abs(ref)


def time_to_reach(t, e, level):
    """The first sample time after which the relative deviation e stays <= level to the end of
    the run (None if its last sample is above)."""
    e = np.asarray(e)
    above = np.where(~(e <= level))[0]
    if len(above) == 0:
        return float(t[0])
    if above[-1] == len(e) - 1:
        return None
    return float(t[above[-1] + 1])


def polar_slope(o, idx):
    """Mean whirl speed from the polar angle alone over the grid rows idx: (phi_end - phi_start)
    / (t_end - t_start) with phi unwrapped. Returns (slope, largest |phi step| over the rows):
    the unwrapping is unambiguous while every step is well below pi."""
    phi, _ = o.polar()
    t = o.t[idx]
    ph = np.unwrap(phi[idx])
    step = float(np.max(np.abs(np.diff(ph))))
    return (ph[-1] - ph[0]) / (t[-1] - t[0]), step


class Quantity:
    """One compared quantity: the closed form's value, rubdyn's final value, the relative
    deviation's time series (for the approach plot and the times to reach)."""

    def __init__(self, name, closed, measured, t=None, dev=None, note="", unit="",
                 reach=True):
        self.name, self.closed, self.measured = name, closed, measured
        self.t, self.dev, self.note, self.unit, self.reach = t, dev, note, unit, reach
        self.runs = None      # the output folders it was measured on (None: the study's runs)
        if closed is None or measured is None:
            self.rel = None
        elif isinstance(closed, str):
            self.rel = None
        else:
            self.rel = abs(measured - closed) / abs(closed) if closed != 0 else abs(measured)

    def t_reach(self, level):
        if self.t is None or not self.reach:
            return None
        return time_to_reach(self.t, self.dev, level)


class Study:
    """The runs of one closed form and its compared quantities."""

    def __init__(self, key, title):
        self.key, self.title = key, title
        self.quantities = []
        self.runs = []          # (label, Output)
        self.notes = []
        self.status = "ok"

    def add(self, q):
        self.quantities.append(q)
        return q

    def q(self, name):
        return next(x for x in self.quantities if x.name == name)

    def run(self, label, o):
        """Records a run; one that did not complete makes the study's status say why."""
        self.runs.append((label, o))
        if not o.summary.get("complete", False):
            self.status = "incomplete"
            self.notes.append("%s: %s at t = %.6g s: %s" % (
                label, o.summary.get("termination"), o.summary.get("t_reached", float("nan")),
                o.summary.get("message", "")))
        return o


def _stick_rows(o):
    return np.where(o.phase == "stick")[0]


# ---- (a) rolling kinematics ---------------------------------------------------------------------
def rolling_kinematics(o, R, g0):
    """In every stick sample of a run: phi' from the sampled positions and velocities against
    -(R/g0) Omega (relative), and, within each stick phase, the polar angle against the spin
    angle, phi - phi_a = -(R/g0)(theta - theta_a) (wrapped to (-pi, pi]: no unwrapping, so the
    output grid may be coarser than the whirl). Returns a dict of the largest deviations, the
    number of stick samples and phases, and the deviation series."""
    idx = _stick_rows(o)
    if len(idx) == 0:
        return {"samples": 0, "phases": 0}
    phi, phid = o.polar()
    Om = o.col["omega"]
    w = -(R / g0) * Om[idx]
    dev = np.abs(phid[idx] - w) / np.abs(w)
    # stick phases: runs of consecutive stick rows
    breaks = np.where(np.diff(idx) > 1)[0]
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [len(idx) - 1]])
    ang, turned = [], []
    for a, b in zip(starts, ends):
        j = idx[a:b + 1]
        th = o.col["theta"][j] - o.col["theta"][j[0]]
        d = phi[j] - phi[j[0]] + (R / g0) * th
        ang.append(np.abs(np.angle(np.exp(1j * d))))
        turned.append(abs(R / g0 * th[-1]))
    ang = np.concatenate(ang)
    gap = np.abs(np.abs(o.z_r()[idx] - o.z_s()[idx]) - g0) / g0
    return {"samples": len(idx), "phases": len(starts), "max_rel": float(dev.max()),
            "max_angle": float(ang.max()), "turned": float(max(turned)),
            "max_gap_rel": float(gap.max()), "max_vt_rel": float(
                np.max(np.abs(o.col["v_t"][idx]) / (R * np.abs(Om[idx])))),
            "t": o.t[idx], "dev": dev, "t_first": float(o.t[idx[0]])}


# ---- (b) rigid stator, torque-driven rolling -------------------------------------------------
OMEGA_START_RIGID = 10.0    # rad/s: on the rolling manifold, above (g0/R) w_r = 4 rad/s


def rigid_params(law):
    P = dict(RIGID, **{"loads.unbalance": 0.0})
    if law == "linear":
        P.update({"loads.torque_law": "linear", "loads.torque_free_speed": 40.0})
    return P


def rigid_closed(P):
    s = cf.short(P)
    Om0 = s["Omega_0"] if s["torque_law"] == "linear" else None
    return cf.rolling_rigid_stator(s["m_r"], s["k_r"], s["c_r"], s["J"], s["R"], s["g0"],
                                   s["tau"], Omega_0=Om0, mu=s["mu"]), Om0


def fit_exponential(t, y, guess):
    """Least-squares fit y = A + B exp(-t / T) (all three free); returns (A, B, T)."""
    from scipy.optimize import least_squares
    A0, B0, T0 = guess

    def res(p):
        A, B, T = A0 * (1 + p[0]), B0 * (1 + p[1]), T0 * (1 + p[2])
        return (A + B * np.exp(-t / T) - y) / abs(A0)
    sol = least_squares(res, [0.0, 0.0, 0.0], xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        method="lm")
    p = sol.x
    return A0 * (1 + p[0]), B0 * (1 + p[1]), T0 * (1 + p[2])


def study_rigid_rolling(rubdyn, out, law="constant", tol=TIGHT, n_tc=30.0):
    """Rigid stator, torque-driven rolling (docs/closed-forms.md section 2): started rolling at
    Omega = 10 rad/s, run n_tc time constants."""
    P = rigid_params(law)
    cfr, Om0 = rigid_closed(P)
    s = cf.short(P)
    R, g0 = s["R"], s["g0"]
    Tc, Oss = cfr["time_constant"], cfr["Omega"]
    st = Study("rigid-" + law, "Jeffcott, rigid stator, rolling, %s torque" % law)
    keys = cf.contact_orbit_state(P, cf.rolling_whirl(R, g0, OMEGA_START_RIGID),
                                  OMEGA_START_RIGID)
    name = "rigid_rolling_" + law
    case = write_case(out, P, name)
    t_end = round(n_tc * Tc, 1)
    o = run(rubdyn, case, os.path.join(out, name), initial_sets(keys), t_end=t_end, **tol)
    st.run("rolling from Omega = %g rad/s" % OMEGA_START_RIGID, o)
    if st.status != "ok":
        return st
    t, Om = o.t, o.col["omega"]
    ex = cf.rolling_rigid_stator_spin(s["m_r"], s["c_r"], s["J"], R, s["tau"], OMEGA_START_RIGID,
                                      t, Omega_0=Om0)
    stick = set(o.phase) == {"stick"}
    if not stick:
        st.status = "left stick"
        st.notes.append("phases %s: the run left the rolling phase" % sorted(set(o.phase)))
    st.add(Quantity("Omega(t) - exponential (2.4), largest over the run", 0.0,
                    float(np.max(np.abs(Om - ex) / ex)), t, np.abs(Om - ex) / ex,
                    note="relative, max over all samples", reach=False))
    st.add(Quantity("Omega_ss = tau/(c_r R^2)" if law == "constant" else
                    "Omega_ss = tau_a/(c_r R^2 + tau_a/Omega_0)", Oss, Om[-1], t, rel(Om, Oss),
                    unit="rad/s"))
    phi, phid = o.polar()
    st.add(Quantity("whirl w = phi' (positions, velocities)", cfr["w"], phid[-1], t,
                    rel(phid, cfr["w"]), unit="rad/s"))
    g = o.grid()
    tail = g[o.t[g] >= t_end - 0.1]
    slope, step = polar_slope(o, tail)
    st.add(Quantity("whirl w from the polar angle, last 0.1 s", cfr["w"], slope,
                    note="largest phi step between samples %.2f rad" % step, unit="rad/s",
                    reach=False))
    st.add(Quantity("N", cfr["N"], o.col["F_N"][-1], t, rel(o.col["F_N"], cfr["N"]), unit="N"))
    st.add(Quantity("F_T = tau(Omega_ss)/R", cfr["F_T"], o.col["F_T"][-1], t,
                    rel(o.col["F_T"], cfr["F_T"]), unit="N"))
    # N at every instant from the sampled spin (2.1): N(t) = g0 (m_r (R Omega/g0)^2 - k_r)
    Nt = g0 * (s["m_r"] * (R * Om / g0) ** 2 - s["k_r"])
    st.add(Quantity("N(t) - (2.1) of the sampled Omega, largest over the run", 0.0,
                    float(np.max(np.abs(o.col["F_N"] - Nt) / Nt)), reach=False))
    # the time constant: a 3-parameter fit of the samples while Omega_ss - Omega > 1e-7 Omega_ss
    # (beyond, the departure is 1e-7 and the integration error, 1e-11, no longer negligible)
    sel = np.abs(Om - Oss) > 1e-7 * Oss
    A, B, T = fit_exponential(t[sel], Om[sel], (Oss, OMEGA_START_RIGID - Oss, Tc))
    st.add(Quantity("time constant T_c (fit of Omega(t), %d samples to %.2f s)"
                    % (sel.sum(), t[sel][-1]), Tc, T, unit="s", reach=False))
    st.add(Quantity("the same fit's Omega_ss", Oss, A, unit="rad/s", reach=False))
    st.fit = (A, B, T)
    st.closed = cfr
    st.output = o
    return st


# ---- (c) Black's model: rolling ----------------------------------------------------------------
PERT = 1e-3                 # the start off the orbit: translation d0 = PERT g0, r' x (1 + PERT)


def black_roll_roots():
    return [r for r in cf.black_rolling_roots(BLACK_ROLL) if r["contact"] and r["stick"]]


def perturbed_keys(keys, d0, w, eps, spin=True):
    """A contact state off the steady orbit: rotor and stator translated together by d0 along
    X with the velocity d0 |w| along Y added to both (r and r' unchanged: still on the contact
    circle, v_t unchanged; the springs' forces are not), and the relative velocity r' scaled by
    1 + eps, with the spin too when spin=True (v_t = (1 + eps) v_t: rolling stays rolling).
    Both together excite every mode of the orbit, the slowest included (the translation alone
    hardly excites the high branch's slowest, real, mode)."""
    k = dict(keys)
    vr = complex(k["initial.vx_r"], k["initial.vy_r"])
    vs = complex(k.get("initial.vx_s", 0.0), k.get("initial.vy_s", 0.0))
    k["initial.vx_r"] += eps * (vr - vs).real
    k["initial.vy_r"] += eps * (vr - vs).imag
    if spin:
        k["initial.omega0"] *= 1 + eps
    for a in ("initial.x_r", "initial.x_s"):
        if a in k:
            k[a] += d0
    for a in ("initial.vy_r", "initial.vy_s"):
        if a in k:
            k[a] += d0 * abs(w)
    return k


def orbit_measures(st, o, root, zs_frame, Omega=None, spin=True, t_from=0.0):
    """Omega, w (phi' and polar angle), N, F_T and the stator's position in the frame of n
    against a steady orbit (root: w, N, F_T; zs_frame: z_s e^{-i phi} of the orbit)."""
    sel = o.t >= t_from
    t = o.t[sel]
    phi, phid = o.polar()
    if spin:
        st.add(Quantity("Omega", root["Omega"] if Omega is None else Omega, o.col["omega"][-1],
                        t, rel(o.col["omega"][sel], root["Omega"] if Omega is None else Omega),
                        unit="rad/s"))
    st.add(Quantity("whirl w = phi' (positions, velocities)", root["w"], phid[-1], t,
                    rel(phid[sel], root["w"]), unit="rad/s"))
    g = o.grid()
    win = 2 * math.pi / abs(root["w"]) * 20
    tail = g[(o.t[g] >= o.t[-1] - win - 1e-12)]
    slope, step = polar_slope(o, tail)
    st.add(Quantity("whirl w from the polar angle, last 20 periods", root["w"], slope,
                    note="largest phi step between samples %.2f rad" % step, unit="rad/s",
                    reach=False))
    st.add(Quantity("N", root["N"], o.col["F_N"][-1], t, rel(o.col["F_N"][sel], root["N"]),
                    unit="N"))
    st.add(Quantity("F_T", root["F_T"], o.col["F_T"][-1], t, rel(o.col["F_T"][sel], root["F_T"]),
                    unit="N"))
    if zs_frame is not None and zs_frame != 0:
        zeta = o.z_s() * np.exp(-1j * phi)
        d = np.abs(zeta[sel] - zs_frame) / abs(zs_frame)
        st.add(Quantity("stator orbit z_s e^{-i phi} (|difference| / |z_s|)", abs(zs_frame),
                        abs(zeta[-1]), t, d, unit="m"))
        st.q("stator orbit z_s e^{-i phi} (|difference| / |z_s|)").rel = float(d[-1])


def study_black_rolling(rubdyn, out, branch, tol=TIGHT, t_end=0.8, exact=False, eps=PERT):
    """Black's model, steady rolling on one branch of BLACK_ROLL (0: low band, 1: high band),
    started off the orbit (perturbed_keys, PERT = 1e-3; exact=True: on it)."""
    P = dict(BLACK_ROLL, **{"loads.unbalance": 0.0})
    root = black_roll_roots()[branch]
    label = ("low", "high")[branch]
    tag = "-exact" if exact else ("" if eps == PERT else "-translated")
    st = Study("black-roll-" + label + tag, "Black's model, rolling, %s branch, started %s"
               % (label, "on the orbit" if exact else "off the orbit"))
    keys0 = cf.contact_orbit_state(P, root["w"], root["Omega"], phi0=0.5)
    zs_frame = complex(keys0["initial.x_s"], keys0["initial.y_s"]) * np.exp(-0.5j)
    s = cf.short(P)
    keys = keys0 if exact else perturbed_keys(keys0, PERT * s["g0"], root["w"], eps)
    name = "black_roll_%s%s" % (label, tag.replace("-", "_"))
    case = write_case(out, P, name)
    o = run(rubdyn, case, os.path.join(out, name), initial_sets(keys), t_end=t_end, **tol)
    st.run("on the orbit" if exact else "off the orbit: 1e-3 g0, %g in r' and Omega" % eps, o)
    if st.status != "ok":
        return st
    if set(o.phase) != {"stick"}:
        st.status = "left stick"
        st.notes.append("phases %s" % sorted(set(o.phase)))
    orbit_measures(st, o, root, zs_frame)
    st.root, st.output = root, o
    return st


# ---- (d) whip ------------------------------------------------------------------------------------
def whip_params(law="constant"):
    P = dict(BLACK_WHIP, **{"loads.unbalance": 0.0})
    if law == "linear":     # docs/closed-forms.md 4.4: Omega_0 = 50 rad/s
        P.update({"loads.torque_law": "linear", "loads.torque_free_speed": 50.0})
    return P


def study_whip_exact(rubdyn, out, tol=TIGHT, Omega0=10.0, t_end=0.03, law="constant"):
    """The stable (middle) whip root of BLACK_WHIP, started exactly on it at Omega0: the locked
    frequency and N during the slip, Omega(t) linear (constant torque) or the exponential of the
    linear law, and the time at which it sticks (4.3)."""
    P = whip_params(law)
    root = cf.black_whip_roots(P)[1]
    ts = cf.whip_stick_time(P, root, Omega0)
    lin = law == "linear"
    st = Study("whip-exact" + ("-linear" if lin else ""),
               "Black's model, whip (middle root), started on the orbit, %s torque" % law)
    keys = cf.contact_orbit_state(P, root["w"], Omega0)
    zs_frame = complex(keys["initial.x_s"], keys["initial.y_s"])
    name = "whip_exact" + ("_linear" if lin else "")
    case = write_case(out, P, name)
    o = run(rubdyn, case, os.path.join(out, name), initial_sets(keys), t_end=t_end, **tol)
    st.run("on the orbit, Omega0 = %g rad/s" % Omega0, o)
    if st.status != "ok":
        return st
    e = o.first_event("stick")
    t_stick = e["t"] if e else None
    st.add(Quantity("t_stick (4.3)", ts["t_stick"], t_stick, unit="s", reach=False))
    slip = np.where(o.phase == "slip-")[0]
    if e is not None:
        slip = slip[o.t[slip] < t_stick]
    phi, phid = o.polar()
    sl = slip
    dev_w = rel(phid[sl], root["w"])
    st.add(Quantity("locked whirl w during the slip, largest deviation", root["w"],
                    phid[sl][np.argmax(dev_w)], o.t[sl], dev_w, unit="rad/s", reach=False))
    dev_N = rel(o.col["F_N"][sl], root["N"])
    st.add(Quantity("N during the slip, largest deviation", root["N"],
                    o.col["F_N"][sl][np.argmax(dev_N)], o.t[sl], dev_N, unit="N", reach=False))
    if lin:
        Om_ex = ts["Omega_inf"] + (Omega0 - ts["Omega_inf"]) * np.exp(-o.t[sl]
                                                                      / ts["time_constant"])
        lab = "Omega(t) - exponential (4.2), largest / Omega0"
    else:
        Om_ex = Omega0 + ts["Omega_rate"] * o.t[sl]
        lab = "Omega(t) - (Omega0 + rate t) (4.2), largest / Omega0"
    dev_O = np.abs(o.col["omega"][sl] - Om_ex) / Omega0
    st.add(Quantity(lab, 0.0, float(dev_O.max()), o.t[sl], dev_O, reach=False))
    zeta = o.z_s() * np.exp(-1j * phi)
    dz = np.abs(zeta[sl] - zs_frame) / abs(zs_frame)
    st.add(Quantity("stator orbit z_s e^{-i phi} during the slip, largest", abs(zs_frame),
                    abs(zeta[sl][np.argmax(dz)]), o.t[sl], dz, unit="m", reach=False))
    st.q("stator orbit z_s e^{-i phi} during the slip, largest").rel = float(dz.max())
    after = o.phase[o.t > (t_stick or math.inf)]
    st.notes.append("after t_stick: phases %s" % sorted(set(after)))
    st.root, st.ts, st.output = root, ts, o
    return st


def study_whip_approach(rubdyn, out, tol=TIGHT, Omega0=60.0, t_end=0.3, t_a=0.2):
    """The middle whip root started off the orbit (1e-3 g0, r' x (1 + 1e-3)) at Omega0 = 60
    rad/s: the whirl locks to w while the spin falls from 60 to 6 rad/s; the stick time from the
    state at t_a (on the orbit by then) by (4.3)."""
    P = whip_params()
    root = cf.black_whip_roots(P)[1]
    st = Study("whip-approach", "Black's model, whip (middle root), started off the orbit")
    keys0 = cf.contact_orbit_state(P, root["w"], Omega0)
    zs_frame = complex(keys0["initial.x_s"], keys0["initial.y_s"])
    keys = perturbed_keys(keys0, PERT * cf.short(P)["g0"], root["w"], PERT, spin=False)
    name = "whip_approach"
    case = write_case(out, P, name)
    o = run(rubdyn, case, os.path.join(out, name), initial_sets(keys), t_end=t_end, **tol)
    st.run("off the orbit: 1e-3 g0, 1e-3 in r'; Omega0 = %g rad/s" % Omega0, o)
    if st.status != "ok":
        return st
    e = o.first_event("stick")
    t_stick = e["t"] if e else None
    end = t_stick if t_stick is not None else o.t[-1]
    sl = np.where((o.phase == "slip-") & (o.t < end))[0]
    phi, phid = o.polar()
    t = o.t[sl]
    st.add(Quantity("locked whirl w", root["w"], phid[sl][-1], t, rel(phid[sl], root["w"]),
                    unit="rad/s"))
    st.add(Quantity("N", root["N"], o.col["F_N"][sl][-1], t, rel(o.col["F_N"][sl], root["N"]),
                    unit="N"))
    zeta = o.z_s() * np.exp(-1j * phi)
    dz = np.abs(zeta[sl] - zs_frame) / abs(zs_frame)
    q = st.add(Quantity("stator orbit z_s e^{-i phi}", abs(zs_frame), abs(zeta[sl][-1]), t, dz,
                        unit="m"))
    q.rel = float(dz[-1])
    # the spin's rate from the samples after t_a - 0.05 s (on the orbit): a straight-line fit
    ts0 = cf.whip_stick_time(P, root, Omega0)
    fit = sl[(t >= t_a - 0.05) & (t <= t_a)]
    rate = np.polyfit(o.t[fit], o.col["omega"][fit], 1)[0]
    st.add(Quantity("dOmega/dt = (tau - mu R N_w)/J (fit, %.2f-%.2f s)" % (t_a - 0.05, t_a),
                    ts0["Omega_rate"], rate, unit="rad/s^2", reach=False))
    ia = np.argmin(np.abs(o.t - t_a))
    pred = o.t[ia] + cf.whip_stick_time(P, root, o.col["omega"][ia])["t_stick"]
    st.add(Quantity("t_stick from the state at t = %.2f s (4.3)" % o.t[ia], pred, t_stick,
                    unit="s", reach=False))
    st.root, st.output = root, o
    return st


# ---- (e) unbalance at a prescribed speed --------------------------------------------------------
def unb_params():
    return dict(UNB)


def study_unbalance(rubdyn, out, tol=TIGHT, t_end=0.2, dv=1e-4):
    """Forward synchronous full annular rub at the prescribed 1500 rad/s, rigid stator (UNB):
    the larger root started with the rotor's velocity 1e-4 off (both signs), the smaller one
    likewise (a saddle: one side lifts off, the other goes to the larger root)."""
    P = unb_params()
    Om = OMEGA_U
    roots = cf.unbalance_full_rub_roots(P, Om)["roots"]
    big, small = roots
    st = Study("unbalance", "Jeffcott, rigid stator, unbalance at a prescribed speed")
    name = "unbalance"
    case = write_case(out, P, name)
    outs = {}
    for which, root in (("larger", big), ("smaller", small)):
        for sgn in (1, -1):
            keys = dict(cf.unbalance_orbit_state(P, Om, root))
            keys["initial.vx_r"] *= 1 + sgn * dv
            keys["initial.vy_r"] *= 1 + sgn * dv
            folder = os.path.join(out, "unbalance_%s_%s" % (which, "fast" if sgn > 0 else "slow"))
            o = run(rubdyn, case, folder, initial_sets(keys), t_end=t_end, check=False, **tol)
            if o is None:
                st.status = "refused"
                st.notes.append("rubdyn refused the case (loads.spin = \"prescribed\")")
                return st
            outs[(which, sgn)] = o
            st.run("%s root, rotor velocity x (1 %s 1e-4)" % (which, "+" if sgn > 0 else "-"), o)
            if st.status != "ok":
                return st
    s = cf.short(P)
    for sgn in (1, -1):
        o = outs[("larger", sgn)]
        sgnlab = "+" if sgn > 0 else "-"
        phi, phid = o.polar()
        t = o.t
        sfx = " (start %s1e-4)" % sgnlab
        n0 = len(st.quantities)
        st.add(Quantity("N" + sfx, big["N"], o.col["F_N"][-1], t, rel(o.col["F_N"], big["N"]),
                        unit="N"))
        st.add(Quantity("F_T = mu N" + sfx, big["F_T"], o.col["F_T"][-1], t,
                        rel(o.col["F_T"], big["F_T"]), unit="N"))
        st.add(Quantity("whirl w = phi' = Omega" + sfx, Om, phid[-1], t, rel(phid, Om),
                        unit="rad/s"))
        theta = o.col["theta"] if o.has("theta") else P["initial.theta"] + Om * (o.t - o.t[0])
        delta = np.angle(np.exp(1j * (theta + s["phi_u"] - phi)))
        st.add(Quantity("spin Omega (prescribed)" + sfx, Om, o.col["omega"][-1], t,
                        rel(o.col["omega"], Om), unit="rad/s"))
        st.add(Quantity("delta = psi - phi" + sfx, big["delta"], delta[-1], t,
                        rel(delta, big["delta"]), unit="rad"))
        if o.has("drive_torque"):
            st.add(Quantity("drive torque tau_d" + sfx, big["tau_d"], o.col["drive_torque"][-1],
                            t, rel(o.col["drive_torque"], big["tau_d"]), unit="N m"))
        for x in st.quantities[n0:]:
            x.runs = [o.folder]
    for sgn in (1, -1):
        o = outs[("smaller", sgn)]
        lift = o.first_event("liftoff")
        st.notes.append("smaller root, start %s1e-4: %s" % (
            "+" if sgn > 0 else "-",
            "lifts off at %.4f s" % lift["t"] if lift else
            "ends in contact with N = %.10g N (larger root %.10g N)"
            % (o.col["F_N"][-1], big["N"])))
    st.roots = roots
    st.outs = outs
    return st


# ---- (f) power balance over a window ------------------------------------------------------------
def window_run(rubdyn, case, src, out, t1, periods, w, tol, sets=()):
    """`rubdyn run case --from src --at t1` over `periods` whirl periods 2 pi/|w|: the summary's
    works are those of the window."""
    T = 2 * math.pi / abs(w) * periods
    return run(rubdyn, case, out, list(sets), t_end=t1 + T,
               extra=["--from", src, "--at", repr(t1)], **tol), T


def sample_powers(o, P):
    """Powers at every sample: drive tau(Omega) Omega, dampers, friction F_T v_t."""
    s = cf.short(P)
    Om = o.col["omega"]
    if o.has("drive_torque"):         # a prescribed spin: the torque that holds it
        tau = o.col["drive_torque"]
    elif s["torque_law"] == "linear":
        tau = s["tau"] * (1 - Om / s["Omega_0"])
    else:
        tau = s["tau"] * np.ones_like(Om)
    drive = tau * Om
    damp = -s["c_r"] * np.abs(o.v_r()) ** 2 - (0 if s["rigid"] else s["c_s"] * np.abs(o.v_s())
                                               ** 2)
    fric = o.col["F_T"] * o.col["v_t"]
    return drive, damp, fric


def trapz(t, y):
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def power_window(st, rubdyn, case, src_out, t1, periods, w, P, tol, label, drive_cf,
                 diss_cf=None, fric_cf=0.0, dE_cf=None, sets=()):
    """One window: the works of the summary and of the sampled powers against the closed
    form's drive power x window (drive_cf [W]), dissipation, friction."""
    folder = os.path.join(os.path.dirname(src_out.folder), "window_" + st.key + "_" + label)
    o, T = window_run(rubdyn, case, src_out.folder, folder, t1, periods, w, tol, sets)
    S = o.summary
    st.run("window %s: %g periods from t = %g s" % (label, periods, t1), o)
    if not o.summary["complete"]:
        return o
    n0 = len(st.quantities)
    Wd, Wc, Wf, Wi = S["work_torque"], S["work_damping"], S["work_friction"], S["work_impacts"]
    dE = S["energy_final"] - S["energy_initial"]
    dt_w = o.t[-1] - o.t[0]
    st.add(Quantity("%s: mean drive power W_torque/T" % label, drive_cf, Wd / dt_w, unit="W",
                    reach=False))
    diss = -(Wc + Wf) / dt_w
    st.add(Quantity("%s: mean dissipation -(W_damping + W_friction)/T" % label,
                    drive_cf if diss_cf is None else diss_cf, diss, unit="W", reach=False))
    q = st.add(Quantity("%s: W_friction / W_torque" % label, fric_cf, Wf / Wd, reach=False))
    if fric_cf == 0.0:
        q.rel = abs(Wf / Wd)
    q = st.add(Quantity("%s: (W_torque + W_damping + W_friction + W_impacts - dE) / W_torque"
                        % label, 0.0, (Wd + Wc + Wf + Wi - dE) / Wd, reach=False))
    q.rel = abs(q.measured)
    if dE_cf is not None:
        q = st.add(Quantity("%s: dE over the window / W_torque" % label,
                            dE_cf / (drive_cf * dt_w), dE / Wd, reach=False))
        if dE_cf == 0.0:
            q.rel = abs(dE / Wd)
    # the same from the sampled powers (trapezoid on the output grid)
    drive, damp, fric = sample_powers(o, P)
    q = st.add(Quantity("%s: sampled powers, (P_drive + P_dampers + P_friction) mean / P_drive"
                        % label, 0.0, (trapz(o.t, drive + damp + fric) - (dE if dE_cf is not None
                                                                          else 0.0))
                        / trapz(o.t, drive), reach=False))
    q.rel = abs(q.measured)
    for x in st.quantities[n0:]:
        x.runs = [o.folder]
    return o


def study_power(rubdyn, out, rigid_st, roll_sts, whip_st, tol=TIGHT, periods=50,
                whip_periods=20, unb_st=None):
    """Power balance over windows of whole whirl periods of converged steady orbits: the
    rigid stator's rolling, both Black rolling branches, and the locked whip (whose spin energy
    changes: drive + dampers + friction = d(J Omega^2/2)/dt)."""
    st = Study("power", "Power balance over a window of whole periods (section 6)")
    # rigid stator rolling: tau Omega_ss = c_r R^2 Omega_ss^2, friction 0
    P = rigid_params("constant")
    if rigid_st.status != "ok" or any(x.status != "ok" for x in roll_sts) or \
            (whip_st is not None and whip_st.status != "ok"):
        st.status = "skipped"
        st.notes.append("a run it starts from did not complete")
        return st
    o = rigid_st.output
    cfr = rigid_st.closed
    t1 = round(o.t[-1] - 0.5, 6)
    case = write_case(out, P, "rigid_rolling_constant")
    power_window(st, rubdyn, case, o, t1, periods, cfr["w"], P, tol, "rigid-stator rolling",
                 P["loads.torque"] * cfr["Omega"], dE_cf=0.0)
    for rs_ in roll_sts:
        P = dict(BLACK_ROLL, **{"loads.unbalance": 0.0})
        root = rs_.root
        o = rs_.output
        t1 = round(o.t[-1] - 0.1, 6)
        label = rs_.key.replace("black-roll-", "Black rolling ")
        case = write_case(out, P, "black_roll_" + rs_.key.split("-")[-1])
        power_window(st, rubdyn, case, o, t1, periods, root["w"], P, tol, label,
                     P["loads.torque"] * root["Omega"], dE_cf=0.0)
    # the locked whip: drive + dampers + friction = d(J Omega^2 / 2)/dt; over [t1, t2] with
    # Omega linear, friction's work is -mu N_w int (R Omega - g0 |w|) dt
    if whip_st is not None:
        P = whip_params()
        s = cf.short(P)
        root = whip_st.root
        o = whip_st.output
        t1 = 0.15
        i1 = np.argmin(np.abs(o.t - t1))
        t1 = float(o.t[i1])
        case = write_case(out, P, "whip_approach")
        T = 2 * math.pi / abs(root["w"]) * whip_periods
        Om1 = o.col["omega"][i1]
        rate = cf.whip_stick_time(P, root, Om1)["Omega_rate"]
        Om2 = Om1 + rate * T
        dE = 0.5 * s["J"] * (Om2 ** 2 - Om1 ** 2)
        drive = s["tau"] * (Om1 + Om2) / 2
        fric = -s["mu"] * root["N"] * (s["R"] * (Om1 + Om2) / 2 - s["g0"] * abs(root["w"]))
        # the dampers: -w^2 (c_r |z_r|^2 + c_s |z_s|^2) on the orbit
        keys = cf.contact_orbit_state(P, root["w"], 1.0)
        zr = abs(complex(keys["initial.x_r"], keys["initial.y_r"]))
        zs = abs(complex(keys["initial.x_s"], keys["initial.y_s"]))
        damp = -root["w"] ** 2 * (s["c_r"] * zr ** 2 + s["c_s"] * zs ** 2)
        power_window(st, rubdyn, case, o, t1, whip_periods, root["w"], P, tol, "whip",
                     drive, diss_cf=-(damp + fric), fric_cf=fric / drive, dE_cf=dE)
    # the unbalance at a prescribed speed: tau_d Omega = c_r Omega^2 g0^2 (rigid stator: the
    # rotor's orbit is the contact circle) + mu N (g0 + R) Omega, friction's share by (5.1)
    if unb_st is not None and unb_st.status == "ok":
        P = unb_params()
        s = cf.short(P)
        big = unb_st.roots[0]
        o = unb_st.outs[("larger", 1)]
        case = os.path.join(out, "unbalance.toml")
        Om = OMEGA_U
        drive = big["tau_d"] * Om
        fric = -s["mu"] * big["N"] * (s["g0"] + s["R"]) * Om
        power_window(st, rubdyn, case, o, 0.15, periods, Om, P, tol, "unbalance",
                     drive, fric_cf=fric / drive, dE_cf=0.0)
    return st


# ---- (a) rolling kinematics: the runs ------------------------------------------------------------
def study_rolling_rigid_rotor(rubdyn, out, tol=TIGHT, t_end=0.5, phases="reduced"):
    """The paper's rigid rotor, cases/reference.toml at mu = 0.25: it rolls from about 0.116 s
    to the end (gravity on, the stator sprung)."""
    st = Study("kinematics-rigid-rotor-" + phases,
               "Rolling kinematics, rigid rotor (reference.toml, mu = 0.25), %s contact phases"
               % phases)
    with open(REFERENCE, "rb") as f:
        c = tomllib.load(f)
    R, g0 = c["rotor"]["radius"], c["stator"]["gap"]
    o = run(rubdyn, REFERENCE, os.path.join(out, "rigid_rotor_mu0.25_" + phases),
            ["contact.mu=0.25", "solver.contact_phases=" + phases], t_end=t_end, **tol)
    st.run("reference.toml, mu = 0.25", o)
    if st.status != "ok":
        return st
    _kinematics_rows(st, o, R, g0)
    return st


def _kinematics_rows(st, o, R, g0):
    k = rolling_kinematics(o, R, g0)
    st.kin = k
    if k["samples"] == 0:
        st.status = "no stick"
        st.notes.append("no stick sample")
        return
    st.add(Quantity("phi' + (R/g0) Omega, largest / ((R/g0) |Omega|) over %d stick samples "
                    "(%d phases)" % (k["samples"], k["phases"]), 0.0, k["max_rel"], k["t"],
                    k["dev"], reach=False))
    q = st.add(Quantity("phi - phi_a + (R/g0)(theta - theta_a), largest [rad] (orbit turned "
                        "%.3g rad)" % k["turned"], 0.0, k["max_angle"], reach=False))
    q.rel = k["max_angle"] / k["turned"]
    q.note = "relative to the angle turned"
    q = st.add(Quantity("|r| - g0, largest / g0", 0.0, k["max_gap_rel"], reach=False))
    q.rel = k["max_gap_rel"]
    q = st.add(Quantity("v_t column, largest / (R |Omega|)", 0.0, k["max_vt_rel"], reach=False))
    q.rel = k["max_vt_rel"]


def study_rolling_jeffcott(rubdyn, out, tol=TIGHT, t_end=0.3, phases="reduced"):
    """A Jeffcott rolling run that is not steady: the high Black rolling branch of BLACK_ROLL
    with gravity (9.81) and an unbalance (1e-4 kg m) switched on: the orbit wobbles, the
    rolling kinematics must hold exactly all the same."""
    P = dict(BLACK_ROLL, **{"loads.gravity": 9.81, "loads.unbalance": 1e-4,
                            "loads.unbalance_phase": 0.7})
    root = black_roll_roots()[1]
    st = Study("kinematics-jeffcott-" + phases, "Rolling kinematics, Jeffcott (Black rolling "
               "branch with gravity and unbalance), %s contact phases" % phases)
    keys = cf.contact_orbit_state(dict(P, **{"loads.unbalance": 0.0}), root["w"],
                                  root["Omega"], phi0=0.5)
    case = write_case(out, P, "jeffcott_rolling_g")
    o = run(rubdyn, case, os.path.join(out, "jeffcott_rolling_g_" + phases),
            initial_sets(keys) + ["solver.contact_phases=" + phases], t_end=t_end, **tol)
    st.run("high branch, gravity and unbalance on", o)
    if st.status != "ok":
        return st
    s = cf.short(P)
    _kinematics_rows(st, o, s["R"], s["g0"])
    return st


def kinematics_of(st_list, title, key):
    """Rolling kinematics pooled over the stick samples of other studies' runs (R and g0 of
    each run from its case.resolved.toml)."""
    st = Study(key, title)
    for s in st_list:
        for label, o in s.runs:
            if "stick" in set(o.phase):
                st.run(s.key + ": " + label, o)
    ks = [rolling_kinematics(o, o.case["rotor"]["radius"], o.case["stator"]["gap"])
          for _, o in st.runs]
    ks = [k for k in ks if k["samples"]]
    st.kin = ks
    if not ks:
        st.status = "no stick"
        return st
    st.add(Quantity("phi' + (R/g0) Omega, largest / ((R/g0) |Omega|) over %d stick samples "
                    "(%d runs)" % (sum(k["samples"] for k in ks), len(ks)), 0.0,
                    max(k["max_rel"] for k in ks), reach=False))
    q = st.add(Quantity("phi - phi_a + (R/g0)(theta - theta_a), largest [rad]", 0.0,
                        max(k["max_angle"] for k in ks), reach=False))
    q.rel = max(k["max_angle"] / k["turned"] for k in ks)
    q.note = "relative to the angle turned"
    return st


# ---- approach rates --------------------------------------------------------------------------------
def approach_rate(t, dev, hi=1e-5, lo=3e-9):
    """Decay rate [1/s] of a relative deviation: the slope of log of its envelope from the
    right, env(t_k) = max over j >= k of dev(t_j) (the bound it stays under), between the
    times it stays under hi and under lo; None if it does not reach lo."""
    t, dev = np.asarray(t), np.asarray(dev)
    t1, t2 = time_to_reach(t, dev, hi), time_to_reach(t, dev, lo)
    if t1 is None or t2 is None or t2 <= t1:
        return None
    env = np.maximum.accumulate(dev[::-1])[::-1]
    sel = (t >= t1) & (t <= t2) & (env > 0)
    return -np.polyfit(t[sel], np.log(env[sel]), 1)[0]


def orbit_eigen(P, root, mode):
    """Eigenvalues of the steady orbit in its own frame, from the independent simulation's
    vector field (reference_sim.orbit_eigenvalues): the rates a perturbation decays with."""
    import reference_sim as rs
    m = rs.JeffcottBlack(P)
    Om = root["Omega"] if mode == "stick" else 10 * root["Omega_stick"]
    keys = cf.contact_orbit_state(P, root["w"], Om)
    zs = complex(keys["initial.x_s"], keys["initial.y_s"])
    head = [root["Omega"]] if mode == "stick" else [root["w"]]
    xi = head + [zs.real, zs.imag, (1j * root["w"] * zs).real, (1j * root["w"] * zs).imag]
    ev, _ = rs.orbit_eigenvalues(m, mode, xi)
    return ev


def unbalance_eigen(P, root, Omega):
    """Eigenvalues of the forward synchronous rub orbit at a prescribed speed (slip, invariant
    coordinates delta, phi'; rigid stator), from reference_sim's vector field."""
    import reference_sim as rs
    m = rs.JeffcottBlack(P)
    ev, _ = rs.orbit_eigenvalues(m, "slip-", [root["delta"], Omega])
    return ev
