"""Errors that map to the exit codes of DESIGN.md."""


class SceneError(Exception):
    """Bad input: one line naming key, value and rule. Exit code 2."""

    exit_code = 2


class NumericalError(Exception):
    """Numerical failure (NaN/inf, particle out of the domain, dt collapse). Exit code 3."""

    exit_code = 3


class Interrupted(Exception):
    """Stopped by SIGTERM/SIGUSR1 (a scheduler's wall-time limit) after writing a
    checkpoint. Exit code 75 (EX_TEMPFAIL: rerun with --restart to continue)."""

    exit_code = 75
