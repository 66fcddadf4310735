"""crumble.registry, crumble.run (in-process, the command line's run pipeline) and
crumble.compare / crumble.sweep (the crumble binary as a subprocess: they fork one process
per setting anyway)."""

import json
import os
import shutil
import signal
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from ._errors import InputError, RunFailed
from ._native import native
from ._run import Run, read_csv
from ._scenario import as_scenario, value_text


@dataclass(frozen=True)
class Option:
    """One row of an option table (``crumble list --options NAME``)."""
    key: str
    type: str
    default: object  # None when it depends on other options (default_text says how)
    default_text: str
    range: str
    unit: str
    doc: str
    choices: tuple = ()
    required: bool = False
    optional: bool = False


@dataclass(frozen=True)
class Implementation:
    """A registered engine, breakage model, fragment builder or scenario section."""
    name: str
    description: str
    options: tuple
    dimensions: tuple = ()
    variants: tuple = ()  # the criteria of the stress model


@dataclass(frozen=True)
class Registry:
    """What this build contains: ``engines``, ``models``, ``builders``, ``sections`` (the
    scenario's own sections: output, simulation, ...), ``criteria`` (model name -> its
    criteria), ``presets`` (the fidelity presets: names and knobs), ``not_compiled``,
    ``methods`` (the named methods: name, description and the settings each fills in)."""
    engines: tuple
    models: tuple
    builders: tuple
    sections: tuple
    criteria: dict
    presets: dict
    not_compiled: tuple = field(default=())
    methods: tuple = field(default=())

    def find(self, name):
        """The implementations or sections called ``name``."""
        return [i for t in (self.engines, self.models, self.builders, self.sections) for i in t if i.name == name]


def _implementation(d):
    opts = tuple(Option(o["key"], o["type"], o["default"], o["default_text"], o["range"], o["unit"], o["doc"],
                        tuple(o["choices"]), o["required"], o["optional"]) for o in d["options"])
    return Implementation(d["name"], d["description"], opts, tuple(d.get("dimensions", ())),
                          tuple(d.get("variants", ())))


def registry():
    """The registry and option tables of this build (what ``crumble list`` prints)."""
    j = json.loads(native().registry_json())
    seams = {k: tuple(_implementation(d) for d in j[k]) for k in ("engines", "models", "builders", "sections")}
    criteria = {m.name: m.variants for m in seams["models"] if m.variants}
    return Registry(criteria=criteria, presets=j["presets"], not_compiled=tuple(j["not_compiled"]),
                    methods=tuple(j["methods"]), **seams)


def _checked_int(name, v, lo, hi):
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise InputError(f"{name}: expected a whole number from {lo} to {hi}, got {v!r}")
    return v


def run(scenario, out, seed=None, threads=None, progress=None, resume=False, force=False, quiet=True,
        plots=False, packing_only=False):
    """Runs a scenario (a file path, a dict or a crumble.Scenario) into ``out`` in this process,
    through the pipeline ``crumble run`` uses; returns the crumble.Run. ``progress``: a callable
    given a dict (step, time_s, fraction, elapsed_s, eta_s, platen_stress_Pa, axial_strain,
    grains, breakage_events) about once a second of the loading. Ctrl-C (SIGINT) ends the run
    at the end of its step with every output and the checkpoint written, then raises
    KeyboardInterrupt; ``resume=True`` continues it. ``packing_only=True`` stops once the
    packing is settled and out/packing.json written (what compare and sweep do first). Bad
    input: crumble.InputError; a failure while running: crumble.RunFailed."""
    sc = as_scenario(scenario)
    if not isinstance(out, (str, os.PathLike)) or not os.fspath(out):
        raise InputError(f"out: expected an output folder path, got {out!r}")
    if progress is not None and not callable(progress):
        raise InputError(f"progress: expected a callable or None, got {type(progress).__name__}")
    req = native().RunRequest(sc.text(), sc.source, sc.sets)
    req.out = out = os.fspath(out)
    req.seed = _checked_int("seed", seed, 0, 2**64 - 1)
    req.threads = _checked_int("threads", threads, 1, 1024)
    req.force, req.resume, req.quiet, req.plots = bool(force), bool(resume), bool(quiet), bool(plots)
    req.packing_only = bool(packing_only)
    status, summary, reason = native().run(req, progress)
    if status == 130:
        raise KeyboardInterrupt(f"crumble: run interrupted ({reason}); outputs in {out}, "
                                "continue with crumble.run(..., resume=True)")
    if status == 143:
        raise SystemExit(143)
    if status != 0:
        raise RunFailed(reason, Run(out) if os.path.isdir(out) else None)
    return Run(out)


# ---- compare and sweep: the binary


