"""Helpers shared by the validation scripts: running rubdyn into an output folder and reading
it back, and naming the machine a table was measured on."""
import csv
import io
import json
import math
import os
import platform
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASE = os.path.join(ROOT, "cases", "reference.toml")


def machine():
    """CPU model and architecture, for the tables' headers."""
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return "%s, %s, %d cores" % (cpu, platform.machine(), os.cpu_count() or 0)


def read_output(folder, dt=1e-4, last=False):
    """Reads an output folder: (summary dict, grid, events) with grid[k] = {column: value} for
    the rows at t = k dt (the output grid; at an event on a grid time the row before the event,
    or with last=True the one after it) and events as (t, kind)."""
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    grid = {}
    for r in read_rows(os.path.join(folder, "timeseries.csv")):
        t = float(r["t"])
        k = round(t / dt)
        if abs(t - k * dt) < 1e-9 and (last or k not in grid):
            grid[k] = {c: float(v) for c, v in r.items()
                       if c != "phase" and not c.startswith("phase_")}
    events = [(float(r["t"]), r["kind"]) for r in read_rows(os.path.join(folder, "events.csv"))]
    return summary, grid, events


def read_rows(path):
    """The rows of a CSV file written by rubdyn, as dicts. rubdyn ends every row with a line end:
    a last row without one was cut by a kill (it may hold a truncated number) and is dropped
    with a warning on stderr. An empty file (a killed run of an older rubdyn) has no rows."""
    with open(path, newline="") as f:
        text = f.read()
    if text and not text.endswith("\n"):
        cut = text.rfind("\n") + 1
        print("warning: %s: the last row has no line end (the run was cut short): ignored" % path,
              file=sys.stderr)
        text = text[:cut]
    return list(csv.DictReader(io.StringIO(text)))


def run_case(rubdyn, folder, args, dt=1e-4):
    """Runs `rubdyn run` on the reference case into folder; returns (summary dict, grid) with
    grid[k] = (x_r, y_r, omega) at t = k dt (the output grid; event rows are skipped), and the
    list of events as (t, kind)."""
    subprocess.run([rubdyn, "run", CASE, "--out", folder, "--quiet"] + args, check=True,
                   stdout=subprocess.DEVNULL)
    summary, rows, events = read_output(folder, dt)
    grid = {k: (r["x_r"], r["y_r"], r["omega"]) for k, r in rows.items()}
    return summary, grid, events


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def script_args(name):
    """The command line of the study scripts: `run.py [path/to/rubdyn] [--quick]`. Returns
    (rubdyn, quick, out) with out = ROOT/out/<name>."""
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rubdyn = args[0] if args else os.path.join(ROOT, "build", "rubdyn")
    return rubdyn, "--quick" in sys.argv, os.path.join(ROOT, "out", name)


def longest_free_flight(times, phases, t0):
    """Longest free flight [s] after t0 in a series: a run of phase 'free' between two contact
    phases or until the end, counted from t0 when it began earlier."""
    best, start, t = 0.0, None, None
    for t, ph in zip(times, phases):
        if ph == "free":
            if start is None:
                start = t
        elif start is not None:
            if t > t0:
                best = max(best, t - max(start, t0))
            start = None
    if start is not None:
        best = max(best, t - max(start, t0))
    return best

def grid_errors(grid, ref):
    """(orbit error, omega error) of a grid {k: (x_r, y_r, omega)} against a reference grid: the
    largest |r_r - r_r,ref| over the common sample times, and |omega - omega_ref| at the
    reference's last sample (nan when the run does not reach it)."""
    common = sorted(set(grid) & set(ref))
    orbit = max(math.hypot(grid[k][0] - ref[k][0], grid[k][1] - ref[k][1]) for k in common)
    kmax = max(ref)
    omega = abs(grid[kmax][2] - ref[kmax][2]) if kmax in grid else float("nan")
    return orbit, omega


