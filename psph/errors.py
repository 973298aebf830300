"""Errors that map to the command line's exit codes (docs/guide/exit_codes.md)."""


class SceneError(Exception):
    """Bad input: one line naming key, value and rule. Exit code 2."""

    exit_code = 2


class SceneRule(ValueError):
    """Raised inside a scene model's validator: the key, the value and the rule that
    `psph.config.load.validate` turns into one SceneError line."""

    def __init__(self, key: str, value, rule: str):
        super().__init__(rule)
        self.key, self.value, self.rule = key, value, rule


class NumericalError(Exception):
    """Numerical failure (NaN/inf, particle out of the domain, dt collapse). Exit code 3."""

    exit_code = 3


class Interrupted(Exception):
    """Stopped by SIGTERM/SIGUSR1 (a scheduler's wall-time limit) after writing a
    checkpoint. Exit code 75 (EX_TEMPFAIL: rerun with --restart to continue)."""

    exit_code = 75


class OutputError(Exception):
    """The output file system cannot take the next snapshot or checkpoint (full disk or
    quota): one line naming the file, the cause and the last complete checkpoint. Exit
    code 74 (EX_IOERR)."""

    exit_code = 74


# Stop signals that arrive outside a run (while Python imports, or after the run has
# finished and restored its handlers): recorded, never the default action, which would
# kill a finished run (a scheduler or jobs/local.sh sends them at a fixed wall time).
EARLY_STOP_SIGNALS: list[int] = []


def record_stop_signals() -> None:
    """Install the recording handler for SIGTERM and SIGUSR1 (main thread only)."""
    import signal

    def _record(signum, frame) -> None:
        EARLY_STOP_SIGNALS.append(signum)

    for sig in (signal.SIGTERM, signal.SIGUSR1):
        signal.signal(sig, _record)
