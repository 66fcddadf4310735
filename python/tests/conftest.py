"""Shared runs of the Python suite (ctest -L python): a shortened single-grain run written
once by the command line and once by crumble.run, reused by the tests that read them."""

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(os.environ.get("CRUMBLE_SOURCE_DIR", Path(__file__).resolve().parents[2]))
SINGLE_GRAIN = ROOT / "scenarios" / "single_grain_pd.json"
# The single grain made cheap: a coarse lattice (the fast preset's spacing), a check every
# 0.4 MPa; it still breaks (about 2 s of CPU).
QUICK_SETS = {"breakage.spacing_fraction": 0.15, "schedule.every_stress": 0.4e6, "output.vtk_every": 100}
# Wall times and what a process counts across its runs: the only fields two runs may differ in.
VOLATILE = {"wall_seconds", "time_breakdown_s", "representations_built"}


def quick_scenario():
    import crumble

    sc = crumble.Scenario.load(SINGLE_GRAIN)
    for k, v in QUICK_SETS.items():
        sc.set(k, v)
    return sc


def cli_sets():
    out = []
    for k, v in QUICK_SETS.items():
        out += ["--set", f"{k}={v}"]
    return out


def stable_summary(run):
    return {k: v for k, v in run.summary.items() if k not in VOLATILE}


def csv_rows(path, drop=("wall_ms",)):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, h in enumerate(rows[0]) if h not in drop]
    return [[r[i] for i in keep] for r in rows]


def assert_same_run(a, b):
    assert stable_summary(a) == stable_summary(b)
    for name in ("series.csv", "events.csv", "psd.csv"):
        assert csv_rows(a.path / name) == csv_rows(b.path / name), name


@pytest.fixture(scope="session")
def cli_run(tmp_path_factory):
    import crumble

    out = tmp_path_factory.mktemp("cli") / "sg"
    cmd = [crumble.binary(), "run", str(SINGLE_GRAIN), "--out", str(out), "--quiet"] + cli_sets()
    subprocess.run(cmd, check=True)
    return crumble.open(out)


@pytest.fixture(scope="session")
def py_run(tmp_path_factory):
    import crumble

    return crumble.run(quick_scenario(), out=tmp_path_factory.mktemp("py") / "sg")


def python_env():
    env = dict(os.environ)
    env["MPLBACKEND"] = "Agg"
    env["PYTHONPATH"] = os.pathsep.join(p for p in [os.environ.get("PYTHONPATH", "")] + sys.path if p)
    return env
