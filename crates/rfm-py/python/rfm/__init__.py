"""rfm: FRF-based finite element model updating of damped structures.

Compare a model with measured FRFs, find which physical effect is missing,
update its parameters and close the loop, from Python, with numpy arrays in
and out. The numerics are the Rust crates of the ``rfm`` command; every
result serialises as the command's ``--json`` and saves the command's files.

>>> import rfm
>>> case = rfm.load_case("cases/tutorial/l-frame.toml")
>>> d = rfm.diagnose(case)              # doctest: +SKIP
>>> d.leader.description                # doctest: +SKIP
'flexible, lossy joint at node 13 (element 13; kr; viscous)'
>>> result = rfm.fix(case, steps=3)     # doctest: +SKIP
>>> result.save("out/fix")              # doctest: +SKIP

Long calls release the GIL, run on :func:`set_num_threads` threads, stop
cleanly on Ctrl-C, and report their stages to the ``rfm`` logger and to an
optional ``progress`` callback (or a tqdm bar with ``progress=True``).
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any, Callable, Union

from . import _rfm, plot
from ._frf import FrfData, read_uff
from ._rfm import Case, get_num_threads, set_num_threads
from ._results import Candidate, Comparison, Diagnosis, FixResult, Parameter, Step, UpdateResult
from .errors import ArgumentError, CaseError, DataError, NotConverged, NumericsError, OutputError, RfmError

__version__: str = _rfm.__version__

__all__ = [
    "ArgumentError",
    "Candidate",
    "Case",
    "CaseError",
    "Comparison",
    "DataError",
    "Diagnosis",
    "FixResult",
    "FrfData",
    "NotConverged",
    "NumericsError",
    "OutputError",
    "Parameter",
    "RfmError",
    "Step",
    "UpdateResult",
    "compare",
    "diagnose",
    "fix",
    "get_num_threads",
    "load_case",
    "plot",
    "read_uff",
    "set_num_threads",
    "update",
]

logger = logging.getLogger("rfm")

#: What ``progress=`` takes: None, a callable given each stage's message,
#: or True for a tqdm bar.
Progress = Union[None, bool, Callable[[str], Any]]
#: What ``measured=`` takes: None (the case's own data), a file, or FRFs.
Measured = Union[None, str, "os.PathLike[str]", FrfData]


def load_case(path: str | os.PathLike[str]) -> Case:
    """Loads and checks a case file (TOML). A mistake raises
    :class:`CaseError` naming the file, line and column."""
    return _rfm.load_case(Path(path))


class _Reporter:
    """Every stage to the ``rfm`` logger, and to the caller's callback or a
    tqdm bar."""

    def __init__(self, progress: Progress, what: str) -> None:
        self.callback: Callable[[str], Any] | None = None
        self.bar: Any = None
        if progress is True:
            try:
                from tqdm.auto import tqdm
            except ImportError as e:
                raise ImportError("progress=True draws a tqdm bar: pip install tqdm") from e
            self.bar = tqdm(desc=what, unit=" stage")
        elif callable(progress):
            self.callback = progress
        elif progress not in (None, False):
            raise ArgumentError("progress: a callable taking a message, True for a tqdm bar, or None")

    def __call__(self, message: str) -> None:
        logger.info("%s", message)
        if self.bar is not None:
            self.bar.set_postfix_str(message[:60])
            self.bar.update(1)
        if self.callback is not None:
            self.callback(message)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _with_reporter(what: str, progress: Progress, call: Callable[[_Reporter], Any]) -> Any:
    reporter = _Reporter(progress, what)
    try:
        return call(reporter)
    finally:
        reporter.close()


def _measured(measured: Measured) -> Any:
    if measured is None or isinstance(measured, FrfData):
        return measured
    return Path(measured)


def _checked(result: Any, check: bool, what: str) -> Any:
    code, meaning = result._inner.exit()
    if check and code != 0:
        raise NotConverged(f"{what}: {meaning} (exit code {code} of the rfm command)", result, code)
    return result


def compare(case: Case, measured: Measured = None, bands: str = "auto", progress: Progress = None) -> Comparison:
    """Compares the case's model with its measured FRFs (or ``measured``: a
    file, or an :class:`FrfData` on the case's DOFs), as ``rfm compare``:
    errors per channel and band, the fitted gains, the modes paired by MAC.
    ``bands``: ``auto``, ``resonances``, ``octave``, ``third-octave`` or
    edges in Hz such as ``"0,50,120,400"``."""
    return _with_reporter(
        "compare", progress, lambda r: Comparison(_rfm.compare(case, _measured(measured), bands, r))
    )


def diagnose(case: Case, measured: Measured = None, progress: Progress = None) -> Diagnosis:
    """Fits every candidate effect (flexible and lossy joints and supports,
    masses, stiffness and mass changes, local damping) and ranks them by
    BIC, as ``rfm diagnose``."""
    return _with_reporter("diagnose", progress, lambda r: Diagnosis(_rfm.diagnose(case, _measured(measured), r)))


def update(
    case: Case,
    method: str | None = None,
    lines: int | None = None,
    iterations: int | None = None,
    progress: Progress = None,
    check: bool = True,
    *,
    measured: Measured = None,
) -> UpdateResult:
    """Updates the case's ``[update]`` parameters, as ``rfm update``:
    ``method`` ``"rfm"`` or ``"output-error"`` (default: the case's),
    ``lines`` to fit that many measured lines, ``iterations`` a limit;
    ``measured`` (a file or an :class:`FrfData`) instead of the case's
    data, as ``--measured``: the updated case then reads them. Unless
    ``check=False``, an update that does not converge raises
    :class:`NotConverged` carrying the result."""
    result = _with_reporter(
        "update",
        progress,
        lambda r: UpdateResult(_rfm.update(case, _measured(measured), method, lines, iterations, r)),
    )
    return _checked(result, check, "update")


def fix(
    case: Case, steps: int = 3, progress: Progress = None, check: bool = True, *, measured: Measured = None
) -> FixResult:
    """Closes the loop, as ``rfm fix``: diagnose, add the recommended effect,
    update, and again until nothing significant remains (at most ``steps``
    effects); ``measured`` (a file or an :class:`FrfData`) instead of the
    case's data, as ``--measured``: every step's case then reads them.
    Unless ``check=False``, a loop that ends without the data explained
    down to their noise raises :class:`NotConverged` carrying the result."""
    result = _with_reporter("fix", progress, lambda r: FixResult(_rfm.fix(case, _measured(measured), steps, r)))
    return _checked(result, check, "fix")
