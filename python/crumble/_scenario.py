"""crumble.Scenario: a scenario document and its ``--set`` assignments. Reading, the
assignments and every check are the command line's own (the compiled module)."""

import copy
import json
import os

from ._errors import InputError
from ._native import native


def value_text(path, value):
    """The text of ``--set path=value`` for a Python value: a str as given (the command line
    reads it as JSON when it is JSON, else as a string), anything else as JSON."""
    if isinstance(value, str):
        return value
    try:
        return json.dumps(value, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise InputError(f"/{path.replace('.', '/')}: {value!r} is not a JSON value ({e})",
                         "/" + path.replace(".", "/")) from None


class Scenario:
    """A scenario: ``Scenario.load(path)`` (the file, read as ``crumble run`` reads it) or
    ``Scenario(dict)``; ``.set("breakage.criterion", "tresca")`` as ``--set``; ``.validate()``
    as ``crumble validate``; ``.to_dict()`` the document with the assignments applied."""

    def __init__(self, document, source="scenario"):
        if isinstance(document, Scenario):
            self._doc, self._sets = copy.deepcopy(document._doc), list(document._sets)
            self.source, self.path = document.source, document.path
            return
        if not isinstance(document, dict):
            raise InputError(f"{source}: a scenario is a JSON object (dict), got {type(document).__name__}")
        self._doc = copy.deepcopy(document)
        self._sets = []
        self.source = source
        self.path = None

    @classmethod
    def load(cls, path):
        """The scenario file at ``path`` (errors name the file, line and JSON path)."""
        path = os.fspath(path)
        sc = cls(json.loads(native().load_scenario(path)), source=path)
        sc.path = path
        return sc

    def __repr__(self):
        return f"crumble.Scenario({self.source!r}, sets={self._sets!r})"

    @property
    def sets(self):
        """The ``path=value`` assignments, in order."""
        return list(self._sets)

    def set(self, path, value):
        """Override a value, as ``--set path=value`` (dotted path). Returns the scenario."""
        if not isinstance(path, str) or not path or "=" in path:
            raise InputError(f"--set {path!r}: expected a dotted scenario path such as breakage.criterion")
        self._sets.append(f"{path}={value_text(path, value)}")
        return self

    def copy(self):
        return Scenario(self)

    def text(self):
        """The document as JSON text (before the assignments)."""
        try:
            return json.dumps(self._doc, allow_nan=False)
        except ValueError as e:
            raise InputError(f"{self.source}: {e} (JSON has no NaN or infinity)") from None

    def to_dict(self):
        """The document with the assignments applied (defaults not filled in: see effective())."""
        return json.loads(native().document(self.text(), self.source, self._sets))

    def validate(self, seed=None, threads=None):
        """The checks of ``crumble validate``: raises crumble.InputError naming the JSON path, or
        returns {"notes", "grains", "engine", "breakage", "fragments", "effective"}."""
        return json.loads(native().validate(self.text(), self.source, self._sets, seed, threads))

    def effective(self):
        """The scenario as a run would run it, every default filled in."""
        return self.validate()["effective"]


def as_scenario(scenario):
    """A Scenario from a Scenario, a dict or a file path."""
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, dict):
        return Scenario(scenario)
    if isinstance(scenario, (str, os.PathLike)):
        return Scenario.load(scenario)
    raise InputError(f"scenario: expected a crumble.Scenario, a dict or a file path, got {type(scenario).__name__}")
