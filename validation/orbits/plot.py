#!/usr/bin/python3
"""Figures of a branch folder of `rubdyn branch` (and of an orbit folder of `rubdyn orbit`):

    validation/orbits/plot.py BRANCH_DIR [--orbit ORBIT_DIR]

writes BRANCH_DIR/branch.png (the orbit's amplitude and normal force against the varied key:
stable solid, unstable dashed, undecided dotted; special points marked and named),
BRANCH_DIR/multipliers.png (every point's multipliers in the complex plane, coloured by the
key, with the unit circle) and, with --orbit, ORBIT_DIR/orbit.png (the rotor's and the ring's
centres over the period, with the contact circle)."""
import argparse
import csv
import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STYLE = {"stable": "-", "unstable": "--", "undecided": ":"}


def read_branch(d):
    with open(os.path.join(d, "branch.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(d, "branch.json")) as f:
        meta = json.load(f)
    return rows, meta


def segments(lam, y, stab):
    """Runs of equal stability, each joined to the next point so that the line is unbroken."""
    out, start = [], 0
    for i in range(1, len(lam) + 1):
        if i == len(lam) or stab[i] != stab[start]:
            j = min(i + 1, len(lam))
            out.append((lam[start:j], y[start:j], stab[start]))
            start = i
    return out


def plot_branch(d):
    rows, meta = read_branch(d)
    # a point whose orbit was not analysed (the events changed there) has no multipliers
    rows = [r for r in rows if r.get("mu1_re")]
    key = meta["key"]
    lam = np.array([float(r[key]) for r in rows])
    amp = np.array([float(r["amplitude"]) for r in rows])
    fn = np.array([float(r["F_N_max"]) for r in rows])
    stab = [r["stability"] for r in rows]
    fig, axes = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    for ax, y, label in ((axes[0], amp * 1e3, "rotor amplitude [mm]"),
                         (axes[1], fn, "normal force (max over the period) [N]")):
        for xs, ys, s in segments(lam, y, stab):
            ax.plot(xs, ys, STYLE.get(s, "-"), color="C0")
        for sp in meta["specials"]:
            i = min(sp["between"][0], len(y) - 1)
            ax.plot(sp["value"], y[i], "o", color="C3")
            ax.annotate(f"{sp['kind']} {sp['value']:.6g}", (sp["value"], y[i]),
                        textcoords="offset points", xytext=(-10, 8), ha="right", fontsize=8)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[1].set_xlabel(key)
    handles = [plt.Line2D([], [], ls=v, color="C0", label=k) for k, v in STYLE.items()]
    axes[0].legend(handles=handles, loc="best", fontsize=8)
    axes[0].set_title(f"branch in {key}: {len(rows)} points, {meta['outcome']}")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "branch.png"), dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 6))
    th = np.linspace(0, 2 * math.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.5", lw=0.8)
    j = 1
    pts, cols = [], []
    while f"mu{j}_re" in rows[0]:
        for r, l in zip(rows, lam):
            if r[f"mu{j}_re"]:
                pts.append((float(r[f"mu{j}_re"]), float(r[f"mu{j}_im"])))
                cols.append(l)
        j += 1
    if pts:
        p = np.array(pts)
        sc = ax.scatter(p[:, 0], p[:, 1], c=cols, s=6, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=key)
    ax.set_aspect("equal")
    ax.set_xlabel("Re mu")
    ax.set_ylabel("Im mu")
    ax.set_title("Floquet multipliers along the branch")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(d, "multipliers.png"), dpi=120)
    plt.close(fig)


def plot_orbit(d):
    with open(os.path.join(d, "orbit.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(d, "orbit.json")) as f:
        meta = json.load(f)
    col = {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k != "phase"}
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot(col["x_r"] * 1e3, col["y_r"] * 1e3, label="rotor centre")
    if "x_s" in col:
        ax.plot(col["x_s"] * 1e3, col["y_s"] * 1e3, label="ring centre")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"orbit: period {meta['period']:.6g} s, {meta['stability']}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(d, "orbit.png"), dpi=120)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("branch")
    ap.add_argument("--orbit")
    a = ap.parse_args()
    plot_branch(a.branch)
    if a.orbit:
        plot_orbit(a.orbit)


if __name__ == "__main__":
    main()
