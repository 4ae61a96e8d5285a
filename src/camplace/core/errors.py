"""Errors that the CLI turns into one clear line and a non-zero exit code.

Library code never names a command-line flag. An error about a parameter of a library
call (``workers``, ``max_memory_bytes``, a solver option, ...) says so with
``InputError(message, option="workers")``: the message names the parameter the way
the library spells it, and the CLI layer (camplace.cli) rewrites ``option`` into the
flag the user typed (``--workers``) when it prints the line.
"""

from __future__ import annotations


class CamplaceError(Exception):
    """A failure the user can act on; the message is shown as-is (one line)."""

    exit_code = 1


class InputError(CamplaceError):
    """Bad input: a file, a key path or an option that does not hold what is expected.

    option: the library parameter the error is about (None: a file / key path that the
    message itself names)."""

    exit_code = 2

    def __init__(self, message: str, *, option: str | None = None) -> None:
        super().__init__(message)
        self.option = option


class Interrupted(CamplaceError):
    """The user stopped the run (Ctrl-C) before there was a placement to write."""

    exit_code = 130
