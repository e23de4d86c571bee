"""The results of the workflow. Each wraps the Rust result (``rfm._rfm``):
``to_dict()`` is the ``rfm`` command's ``--json`` for the same run (parsed
from the same serialisation of the same library struct, so fields the
library adds appear here unchanged), ``save(folder)`` writes the files the
command writes, and the attributes read ``to_dict()``."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from . import _rfm
from ._frf import FrfData


class _Result:
    _inner: Any

    def to_dict(self) -> dict[str, Any]:
        """What the ``rfm`` command prints with ``--json`` for this run (a
        new copy each call)."""
        return json.loads(self._json)

    @cached_property
    def _json(self) -> str:
        return self._inner.json()

    @cached_property
    def _doc(self) -> dict[str, Any]:
        return self.to_dict()


class _MeshChecked(_Result):
    """A result that carries the mesh check (compare, diagnose, fix)."""

    @property
    def mesh(self) -> dict[str, Any] | None:
        """The model against itself with every element cut in two, at the
        lines the misfit is read on (``change``, ``misfit``,
        ``refined_misfit``, ``parts``), or None for a model without beams
        or above 10,000 DOFs: a ``refined_misfit`` well below ``misfit``
        says the mesh, not missing physics, decides part of the misfit."""
        return self._doc.get("mesh")


class Comparison(_MeshChecked):
    """The model against the measured FRFs (``rfm compare``)."""

    def __init__(self, inner: _rfm.Comparison) -> None:
        self._inner = inner

    @cached_property
    def measured(self) -> FrfData:
        """The measured FRFs, in the kind they were measured in."""
        return self._inner.measured()

    @cached_property
    def model(self) -> FrfData:
        """The model's FRFs on the measured channels and lines, in the same
        kind, times the gains fitted to the data (if the case has any)."""
        return self._inner.model()

    @property
    def correlation(self) -> dict[str, Any]:
        """Errors per channel, per band and in total (``compare --json``'s
        ``correlation``)."""
        return self._doc["correlation"]

    @property
    def misfit(self) -> float:
        """The complex-log misfit over every channel and line."""
        return float(self._doc["correlation"]["total"]["log_misfit"])

    @cached_property
    def mac(self) -> tuple[list[list[float]], list[float], list[float]] | None:
        """The MAC matrix of the measured modes (rows) against the model's
        (columns), with their frequencies in Hz; None when the modes could
        not be compared."""
        return self._inner.mac()

    @property
    def modes(self) -> dict[str, Any] | None:
        """Measured (LSCF) against model modes with the MAC matrix, or None
        when they could not be compared (``modes_error`` says why)."""
        return self._doc.get("modes")

    def save(self, folder: str | os.PathLike[str], frequency_axis: str = "auto") -> list[Path]:
        """Writes what ``rfm compare --out FOLDER`` writes (``compare.json``,
        ``report.html``, the figures), all or nothing; returns the files."""
        return list(self._inner.save(Path(folder), frequency_axis))

    def __repr__(self) -> str:
        return f"<rfm.Comparison misfit {self.misfit:.4g}, {len(self.correlation['channels'])} channels>"


@dataclass(frozen=True)
class Candidate:
    """A candidate effect as the diagnosis ranked it; ``raw`` is its entry in
    ``to_dict()['ranking']``."""

    rank: int
    kind: str
    description: str
    nodes: list[int]
    elements: list[int]
    delta_bic: float
    explained: float
    significant: bool
    plausible: bool
    values: dict[str, float]
    raw: dict[str, Any] = field(repr=False, compare=False)

    @classmethod
    def _of(cls, rank: int, r: dict[str, Any]) -> Candidate:
        return cls(
            rank=rank,
            kind=r["kind"],
            description=r["description"],
            nodes=list(r.get("nodes", [])),
            elements=list(r.get("elements", [])),
            delta_bic=float(r["delta_bic"]),
            explained=float(r["explained"]),
            significant=bool(r["significant"]),
            plausible=bool(r["plausible"]),
            values={p["name"]: float(p["value"]) for p in r.get("parameters", [])},
            raw=r,
        )


class Diagnosis(_MeshChecked):
    """Every candidate effect fitted and ranked (``rfm diagnose``)."""

    def __init__(self, inner: _rfm.DiagnosisResult) -> None:
        self._inner = inner

    @cached_property
    def ranking(self) -> list[Candidate]:
        """The candidates, best first (rank 1 first)."""
        return [Candidate._of(k + 1, r) for k, r in enumerate(self._doc["ranking"])]

    @property
    def leader(self) -> Candidate | None:
        """The candidate ranked first."""
        return self.ranking[0] if self.ranking else None

    @property
    def recommended(self) -> Candidate | None:
        """The effect to add: the best significant one at plausible values,
        or None when nothing is significant (or nothing plausible)."""
        rank = self._doc.get("recommended")
        return None if rank is None else self.ranking[rank - 1]

    @property
    def noise(self) -> float:
        """The noise level estimated from the data."""
        return float(self._doc["noise"])

    @property
    def nominal_misfit(self) -> float:
        """The misfit of the case's model as it is."""
        return float(self._doc["nominal_misfit"])

    def _rank(self, rank: int | None) -> int:
        if rank is not None:
            return rank
        recommended = self.recommended
        if recommended is None:
            from .errors import ArgumentError

            raise ArgumentError("no effect is recommended: give the rank of the effect to add")
        return recommended.rank

    def apply(self, rank: int | None = None) -> _rfm.Case:
        """The case with the effect of ``rank`` (default: the recommended
        one) added, as ``rfm diagnose --apply`` writes it."""
        return self._inner.apply(self._rank(rank))

    def save(self, path: str | os.PathLike[str], rank: int | None = None) -> Path | None:
        """Writes what ``rfm diagnose --apply RANK --out PATH`` writes: the
        case with the effect added (and beside it, when the case synthesises
        its data from a ``[truth]``, those data, whose path is returned; when
        the data were given as an ``FrfData``, a copy of the file written for
        them, ``PATH-measured.uff`` or ``.csv``, which the case reads)."""
        return self._inner.save(Path(path), self._rank(rank))

    def __repr__(self) -> str:
        lead = self.leader
        return f"<rfm.Diagnosis leader {lead.description!r} dBIC {lead.delta_bic:.1f}>" if lead else "<rfm.Diagnosis>"


