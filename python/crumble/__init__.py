"""crumble from Python (docs/python.md): build, run and read crumble scenarios.

    import crumble
    r = crumble.run("scenarios/single_grain_pd.json", out="/tmp/sg")
    r.summary["crushing_force_N"], r.series, r.grains()

crumble.open, crumble.Run and the readers are pure Python (numpy, pandas); registry, Scenario
checks and run need the compiled module (_crumble, built with pybind11); compare and sweep
call the crumble binary."""

from ._api import Comparison, Implementation, Option, Registry, binary, compare, registry, run, sweep
from ._errors import InputError, RunFailed
from ._native import module as _module
from ._run import Run, read_grains_vtp
from ._run import open_run as open  # noqa: A001 (crumble.open, as the issue names it)
from ._scenario import Scenario
from ._version import __version__

version = _module.version if _module is not None else None

__all__ = ["Comparison", "Implementation", "InputError", "Option", "Registry", "Run", "RunFailed", "Scenario",
           "binary", "compare", "open", "read_grains_vtp", "registry", "run", "sweep", "version", "__version__"]
