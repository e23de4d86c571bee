"""The exceptions of rfm: one hierarchy under :class:`RfmError`.

Each message is the text the ``rfm`` command prints for the same error (a
case error names the file, line and column and shows the line), and
``exit_code`` is the code the command would exit with.
"""

from __future__ import annotations

from typing import Any


class RfmError(Exception):
    """Any error of rfm. ``exit_code`` is the ``rfm`` command's code for it."""

    exit_code: int = 1


class CaseError(RfmError, ValueError):
    """A case file (or a case given as text or a dict) is malformed or
    inconsistent; the message names the file, line and column."""

    exit_code = 3


class DataError(RfmError, ValueError):
    """Measured data are malformed or do not fit the case (a channel the
    model lacks, lines out of order, a value that is not finite, ...)."""

    exit_code = 3


class ArgumentError(RfmError, ValueError):
    """An argument of a function is wrong (the command line's usage error)."""

    exit_code = 2


class NumericsError(RfmError, ArithmeticError):
    """The model cannot be evaluated (a singular dynamic stiffness at a
    line) or a fit produced numbers that are not finite."""

    exit_code = 4


class OutputError(RfmError, OSError):
    """Outputs could not be written (none of them were), or another run is
    writing into the same folder."""

    exit_code = 6


class NotConverged(RfmError):
    """An update or a loop ended without the data explained down to their
    noise. ``result`` holds the best result reached (what the ``rfm``
    command writes in that case too); pass ``check=False`` to get it
    returned instead."""

    def __init__(self, message: str, result: Any, exit_code: int) -> None:
        super().__init__(message)
        self.result = result
        self.exit_code = exit_code