@dataclass(frozen=True)
class Parameter:
    """An updated parameter: its value with its standard deviation (None
    without an uncertainty analysis, as after the RFM)."""

    name: str
    initial: float
    value: float
    std: float | None
    relative_std: float | None
    well_determined: bool | None
    truth: float | None


def _parameters(doc: dict[str, Any]) -> list[Parameter]:
    unc = (doc.get("uncertainty") or {}).get("parameters") or []
    out = []
    for i, p in enumerate(doc["parameters"]):
        u = unc[i] if i < len(unc) else None
        out.append(
            Parameter(
                name=p["name"],
                initial=float(p["initial"]),
                value=float(p["updated"]),
                std=None if u is None else float(u["std"]),
                relative_std=None if u is None else float(u["relative_std"]),
                well_determined=None if u is None else bool(u["well_determined"]),
                truth=p.get("truth"),
            )
        )
    return out


def _status_name(status: Any) -> str:
    return status if isinstance(status, str) else next(iter(status))


class UpdateResult(_Result):
    """The case's parameters updated (``rfm update``)."""

    def __init__(self, inner: _rfm.UpdateResult) -> None:
        self._inner = inner

    @property
    def status(self) -> str:
        """How the update ended (``converged``, ``stalled``, ...)."""
        return _status_name(self._doc["status"])

    @property
    def exit_code(self) -> int:
        """The code ``rfm update`` would exit with (0 only when converged)."""
        return self._inner.exit()[0]

    @property
    def parameters(self) -> list[Parameter]:
        """The parameters with their updated values and uncertainty."""
        return _parameters(self._doc)

    @property
    def misfit(self) -> float:
        """The residual the fit left (RMS per value)."""
        return float(self._doc["residual"])

    @cached_property
    def case(self) -> _rfm.Case:
        """The updated case (``updated.toml``), in memory."""
        return self._inner.case()

    def save(self, folder: str | os.PathLike[str], frequency_axis: str = "auto") -> list[Path]:
        """Writes what ``rfm update --out FOLDER`` writes (``results.json``,
        ``updated.toml``, ``report.html``, the figures), all or nothing; when
        the data were given as an ``FrfData``, a copy of the file written for
        them too (``measured.uff`` or ``measured.csv``), which
        ``updated.toml`` reads."""
        return list(self._inner.save(Path(folder), frequency_axis))

    def __repr__(self) -> str:
        return f"<rfm.UpdateResult {self.status}, misfit {self.misfit:.4g}>"


