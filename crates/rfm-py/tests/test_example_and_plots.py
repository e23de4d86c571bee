"""The example runs end to end, the plots draw what the results hold, and
the package computes nothing in Python."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import rfm
import rfm.plot
from conftest import ROOT

EXAMPLE = ROOT / "examples" / "python" / "tutorial_loop.py"


def test_the_example_runs_the_tutorial_loop(tmp_path: Path, fixed) -> None:
    done = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "599 lines from 2 to 600 Hz, 8 outputs x 1 input(s), m/N" in done.stdout
    assert f"final misfit {fixed.final_misfit:.4f}" in done.stdout
    for name in ("fix/report.html", "fix/step-1.toml", "tip-frf.png", "misfit-per-step.png", "mac.png"):
        assert (tmp_path / name).is_file(), name
    # the library's stages went to Python's logging
    assert "rfm: diagnosis 1:" in done.stderr


def test_frf_overlay_draws_the_arrays(tutorial) -> None:
    comparison = rfm.compare(tutorial)
    fig, axes = plt.subplots(2, 1)
    rfm.plot.comparison(comparison, output=(21, "uy"), ax=list(axes))
    o = comparison.measured.outputs.index((21, "uy"))
    lines = axes[0].get_lines()
    assert [line.get_label() for line in lines] == ["measured", "model"]
    np.testing.assert_array_equal(lines[0].get_ydata(), np.abs(comparison.measured.h[:, o, 0]))
    np.testing.assert_array_equal(lines[1].get_ydata(), np.abs(comparison.model.h[:, o, 0]))
    np.testing.assert_allclose(axes[1].get_lines()[1].get_ydata(), np.degrees(np.angle(comparison.model.h[:, o, 0])))
    plt.close(fig)


def test_steps_and_mac_figures(fixed, tutorial) -> None:
    fig, ax = plt.subplots()
    rfm.plot.steps(fixed, ax=ax)
    misfits = ax.get_lines()[0].get_ydata()
    assert list(misfits) == [m for _, m in fixed.stages]
    assert ax.get_lines()[1].get_ydata()[0] == fixed.noise
    plt.close(fig)
    comparison = rfm.compare(tutorial)
    fig, ax = plt.subplots()
    rfm.plot.mac(comparison, ax=ax)
    values, measured_hz, model_hz = comparison.mac
    np.testing.assert_array_equal(ax.get_images()[0].get_array(), np.asarray(values))
    assert len(measured_hz) == len(values) and len(model_hz) == len(values[0])
    # the pairs the JSON lists are entries of the matrix
    for row in comparison.modes["rows"]:
        if row.get("mac") is not None:
            assert any(np.isclose(row["mac"], v) for r in values for v in r)
    plt.close(fig)


def test_the_python_side_computes_nothing() -> None:
    """The package converts and draws; every number comes from the Rust
    crates (no linear algebra, FFTs, fits or solvers in Python)."""
    package = Path(rfm.__file__).parent
    sources = {p.name: p.read_text() for p in package.glob("*.py")}
    assert set(sources) == {"__init__.py", "_frf.py", "_results.py", "errors.py", "plot.py"}
    forbidden = re.compile(r"linalg|scipy|np\.fft|lstsq|solve\(|\binv\(|eig|polyfit|optimi[sz]e|\bsum\(|np\.mean")
    for name, text in sources.items():
        assert not forbidden.search(text), (name, forbidden.search(text))
    assert (package / "py.typed").is_file() and (package / "_rfm.pyi").is_file()


def test_the_stub_names_everything_the_compiled_module_has() -> None:
    import inspect

    stub = (Path(rfm.__file__).parent / "_rfm.pyi").read_text()
    stubbed = set(re.findall(r"^(?:def|class) (\w+)", stub, re.M))
    compiled = {n for n in dir(rfm._rfm) if not n.startswith("_")}
    assert stubbed == compiled
    blocks = dict(re.findall(r"^class (\w+):\n((?:    .*\n|\n)*)", stub, re.M))
    for name, block in blocks.items():
        members = {n for n, _ in inspect.getmembers(getattr(rfm._rfm, name)) if not n.startswith("_")}
        assert set(re.findall(r"def (\w+)", block)) == members, name
