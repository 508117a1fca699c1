"""Shared fixtures: the CLI of the same build and the repository's cases (set by ctest, see
python/CMakeLists.txt; defaults for running pytest by hand from the build folder)."""
import os
import subprocess

import pytest

SOURCE = os.environ.get("RUBDYN_SOURCE_DIR",
                        os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("RUBDYN_CLI", os.path.join(SOURCE, "build", "rubdyn"))
REFERENCE = os.path.join(SOURCE, "cases", "reference.toml")


@pytest.fixture(scope="session")
def cli():
    if not os.path.exists(CLI):
        pytest.skip(f"no CLI at {CLI} (set RUBDYN_CLI)")
    return CLI


@pytest.fixture(scope="session")
def reference_case():
    return REFERENCE


def run_cli(cli, *args):
    """Runs the CLI; returns the completed process (stdout, stderr as text)."""
    return subprocess.run([cli, *args], capture_output=True, text=True, check=False)


@pytest.fixture(scope="session")
def cli_reference_out(cli, tmp_path_factory):
    """The reference case for 0.1 s written by the CLI (impacts, slip, lift-offs)."""
    out = tmp_path_factory.mktemp("cli") / "ref"
    p = run_cli(cli, "run", REFERENCE, "--t-end", "0.1", "--rtol", "1e-9", "--out", str(out),
                "--quiet")
    assert p.returncode == 0, p.stderr
    return out


@pytest.fixture(scope="session")
def small_out(cli, tmp_path_factory):
    """The reference case for 10 ms written by the CLI (an impact, slip): a folder to damage."""
    out = tmp_path_factory.mktemp("cli") / "small"
    p = run_cli(cli, "run", REFERENCE, "--t-end", "0.01", "--out", str(out), "--quiet")
    assert p.returncode == 0, p.stderr
    return out
