"""The one exception family of slipwave.

Every error that bad input can cause is a :class:`SlipwaveError`, so a caller
(or the workflow) can catch them all and show the message as it is: each
message names the file, the place in it and what is wrong.
"""

from __future__ import annotations

from collections.abc import Mapping
from os import PathLike
from typing import Any


class SlipwaveError(Exception):
    """Base class of every error slipwave raises on bad input or failed computation."""


class ConfigError(SlipwaveError):
    """A configuration or campaign table is invalid."""


class AcquisitionError(SlipwaveError):
    """An acquisition file cannot be read.

    Parameters
    ----------
    path
        The file being read.
    message
        What is wrong.
    line
        1-based line number in the file, when the problem has one.
    column
        Name (or 1-based index) of the column, when the problem has one.

    """

    def __init__(
        self,
        path: str | PathLike[str],
        message: str,
        *,
        line: int | None = None,
        column: str | int | None = None,
    ) -> None:
        self.path = str(path)
        self.line = line
        self.column = column
        self.reason = message
        where = self.path
        if line is not None:
            where += f", line {line}"
        if column is not None:
            where += f", column {column!r}" if isinstance(column, str) else f", column {column}"
        super().__init__(f"{where}: {message}")


class SolverError(SlipwaveError):
    """An increment of the contact solver did not converge.

    Parameters
    ----------
    step
        Index of the load step that failed.
    residual
        Relative complementarity residual reached (``nan`` if none).
    message
        What happened.

    """

    def __init__(self, step: int, residual: float, message: str) -> None:
        self.step = step
        self.residual = residual
        super().__init__(f"step {step}: {message} (relative residual {residual:.3g})")


def warning_lines(attrs: Mapping[Any, Any]) -> list[str]:
    r"""The warnings stored in ``attrs["warnings"]``, one per line, as a list.

    Every Dataset and DataFrame slipwave makes keeps its warnings that way
    (text, one warning per line), which netCDF stores as it is.

    Parameters
    ----------
    attrs
        The ``attrs`` of a Dataset or DataFrame.

    Returns
    -------
    list of str
        The non-empty lines.

    Examples
    --------
    >>> warning_lines({"warnings": "first\n\nsecond"})
    ['first', 'second']
    >>> warning_lines({})
    []
    """
    return [line for line in str(attrs.get("warnings") or "").splitlines() if line]