def binary():
    """The crumble binary: $CRUMBLE_BINARY, the build tree's (build/crumble beside
    build/python), the installed one (PREFIX/bin beside PREFIX/lib/crumble/python), or PATH's."""
    here = Path(__file__).resolve().parent
    for c in (os.environ.get("CRUMBLE_BINARY"), here.parents[1] / "crumble", here.parents[3] / "bin" / "crumble",
              shutil.which("crumble")):
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return os.fspath(c)
    raise FileNotFoundError("the crumble binary was not found (set CRUMBLE_BINARY)")


def _call(args):
    """Runs the binary; a Ctrl-C is forwarded so that it ends cleanly, then re-raised."""
    p = subprocess.Popen([binary()] + args, stderr=subprocess.PIPE, text=True)
    try:
        _, err = p.communicate()
    except KeyboardInterrupt:
        p.send_signal(signal.SIGINT)
        p.communicate()
        raise
    if p.returncode == 2:
        raise InputError(err.strip().splitlines()[-1] if err.strip() else "crumble: bad input (exit status 2)")
    if p.returncode in (130, 143):
        raise KeyboardInterrupt(f"crumble {args[0]} interrupted")
    return p.returncode, err


def _scenario_args(scenario, tmp):
    """The scenario file and --set arguments of a command line (a dict: written to tmp)."""
    sc = as_scenario(scenario)
    path = sc.path
    if path is None:
        path = os.path.join(tmp, "scenario.json")
        with open(path, "w", encoding="utf-8") as f:
            f.write(sc.text())
    args = [path]
    for s in sc.sets:
        args += ["--set", s]
    return args


def _common_args(out, sets, seed, threads, jobs, force, quiet):
    args = ["--out", os.fspath(out)]
    for k, v in (sets or {}).items():
        args += ["--set", f"{k}={value_text(k, v)}"]
    for name, v, lo, hi in (("--seed", seed, 0, 2**64 - 1), ("--threads", threads, 1, 1024), ("--jobs", jobs, 1, 64)):
        if _checked_int(name, v, lo, hi) is not None:
            args += [name, str(v)]
    return args + (["--force"] if force else []) + (["--quiet"] if quiet else [])


def _values(path, values):
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise InputError(f"{path}: expected a list of values, got {values!r}")
    return ",".join(value_text(path, v) for v in values)


@dataclass
class Comparison:
    """What compare / sweep wrote: ``table`` (comparison.csv, or sweep.csv for a sweep),
    ``comparison`` (comparison.csv), ``runs`` (folder name -> crumble.Run), ``path``,
    ``status`` (0, or 1 when a setting failed: its row says why) and the command's stderr."""
    path: Path
    table: object
    comparison: object
    runs: dict
    status: int
    log: str


def _result(out, status, log, table_name):
    out = Path(out)
    runs = {d.name: Run(d) for d in sorted(out.iterdir()) if d.is_dir() and (d / "effective_scenario.json").exists()}
    return Comparison(out, read_csv(out / table_name), read_csv(out / "comparison.csv"), runs, status, log)


def compare(scenario, out, vary, sets=None, seed=None, threads=None, jobs=None, force=False, quiet=True):
    """``crumble compare``: ``vary`` maps a scenario path to its values (every combination
    runs), ``sets`` maps a path to a value fixed for all. Returns a Comparison (table:
    comparison.csv). Runs the crumble binary (docs/python.md)."""
    if not isinstance(vary, dict) or not vary:
        raise InputError("vary: expected a dict of scenario path -> list of values")
    with tempfile.TemporaryDirectory(prefix="crumble_py_") as tmp:
        args = ["compare"] + _scenario_args(scenario, tmp) + _common_args(out, sets, seed, threads, jobs, force, quiet)
        for k, v in vary.items():
            args += ["--vary", f"{k}={_values(k, v)}"]
        status, log = _call(args)
    return _result(out, status, log, "comparison.csv")


def sweep(scenario=None, out=None, params=None, reference=None, metrics=None, study=None, sets=None, seed=None,
          threads=None, jobs=None, force=False, quiet=True):
    """``crumble sweep``: ``params`` maps a scenario path to its values, coarse to fine
    (``reference``: one value per path, default the last); ``metrics`` names the metrics; or
    ``study`` names a study file. Returns a Comparison (table: sweep.csv). Runs the binary."""
    if out is None:
        raise InputError("out: the sweep's output folder is required")
    with tempfile.TemporaryDirectory(prefix="crumble_py_") as tmp:
        args = ["sweep"] + (["--study", os.fspath(study)] if study else _scenario_args(scenario, tmp))
        args += _common_args(out, sets, seed, threads, jobs, force, quiet)
        for k, v in (params or {}).items():
            args += ["--param", k, "--values", _values(k, v)]
        for r in reference or ():
            args += ["--reference", value_text("reference", r)]
        for m in metrics or ():
            args += ["--metric", m]
        status, log = _call(args)
    return _result(out, status, log, "sweep.csv")