@dataclass(frozen=True)
class Step:
    """One step of the loop: the effect added (or taken out) and the misfit
    with it at its diagnosed values and after the update."""

    effect: Candidate
    removed: bool
    #: why the effect was taken out (with ``removed``)
    removed_because: str | None
    misfit_added: float
    misfit_updated: float
    status: str
    parameters: list[Parameter]
    case: _rfm.Case = field(repr=False)
    raw: dict[str, Any] = field(repr=False, compare=False)


class FixResult(_MeshChecked):
    """The loop closed (``rfm fix``)."""

    def __init__(self, inner: _rfm.FixResult) -> None:
        self._inner = inner

    @cached_property
    def steps(self) -> list[Step]:
        """The steps, in order."""
        cases = self._inner.step_cases()
        return [
            Step(
                effect=Candidate._of(0, s["effect"]),
                removed=bool(s.get("removed", False)),
                removed_because=s.get("removed_because"),
                misfit_added=float(s["misfit_added"]),
                misfit_updated=float(s["misfit_updated"]),
                status=_status_name(s["status"]),
                parameters=_parameters({"parameters": s["parameters"], "uncertainty": s.get("uncertainty")}),
                case=case,
                raw=s,
            )
            for s, case in zip(self._doc["steps"], cases)
        ]

    @property
    def case(self) -> _rfm.Case | None:
        """The fixed case (the last step's), or None when no step was taken."""
        return self.steps[-1].case if self.steps else None

    @property
    def noise(self) -> float:
        """The noise level estimated from the data."""
        return float(self._doc["noise"])

    @property
    def nominal_misfit(self) -> float:
        """The misfit of the case's model before the loop."""
        return float(self._doc["nominal_misfit"])

    @property
    def final_misfit(self) -> float:
        """The misfit after the last step."""
        return self._inner.final_misfit()

    @property
    def stages(self) -> list[tuple[str, float]]:
        """The misfit at every stage, labelled as ``rfm fix`` prints them."""
        return list(self._inner.stages())

    @property
    def stop(self) -> Any:
        """Why the loop stopped (``to_dict()['stop']``)."""
        return self._doc["stop"]

    @property
    def exit_code(self) -> int:
        """The code ``rfm fix`` would exit with (0 when the data are
        explained down to their noise)."""
        return self._inner.exit()[0]

    def save(self, folder: str | os.PathLike[str], frequency_axis: str = "auto") -> list[Path]:
        """Writes what ``rfm fix --out FOLDER`` writes (``step-1.toml`` ..,
        ``results.json``, ``report.html``, the figures, and ``measured.csv``
        where the case synthesises its data), all or nothing; when the data
        were given as an ``FrfData``, a copy of the file written for them
        (``measured.uff`` or ``measured.csv``), which the steps' cases read."""
        return list(self._inner.save(Path(folder), frequency_axis))

    def __repr__(self) -> str:
        return f"<rfm.FixResult {len(self.steps)} steps, final misfit {self.final_misfit:.4g}>"
