"""Figures on matplotlib, each on the ``ax`` it is given (or a new one):
FRF overlays, the misfit per step of a fix, the MAC matrix. They draw what
the results hold; nothing is computed here but the magnitudes and phases
shown."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from ._frf import FrfData
    from ._results import Comparison, FixResult


def _axes(ax: Axes | None, n: int = 1) -> Any:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(n, 1, sharex=True, squeeze=n == 1)
    return axes if n == 1 else list(axes[:, 0])


def _index(data: FrfData, dofs: Sequence[tuple[int, str]], dof: tuple[int, str] | None, what: str) -> int:
    if dof is None:
        return 0
    key = (int(dof[0]), str(dof[1]).lower())
    if key not in dofs:
        raise KeyError(f"{what} {key} is not among {dofs}")
    return dofs.index(key)


def frf(
    measured: FrfData | None = None,
    models: dict[str, FrfData] | Sequence[FrfData] | FrfData | None = None,
    output: tuple[int, str] | None = None,
    input: tuple[int, str] | None = None,
    ax: Axes | Sequence[Axes] | None = None,
    phase: bool = True,
) -> Any:
    """Overlays one FRF (``output`` over ``input``; default the first of
    each) of the measured data (black) and of any models: magnitude on a
    log scale and, with ``phase``, the phase in degrees below it. ``ax``: one
    axes (magnitude only) or two (magnitude, phase). Returns the axes."""
    series: list[tuple[str, FrfData, dict[str, Any]]] = []
    if measured is not None:
        series.append(("measured", measured, {"color": "black", "lw": 1.2}))
    if models is not None:
        if not isinstance(models, (dict, list, tuple)):
            models = [models]
        items = models.items() if isinstance(models, dict) else ((f"model {k + 1}", m) for k, m in enumerate(models))
        for label, m in items:
            series.append((label, m, {"lw": 1.0}))
    if not series:
        raise ValueError("nothing to draw: give measured data or a model")
    if ax is None:
        axes = _axes(None, 2 if phase else 1)
    else:
        axes = list(ax) if isinstance(ax, (list, tuple, np.ndarray)) else [ax]
    mag_ax = axes[0] if isinstance(axes, list) else axes
    phase_ax = axes[1] if isinstance(axes, list) and len(axes) > 1 and phase else None
    first = series[0][1]
    o = _index(first, first.outputs, output, "output")
    i = _index(first, first.inputs, input, "input")
    out_dof, in_dof = first.outputs[o], first.inputs[i]
    for label, data, style in series:
        oo = _index(data, data.outputs, out_dof, "output")
        ii = _index(data, data.inputs, in_dof, "input")
        h = data.h[:, oo, ii]
        mag_ax.semilogy(data.freq, np.abs(h), label=label, **style)
        if phase_ax is not None:
            phase_ax.plot(data.freq, np.degrees(np.angle(h)), label=label, **style)
    mag_ax.set_ylabel(f"|H| ({first.units})")
    mag_ax.set_title(f"H({out_dof[0]}:{out_dof[1]}, {in_dof[0]}:{in_dof[1]}), {first.kind}")
    mag_ax.legend()
    if phase_ax is not None:
        phase_ax.set_ylabel("phase (deg)")
        phase_ax.set_xlabel("frequency (Hz)")
        return [mag_ax, phase_ax]
    mag_ax.set_xlabel("frequency (Hz)")
    return mag_ax


def comparison(result: Comparison, output: tuple[int, str] | None = None, ax: Any = None) -> Any:
    """The measured FRF and the model's of a :func:`rfm.compare` result."""
    return frf(result.measured, {"model": result.model}, output=output, ax=ax)


def steps(result: FixResult, ax: Axes | None = None) -> Axes:
    """The misfit at every stage of :func:`rfm.fix` (log scale), with the
    noise level and 1.5 times it, below which the data are explained."""
    ax = _axes(ax)
    labels, values = zip(*result.stages) if result.stages else ((), ())
    x = np.arange(len(values))
    ax.semilogy(x, values, "o-", color="tab:blue", label="misfit")
    ax.axhline(result.noise, color="grey", ls="--", label="noise")
    ax.axhline(1.5 * result.noise, color="grey", ls=":", label="1.5 x noise")
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=30, ha="right", fontsize="small")
    ax.set_ylabel("misfit (RMS of ln(model/measured))")
    ax.legend()
    return ax


def mac(result: Comparison, ax: Axes | None = None) -> Axes:
    """The MAC matrix of the measured modes (rows) against the model's
    (columns) of a :func:`rfm.compare` result."""
    matrix = result.mac
    if matrix is None:
        raise ValueError(f"the modes were not compared: {result.to_dict().get('modes_error')}")
    values, measured_hz, model_hz = matrix
    ax = _axes(ax)
    image = ax.imshow(np.asarray(values), vmin=0.0, vmax=1.0, cmap="Blues", aspect="auto")
    ax.set_yticks(range(len(measured_hz)))
    ax.set_yticklabels([f"{f:.1f}" for f in measured_hz])
    ax.set_xticks(range(len(model_hz)))
    ax.set_xticklabels([f"{f:.1f}" for f in model_hz], rotation=90)
    ax.set_ylabel("measured mode (Hz)")
    ax.set_xlabel("model mode (Hz)")
    ax.figure.colorbar(image, ax=ax, label="MAC")
    return ax
