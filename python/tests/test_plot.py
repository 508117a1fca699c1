"""rubdyn.plot: every figure is written and non-empty, from a folder and from a run; decimation
keeps events, phase changes and the extremes."""
import shutil
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")

import rubdyn  # noqa: E402
import rubdyn.plot as rp  # noqa: E402
from conftest import REFERENCE  # noqa: E402


def test_command_writes_every_figure(cli, cli_reference_out, tmp_path):
    # `rubdyn analyze` adds the spectrogram (OUT_DIR/analysis), drawn with the Campbell overlay
    out = tmp_path / "run"
    shutil.copytree(cli_reference_out, out)
    a = subprocess.run([cli, "analyze", str(out)], capture_output=True, text=True, check=False)
    assert a.returncode == 0, a.stderr
    png = tmp_path / "png"
    p = subprocess.run([sys.executable, "-m", "rubdyn.plot", str(out), "--png",
                        str(png)], capture_output=True, text=True, check=False)
    assert p.returncode == 0, p.stderr
    for name in list(rp.FIGURES) + ["spectrogram"]:
        path = png / f"{name}.png"
        assert path.exists(), name
        # a PNG of a drawn figure at 130 dpi is tens of kB; an empty canvas compresses to ~5 kB
        assert path.stat().st_size > 15_000, (name, path.stat().st_size)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_functions_return_figures_with_data():
    res = rubdyn.run(REFERENCE, overrides={"contact.mu": 0.25}, t_end=0.15)  # slip, then stick
    for name, make in rp.FIGURES.items():
        fig = make(res)
        lines = sum(len(ax.lines) for ax in fig.axes)
        assert lines > 0, name
        matplotlib.pyplot.close(fig)
    fig = rp.timeline(res)
    labels = [t.get_text() for t in fig.axes[1].get_yticklabels()]
    n_impacts = int(np.sum(res.events["kind"] == "impact"))
    assert f"impact ({n_impacts})" in labels and "stick (1)" in labels
    matplotlib.pyplot.close(fig)


def test_decimation_keeps_events_phase_changes_and_extremes():
    n = 200_000
    t = np.linspace(0.0, 1.0, n)
    y = np.sin(2e3 * t) + (t == t[123_457]) * 5.0  # one sample spike
    phase = np.zeros(n, dtype=np.int8)
    phase[50_000:150_001] = 1
    ev_t = t[[10_001, 77_777, 150_001]]
    events = np.zeros(3, dtype=list(rubdyn.EVENT_FIELDS))
    events["t"] = ev_t
    res = rubdyn.Result({"t": t, "y": y, "phase": phase}, events, {})
    i = rp.decimate(res, ["y"], max_points=4000)
    # 1000 bins x (first, last, min, max) + events + phase changes: at most ~4000 + a few
    assert len(i) <= 4010
    assert np.all(np.isin(ev_t, t[i]))
    assert {49_999, 50_000, 150_000, 150_001} <= set(i.tolist())
    assert y[i].max() == y.max() and y[i].min() == y.min()
