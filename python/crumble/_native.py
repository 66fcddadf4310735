"""The compiled module (_crumble, python/module.cpp), when it was built. crumble.open and the
readers work without it; scenarios, runs and the registry need it."""

try:
    from . import _crumble as module
    why_missing = ""
except ImportError as e:  # built without pybind11, or for another Python version
    import glob
    import os

    module = None
    _here = os.path.dirname(os.path.abspath(__file__))
    why_missing = str(e) if glob.glob(os.path.join(_here, "_crumble*.so")) else f"no _crumble*.so in {_here}"


def native():
    """The compiled module, or ImportError saying how to get it."""
    if module is None:
        raise ImportError("crumble's compiled module is not available (" + why_missing + "); install pybind11-dev "
                          "and python3-dev (scripts/setup.sh does) and rebuild; crumble.open works without it")
    return module
