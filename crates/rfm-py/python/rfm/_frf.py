"""FRFs as numpy arrays: :class:`FrfData`, and its conversions to pyuff and
SDynPy. Reading and writing files is done by the Rust crates (``frf::io``);
the conversions to pyuff go through a file that one library writes and the
other reads, so that each side's own codec decides every field."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from . import _rfm

if TYPE_CHECKING:
    from ._rfm import Case

_DIRECTIONS = {"ux": 1, "uy": 2, "uz": 3, "rx": 4, "ry": 5, "rz": 6}


def _units(kind: str) -> str:
    return {"receptance": "m/N", "mobility": "m/s/N", "accelerance": "m/s^2/N"}.get(kind, "m/N")


@dataclass
class FrfData:
    """Frequency response functions on model DOFs.

    ``h[k, o, i]`` is the response at ``outputs[o]`` to a unit force at
    ``inputs[i]`` at ``freq[k]`` Hz: the layout of SDynPy's and pyFBS's numpy
    functions (lines first), in SI units (``units``: ``m/N``, ``m/s/N`` or
    ``m/s^2/N``, or per volt, ``m/V``, when the reference is a voltage). A
    DOF is a ``(node, direction)`` pair with the direction ``"ux"``,
    ``"uy"``, ``"uz"``, ``"rx"``, ``"ry"`` or ``"rz"`` (or the UFF code 1-6
    of ``+X`` .. ``+RZ``). An output/input pair that was not measured is NaN
    at every line. ``coherence`` (optional) has the shape of ``h``;
    ``notes`` says what reading a file changed or passed over.
    """

    freq: np.ndarray
    h: np.ndarray
    outputs: list[tuple[int, str]]
    inputs: list[tuple[int, str]]
    kind: str = "receptance"
    units: str = ""
    coherence: np.ndarray | None = None
    notes: list[str] = field(default_factory=list, compare=False)

    def __post_init__(self) -> None:
        self.freq = np.ascontiguousarray(self.freq, dtype=np.float64)
        self.h = np.ascontiguousarray(self.h, dtype=np.complex128)
        if self.h.ndim == 2:
            self.h = self.h[:, :, np.newaxis]
        self.outputs = [(int(n), _name(d)) for n, d in self.outputs]
        self.inputs = [(int(n), _name(d)) for n, d in self.inputs]
        self.kind = str(self.kind).lower()
        if not self.units:
            self.units = _units(self.kind)
        if self.coherence is not None:
            self.coherence = np.ascontiguousarray(self.coherence, dtype=np.float64)
        expected = (self.freq.shape[0], len(self.outputs), len(self.inputs))
        if self.freq.ndim != 1 or self.h.shape != expected:
            from .errors import DataError

            raise DataError(
                f"h has shape {self.h.shape}; (n_freq, n_out, n_in) is {expected} for {self.freq.shape[0]} lines, "
                f"{len(self.outputs)} outputs and {len(self.inputs)} inputs"
            )

    @property
    def omega(self) -> np.ndarray:
        """The lines in rad/s."""
        return 2.0 * np.pi * self.freq

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(n_freq, n_out, n_in)``."""
        return self.h.shape  # type: ignore[return-value]

    def write_uff(self, path: str | os.PathLike[str], binary: bool = False) -> None:
        """Writes the FRFs as UFF dataset 58 (ASCII, or binary 58b), complex
        double, each DOF as ``+X`` .. ``+RZ`` of its node, with the
        coherence after each FRF."""
        _rfm.write_uff(self, Path(path), binary)

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        """Writes the FRFs as rfm's CSV (every digit of a double; the
        coherence is not written)."""
        _rfm.write_csv(self, Path(path))

    def to_pyuff(self) -> list[dict[str, Any]]:
        """The FRFs as the dataset-58 dicts pyuff reads from the file
        :meth:`write_uff` writes (binary, so every double is kept): one per
        measured pair, followed by its coherence when there is one."""
        pyuff = _import("pyuff", "to_pyuff")
        with tempfile.TemporaryDirectory(prefix="rfm-") as tmp:
            path = Path(tmp) / "frfs.uff"
            self.write_uff(path, binary=True)
            sets = pyuff.UFF(str(path)).read_sets()
        return sets if isinstance(sets, list) else [sets]

    @classmethod
    def from_pyuff(cls, datasets: dict[str, Any] | Sequence[dict[str, Any]], case: Case | None = None) -> FrfData:
        """FRFs from pyuff's dataset-58 dicts (FRFs, and coherences of the
        same channels): pyuff writes them (binary, every double kept) and
        :func:`rfm.read_uff` reads them, with ``case`` as it reads a file."""
        pyuff = _import("pyuff", "from_pyuff")
        if isinstance(datasets, dict):
            datasets = [datasets]
        with tempfile.TemporaryDirectory(prefix="rfm-") as tmp:
            path = Path(tmp) / "frfs.uff"
            uff = pyuff.UFF(str(path))
            uff.write_sets([dict(d, binary=1) for d in datasets], mode="add")
            return read_uff(path, case)

    def to_sdynpy(self) -> Any:
        """The FRFs as an SDynPy ``TransferFunctionArray`` (needs SDynPy),
        indexed ``[output, input]`` with the lines last, as SDynPy keeps
        them."""
        sdpy = _import("sdynpy", "to_sdynpy")
        outputs = sdpy.coordinate_array([n for n, _ in self.outputs], [_DIRECTIONS[d] for _, d in self.outputs])
        inputs = sdpy.coordinate_array([n for n, _ in self.inputs], [_DIRECTIONS[d] for _, d in self.inputs])
        coordinate = sdpy.coordinate.outer_product(outputs, inputs)
        ordinate = np.moveaxis(self.h, 0, -1)
        return sdpy.data_array(sdpy.data.FunctionTypes.FREQUENCY_RESPONSE_FUNCTION, self.freq, ordinate, coordinate)

    def __repr__(self) -> str:
        f = self.freq
        band = f"{f[0]:g} to {f[-1]:g} Hz" if len(f) else "no lines"
        return (
            f"FrfData({self.kind}, {self.units}, {len(f)} lines {band}, {len(self.outputs)} outputs x "
            f"{len(self.inputs)} inputs{', with coherence' if self.coherence is not None else ''})"
        )


def _name(direction: Any) -> str:
    """A direction as its name: ``"uy"`` stays, a UFF code 1-6 is named."""
    if isinstance(direction, (int, np.integer)):
        names = {v: k for k, v in _DIRECTIONS.items()}
        if int(direction) in names:
            return names[int(direction)]
        from .errors import DataError

        raise DataError(f"direction {direction}: UFF codes 1 to 6 are +X .. +RZ")
    return str(direction).strip().lower()


def _import(module: str, what: str) -> Any:
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as e:
        raise ImportError(f"FrfData.{what} needs the package {module} (pip install {module})") from e


def read_uff(path: str | os.PathLike[str], case: Case | None = None) -> FrfData:
    """Reads measured FRFs from a universal file (dataset 58, ASCII or binary
    58b) or rfm's CSV. With ``case``, as the case reads its data (its channel
    map, mask, calibrations, band and exclusions); without, test directions
    ``+X`` .. ``+RZ`` are ``ux`` .. ``rz`` of the node with the same number
    (``-X`` negates). The FRFs keep the file's kind; ``notes`` says what
    reading them changed."""
    data, notes = _rfm.read_measured(Path(path), case)
    data.notes = list(notes)
    return data
