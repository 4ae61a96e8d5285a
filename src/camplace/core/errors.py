"""Errors that the CLI turns into one clear line and a non-zero exit code."""

from __future__ import annotations


class CamplaceError(Exception):
    """A failure the user can act on; the message is shown as-is (one line)."""

    exit_code = 1


class InputError(CamplaceError):
    """Bad input: a file, a key path or an option that does not hold what is expected."""

    exit_code = 2


class Interrupted(CamplaceError):
    """The user stopped the run (Ctrl-C) before there was a placement to write."""

    exit_code = 130
