"""The Python package against the command line (ctest -L python; docs/python.md)."""

import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

import crumble
from conftest import (QUICK_SETS, ROOT, SINGLE_GRAIN, assert_same_run, csv_rows, python_env, quick_scenario,
                      stable_summary)


def cli(*args):
    return subprocess.run([crumble.binary(), *args], check=True, capture_output=True, text=True).stdout


# ---- version


def test_version_is_the_cmake_project_version():
    project = re.search(r"project\(crumble VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text()).group(1)
    assert crumble.__version__ == project
    assert subprocess.run([crumble.binary(), "--version"], capture_output=True, text=True).stdout.split()[1] == project
    if crumble.version is not None:  # the compiled module's CRUMBLE_VERSION
        assert crumble.version == project


# ---- registry


def test_registry_matches_crumble_list():
    text = cli("list")
    blocks = re.split(r"^(engines|breakage models|fragment builders|methods|fidelity presets)\b.*:$", text, flags=re.M)
    listed = {blocks[i]: re.findall(r"^  (\w+) — ", blocks[i + 1], flags=re.M) for i in range(1, len(blocks) - 1, 2)}
    reg = crumble.registry()
    assert [e.name for e in reg.engines] == listed["engines"]
    assert [m.name for m in reg.models] == listed["breakage models"]
    assert [b.name for b in reg.builders] == listed["fragment builders"]
    assert reg.criteria["stress"] == ("max_principal", "von_mises", "tresca")
    assert reg.presets["names"] == ["fast", "balanced", "accurate"]
    assert [m["name"] for m in reg.methods] == listed["methods"] == ["zhu_zhao_2019", "harmon_2020"]
    for m in reg.methods:
        listed_settings = re.findall(r"^      (\S+) = (.+?)   \(", text.split("  " + m["name"] + " — ")[1], flags=re.M)
        assert [p for p, _ in listed_settings[:len(m["settings"])]] == [s["path"] for s in m["settings"]], m["name"]
    for impl in reg.engines + reg.models + reg.builders:
        if impl.options:
            table = cli("list", "--options", impl.name)
            keys = re.findall(r"^  (\S+)\s{2,}", table, flags=re.M)
            assert keys[0] == "key" and keys[1:] == [o.key for o in impl.options], impl.name
    kn = {o.key: o for o in reg.find("lsdem")[0].options}["kn"]
    assert kn.unit == "N/m" and kn.type and kn.doc and kn.range


# ---- bad input


def test_bad_value_raises_input_error_naming_the_path(tmp_path):
    sc = crumble.Scenario.load(SINGLE_GRAIN).set("engine.mass_scale", -1)
    with pytest.raises(crumble.InputError) as e:
        sc.validate()
    assert isinstance(e.value, ValueError)
    assert e.value.path == "/engine/mass_scale" and "/engine/mass_scale" in str(e.value)
    with pytest.raises(crumble.InputError, match="/breakage/criterion"):
        crumble.Scenario.load(ROOT / "scenarios" / "oedometer_harmon_2d_quick.json").set(
            "breakage.criterion", "bogus").validate()
    out = tmp_path / "never"
    with pytest.raises(crumble.InputError, match="/container/lx"):
        crumble.run({"dimension": 3, "engine": {"type": "bullet"}}, out=out)
    assert not out.exists(), "bad input is refused before anything is written"


def test_bad_python_values_raise_input_error(tmp_path):
    with pytest.raises(crumble.InputError, match="no_such.json"):
        crumble.Scenario.load(tmp_path / "no_such.json")
    with pytest.raises(crumble.InputError, match="JSON object"):
        crumble.Scenario([1, 2])
    with pytest.raises(crumble.InputError, match="/simulation/max_steps"):
        crumble.Scenario.load(SINGLE_GRAIN).set("simulation.max_steps", float("nan"))
    with pytest.raises(crumble.InputError, match="threads"):
        crumble.run(SINGLE_GRAIN, out=tmp_path / "t", threads=0)
    with pytest.raises(crumble.InputError, match="not a crumble run folder"):
        crumble.open(tmp_path)


def test_scenario_set_and_to_dict():
    sc = crumble.Scenario.load(SINGLE_GRAIN).set("breakage.gc0", 40).set("output.vtk_final", False)
    d = sc.to_dict()
    assert d["breakage"]["gc0"] == 40 and d["output"]["vtk_final"] is False
    info = sc.validate()
    assert info["engine"] == "bullet" and info["grains"] == 1
    assert info["effective"]["breakage"]["gc0"] == 40


# ---- runs


def test_python_run_equals_cli_run(cli_run, py_run):
    assert py_run.summary["breakage_events"] >= 1, "the quick single grain must break for the test to mean much"
    assert py_run.summary["crushing_force_N"] == cli_run.summary["crushing_force_N"]
    assert_same_run(py_run, cli_run)


def test_run_from_dict_equals_run_from_file(tmp_path, py_run):
    with open(SINGLE_GRAIN) as f:
        doc = json.load(f)
    sc = crumble.Scenario(doc, source=str(SINGLE_GRAIN))
    for k, v in QUICK_SETS.items():
        sc.set(k, v)
    assert_same_run(crumble.run(sc, out=tmp_path / "dict"), py_run)


def test_open_cli_run_row_counts(cli_run):
    for name in ("series", "events", "psd", "stages"):
        df = getattr(cli_run, name)
        assert len(df) == len(csv_rows(cli_run.path / f"{name}.csv")) - 1, name
        assert df.attrs["path"].endswith(f"{name}.csv")
    assert "platen_stress_Pa" in cli_run.series.columns
    assert cli_run.summary["scenario"] == "single_grain_pd"
    assert cli_run.steps[0] == 0 and cli_run.steps[-1] == cli_run.summary["steps"]


def test_grains_conserve_the_mass_of_the_summary(py_run):
    s = py_run.summary
    first, last = py_run.grains(py_run.steps[0]), py_run.grains()
    assert abs(first["mass"].sum() - s["mass_initial_kg"]) <= 1e-12 * s["mass_initial_kg"]
    assert abs(last["mass"].sum() + s["mass_removed_kg"] - s["mass_initial_kg"]) <= 1e-12 * s["mass_initial_kg"]
    assert abs(last["mass"].sum() - s["mass_final_kg"]) <= 1e-12 * s["mass_final_kg"]
    assert len(last["id"]) == s["grains_final"]
    assert last["position"].shape == (s["grains_final"], 3) and last["orientation"].shape == (s["grains_final"], 4)
    assert sorted(last["diameter"]) == pytest.approx(sorted(s["fragment_diameters_m"]), rel=1e-6)
    assert (last["generation"] == 1).all() and (last["parent"] == first["id"][0]).all()
    with pytest.raises(crumble.InputError, match="no grains snapshot at step 7"):
        py_run.grains(7)


def long_rigid_grain(max_steps):
    """The single grain unbreakable on a slow ramp: about 2e5 cheap steps (a progress call a second)."""
    sc = crumble.Scenario.load(SINGLE_GRAIN).set("breakage.type", "none").set("loading.ramp_time", 50)
    return sc.set("simulation.max_steps", max_steps).set("output.checkpoint_every", 1000)


def test_progress_callback_and_its_errors(tmp_path):
    seen = []

    class Enough(Exception):
        pass

    def record(d):
        seen.append(d)
        if len(seen) == 2:
            raise Enough("two calls")

    with pytest.raises(Enough, match="two calls"):
        crumble.run(long_rigid_grain(10**7), out=tmp_path / "p", progress=record)
    assert all(0 <= d["fraction"] <= 1 and d["elapsed_s"] > 0 for d in seen)
    assert 0 < seen[0]["step"] < seen[1]["step"] and seen[1]["grains"] == 1
    assert not (tmp_path / "p" / "summary.json").exists(), "a run the callback ended is a failed run"
    with pytest.raises(crumble.InputError, match="progress"):
        crumble.run(long_rigid_grain(10), out=tmp_path / "q", progress=42)


_INTERRUPTED = textwrap.dedent("""
    import sys, crumble
    sys.path.insert(0, sys.argv[3])
    from test_crumble import long_rigid_grain
    try:
        crumble.run(long_rigid_grain(10**7), out=sys.argv[2], progress=lambda d: print("progress", d["step"], flush=True))
    except KeyboardInterrupt as e:
        import signal
        print("interrupted:", e, "python handler back:", signal.getsignal(signal.SIGINT) is signal.default_int_handler,
              flush=True)
        sys.exit(7)
""")


def test_sigint_leaves_a_resumable_folder(tmp_path):
    out = tmp_path / "sigint"
    p = subprocess.Popen([sys.executable, "-c", _INTERRUPTED, str(SINGLE_GRAIN), str(out), os.path.dirname(__file__)],
                         stdout=subprocess.PIPE, text=True, env=python_env())
    assert p.stdout.readline().startswith("progress"), "the run reports its progress"
    p.send_signal(signal.SIGINT)
    rest = p.stdout.read()
    assert p.wait(timeout=60) == 7, rest
    assert "resume=True" in rest and "python handler back: True" in rest
    assert (out / "checkpoint.json").exists() and (out / "summary.json").exists()
    step = json.loads((out / "summary.json").read_text())["steps"]
    r = crumble.run(long_rigid_grain(step + 100), out=out, resume=True)
    assert r.summary["resumed_from_step"] > 0 and r.summary["steps"] == step + 100


def test_two_threads_give_the_single_thread_results(tmp_path, py_run):
    runs = {}

    def one(name):
        runs[name] = crumble.run(quick_scenario(), out=tmp_path / name)

    threads = [threading.Thread(target=one, args=(n,)) for n in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert set(runs) == {"a", "b"}
    assert_same_run(runs["a"], py_run)
    assert_same_run(runs["b"], py_run)


def test_open_works_without_the_compiled_module(cli_run):
    code = ("import sys; sys.modules['crumble._crumble'] = None; import crumble; "
            "r = crumble.open(sys.argv[1]); print(len(r.series), len(r.grains()['id']))")
    out = subprocess.run([sys.executable, "-c", code, str(cli_run.path)], check=True, capture_output=True, text=True,
                         env=python_env()).stdout.split()
    assert out == [str(len(cli_run.series)), str(cli_run.summary["grains_final"])]


def test_compare_returns_the_table_and_the_runs(tmp_path):
    sc = quick_scenario().set("simulation.max_steps", 60).set("breakage.type", "none")
    c = crumble.compare(sc, out=tmp_path / "cmp", vary={"engine.solver_iterations": [300, 1000]})
    assert c.status == 0 and len(c.table) == 2 and len(c.runs) == 2
    for r in c.runs.values():
        assert r.summary["steps"] == 60
    with pytest.raises(crumble.InputError, match="warp"):
        crumble.compare(sc, out=tmp_path / "bad", vary={"engine.type": ["warp"]})


# ---- the examples (examples/python/), shortened


@pytest.mark.parametrize("script,args,png", [
    ("criteria_2d.py", ["--strain-rate", "50", "--stop-strain", "0.08"], "criteria_2d.png"),
    ("spacing_sweep.py", ["--values", "0.15,0.12"], "spacing_sweep.png"),
])
def test_example_writes_its_figure(tmp_path, script, args, png):
    subprocess.run([sys.executable, str(ROOT / "examples" / "python" / script), "--out", str(tmp_path), *args],
                   check=True, env=python_env(), cwd=ROOT, timeout=600)
    assert (tmp_path / png).stat().st_size > 10000