# ---- runs read back for the paper studies (validation/paper, validation/calibration)
def quiet(rubdyn, args):
    """Runs rubdyn with args, output discarded; returns the exit code (3, a run ended early,
    keeps its folder: the caller reads summary.json)."""
    return subprocess.run([rubdyn] + args, stdout=subprocess.DEVNULL).returncode


def run_analyzed(rubdyn, case, folder, t_end, sets=(), extra=()):
    """`rubdyn run` (t_end, --set overrides, extra options) then `rubdyn analyze`; the folder."""
    args = ["run", case, "--out", folder, "--quiet", "--t-end", "%.6g" % t_end]
    for s in sets:
        args += ["--set", s]
    quiet(rubdyn, args + list(extra))
    quiet(rubdyn, ["analyze", folder])
    return folder


def sweep(rubdyn, case, folder, t_end, varies, sets=(), extra=(), jobs=2):
    """`rubdyn sweep` of the product of `varies`; the rows of sweep.csv."""
    args = ["sweep", case, "--out", folder, "--quiet", "--t-end", "%.6g" % t_end,
            "--jobs", str(jobs)]
    for v in varies:
        args += ["--vary", v]
    for s in sets:
        args += ["--set", s]
    quiet(rubdyn, args + list(extra))
    with open(os.path.join(folder, "sweep.csv")) as f:
        return list(csv.DictReader(f))


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def num(x):
    return float(x) if x not in ("", "nan", None) else np.nan


class Run:
    """One output folder with its analysis, as arrays."""

    def __init__(self, folder):
        self.folder = folder
        ts = read_csv(os.path.join(folder, "timeseries.csv"))
        de = read_csv(os.path.join(folder, "analysis", "derived.csv"))
        self.t = np.array([num(r["t"]) for r in ts])
        self.x = np.array([num(r["x_r"]) for r in ts])
        self.y = np.array([num(r["y_r"]) for r in ts])
        self.vx = np.array([num(r["vx_r"]) for r in ts])
        self.vy = np.array([num(r["vy_r"]) for r in ts])
        self.omega = np.array([num(r["omega"]) for r in ts])
        self.v_t = np.array([num(r["v_t"]) for r in ts])
        self.dN = np.array([num(r["d_N"]) for r in ts])
        self.phase = [r["phase"] for r in ts]
        self.prec = np.array([num(r["precession"]) for r in de])
        self.ftr = np.array([num(r["friction_torque_ratio"]) for r in de])
        self.contact = np.array([r["regime"] != "free" for r in de])
        self.stick = np.array([r["regime"] == "rolling" for r in de])
        self.events = read_csv(os.path.join(folder, "events.csv"))
        self.a = json.load(open(os.path.join(folder, "analysis", "analysis.json")))
        self.summary = json.load(open(os.path.join(folder, "summary.json")))

    def last_liftoff(self):
        """Time of the last lift-off (None: none); meaningful when the run ends in contact."""
        t = [num(e["t"]) for e in self.events if e["kind"] in ("liftoff", "release")]
        return max(t) if t else None

    def liftoffs(self, t0, t1):
        return sum(1 for e in self.events
                   if e["kind"] in ("liftoff", "release") and t0 <= num(e["t"]) < t1)

    def ends_in_contact(self):
        return bool(self.contact[-1])

    def sign_settles(self, sign):
        """Earliest time after which the precession keeps `sign` (ignoring undefined samples),
        or None when its last defined sample has the other sign."""
        ok = ~np.isnan(self.prec)
        bad = ok & (np.sign(self.prec) != sign)
        if not ok.any() or bad[np.where(ok)[0][-1]]:
            return None
        idx = np.where(bad)[0]
        return self.t[idx[-1]] if len(idx) else self.t[0]

    def first_above(self, arr, level):
        idx = np.where(arr > level)[0]
        return self.t[idx[0]] if len(idx) else None


