"""The exceptions of the crumble package."""


class InputError(ValueError):
    """Bad input: a scenario value, an option, a run folder. The message is the command line's
    (it names the JSON path, e.g. ``/breakage/criterion: unknown value 'x'``); ``path`` is the
    JSON path alone when the error has one, else ""."""

    def __init__(self, message, path=""):
        super().__init__(message)
        self.path = path


class RunFailed(RuntimeError):
    """A run that failed while running (a physics guard, a backend error): the command line's
    exit status 1. ``reason`` says why; ``run`` is the output folder (crumble.Run)."""

    def __init__(self, reason, run=None):
        super().__init__(reason)
        self.reason = reason
        self.run = run
