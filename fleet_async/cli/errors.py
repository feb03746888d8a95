"""The one error type of the command line: a message for the user and an exit code."""

from __future__ import annotations

__all__ = ["CliError"]


class CliError(Exception):
    """A problem the user can act on; ``main`` prints it as ``fleet-async: error: <message>``.

    Args:
        message: What went wrong and what to do about it.
        exit_code: The process exit code (2: bad input, as argparse uses).
    """

    def __init__(self, message: str, exit_code: int = 2) -> None:
        super().__init__(message)
        self.exit_code = exit_code