def spectrogram(run, window=0.08, overlap=0.5, pad=4):
    """Full spectrogram of z = x_r + i y_r, frame mean removed (the rotor sits in the clearance:
    without detrending its static offset is the strongest 'peak' at 0 Hz, which the paper does
    not show), Hann window, amplitude |Z| / sum(w). Returns (t_centres, omega_mean, f, A[frame, f])
    on the output grid (event rows dropped)."""
    keep = np.concatenate([[True], np.diff(run.t) > 1e-12])
    t, z, om = run.t[keep], (run.x + 1j * run.y)[keep], run.omega[keep]
    dt = np.median(np.diff(t))
    n = int(round(window / dt))
    step = max(1, int(round(n * (1 - overlap))))
    w = np.hanning(n)
    nf = pad * n
    f = np.fft.fftshift(np.fft.fftfreq(nf, dt))
    tc, oc, amp = [], [], []
    for i0 in range(0, len(t) - n + 1, step):
        seg = z[i0:i0 + n]
        seg = (seg - seg.mean()) * w
        amp.append(np.abs(np.fft.fftshift(np.fft.fft(seg, nf))) / w.sum())
        tc.append(t[i0:i0 + n].mean())
        oc.append(om[i0:i0 + n].mean())
    return np.array(tc), np.array(oc), f, np.array(amp)


# A frame is undersampled when its whirl frequency scale exceeds this fraction of the Nyquist
# frequency (as rubdyn analyze: kUndersampledFraction in include/rubdyn/analysis/postprocess.hpp)
UNDERSAMPLED_FRACTION = 0.5


def whirl_scale(run, window=0.08, overlap=0.5):
    """For the frames of spectrogram(run, window, overlap): the whirl frequency scale
    max |z'| / (2 pi max |z - mean z|) [Hz] of each frame, from the velocities (states, exact at
    the samples: they see a whirl however fast), and the Nyquist frequency 1 / (2 dt) of the
    samples. Exact for a circular whirl; above the Nyquist frequency it proves content that the
    samples alias (Bernstein's inequality). Returns (f_whirl per frame, f_nyquist); a frame is
    undersampled when f_whirl > UNDERSAMPLED_FRACTION f_nyquist."""
    keep = np.concatenate([[True], np.diff(run.t) > 1e-12])
    t, z, vz = run.t[keep], (run.x + 1j * run.y)[keep], (run.vx + 1j * run.vy)[keep]
    dt = np.median(np.diff(t))
    n = int(round(window / dt))
    step = max(1, int(round(n * (1 - overlap))))
    fw = []
    for i0 in range(0, len(t) - n + 1, step):
        seg, vseg = z[i0:i0 + n], vz[i0:i0 + n]
        rmax, vmax = np.abs(seg - seg.mean()).max(), np.abs(vseg).max()
        fw.append(0.0 if vmax == 0 else (vmax / (2 * np.pi * rmax) if rmax > 0 else np.inf))
    return np.array(fw), 0.5 / dt


class Campbell:
    """rubdyn campbell of a case (k_s overridden as needed), interpolated in omega."""

    def __init__(self, rubdyn, case, folder, omega_max, sets=()):
        args = ["campbell", case, "--out", folder, "--omega-max", "%.6g" % omega_max,
                "--points", "401"]
        for s in sets:
            args += ["--set", s]
        quiet(rubdyn, args)
        rows = read_csv(os.path.join(folder, "campbell.csv"))
        self.om = np.array([num(r["omega_rad_s"]) for r in rows])
        self.c = {k: np.array([num(r[k]) for r in rows]) for k in ("f1b", "f1f", "f2b", "f2f")}

    def __call__(self, name, omega):
        return np.interp(omega, self.om, self.c[name])


def peaks(sg, t0, t1, sign=0, fmin=5.0, fmax=np.inf):
    """Median over frames in [t0, t1) of the strongest frequency (fmin <= |f| <= fmax; sign > 0:
    forward only, < 0: backward only) and the frames' mean omega."""
    tc, oc, f, a = sg
    sel = (tc >= t0) & (tc < t1)
    if not sel.any():
        return None, None
    mask = (np.abs(f) >= fmin) & (np.abs(f) <= fmax)
    if sign:
        mask &= np.sign(f) == sign
    fr = [f[mask][np.argmax(row[mask])] for row in a[sel]]
    return float(np.median(fr)), float(np.mean(oc[sel]))
