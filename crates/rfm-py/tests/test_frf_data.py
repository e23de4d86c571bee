"""FrfData: shapes, units and layout against an analytic receptance, the
CLI's simulate, and the round trips through UFF files and pyuff."""

from __future__ import annotations

import numpy as np
import pytest

import rfm
from conftest import TUTORIAL, run_cli

# A mass on springs to ground at one node, with exponential damping in its
# group: each DOF is a single-DOF system whose receptance is known exactly,
#   Z(w) = k (1 + j w h alpha) + m (-w^2 + j w h beta),  h = mu / (mu + j w).
SPRING_MASS = """
title = "mass on springs"
nodes = [[1, 0.0, 0.0]]

[groups.g]
alpha = 1.0e-4
beta = 2.0
mu = 500.0

[[springs]]
name = "s"
node = 1
kx = 4.0e4
ky = 1.0e4
kr = 2.0e3
group = "g"

[[masses]]
name = "m"
node = 1
m = 2.0
j = 0.01
group = "g"

[measurement]
frequencies = { from = 1.0, to = 30.0, step = 0.5 }
references = ["1:uy"]
responses = ["1:uy", "1:ux", "1:rz"]

[truth]
noise = 0.0
"""


def analytic_uy(f: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * f
    h = 500.0 / (500.0 + 1j * w)
    return 1.0 / (1.0e4 * (1 + 1j * w * h * 1.0e-4) + 2.0 * (-(w**2) + 1j * w * h * 2.0))


def test_layout_is_lines_outputs_inputs_against_an_analytic_receptance() -> None:
    case = rfm.Case.from_toml(SPRING_MASS)
    data = case.simulate()
    f = np.arange(1.0, 30.0 + 0.25, 0.5)
    np.testing.assert_array_equal(data.freq, f)
    assert data.freq.dtype == np.float64 and data.h.dtype == np.complex128
    assert data.h.shape == (len(f), 3, 1)
    assert data.outputs == [(1, "uy"), (1, "ux"), (1, "rz")] and data.inputs == [(1, "uy")]
    assert (data.kind, data.units) == ("receptance", "m/N")
    np.testing.assert_allclose(data.h[:, 0, 0], analytic_uy(f), rtol=1e-12)
    # the other DOFs are not coupled to uy
    assert np.all(np.abs(data.h[:, 1:, 0]) <= 1e-12 * np.abs(data.h[:, :1, 0]))


def test_kinds_are_powers_of_j_omega_and_units_follow() -> None:
    case = rfm.Case.from_toml(SPRING_MASS)
    h = case.simulate().h
    w = case.simulate().omega[:, None, None]
    mob = case.simulate(kind="mobility")
    acc = case.simulate(kind="accelerance")
    assert (mob.units, acc.units) == ("m/s/N", "m/s^2/N")
    np.testing.assert_allclose(mob.h, 1j * w * h, rtol=1e-14, atol=0)
    np.testing.assert_allclose(acc.h, -(w**2) * h, rtol=1e-14, atol=0)


def test_simulate_equals_the_cli_written_file(rfm_bin, tmp_path) -> None:
    out = tmp_path / "sim.csv"
    run_cli(rfm_bin, "simulate", TUTORIAL, "--out", out, "--noise", "0.01", "--seed", "3")
    from_cli = rfm.read_uff(out)
    mine = rfm.load_case(TUTORIAL).simulate(noise=0.01, seed=3)
    np.testing.assert_array_equal(mine.freq, from_cli.freq)
    np.testing.assert_array_equal(mine.h, from_cli.h)
    assert mine.outputs == from_cli.outputs and mine.inputs == from_cli.inputs
    assert mine.outputs == [(15, "uy"), (17, "uy"), (19, "uy"), (21, "uy"), (23, "uy"), (5, "ux"), (9, "ux"), (13, "ux")]


def test_pyuff_round_trip_reproduces_the_frfs() -> None:
    data = rfm.load_case(TUTORIAL).simulate(noise=0.02, seed=1, kind="accelerance")
    sets = data.to_pyuff()
    assert len(sets) == 8
    for s, (node, dof) in zip(sets, data.outputs):
        # one dataset per measured pair, as pyuff reads them: FRF, +Y or +X
        assert (s["func_type"], s["rsp_node"], s["ref_node"], s["ref_dir"]) == (4, node, 23, 2)
        assert s["rsp_dir"] == {"ux": 1, "uy": 2}[dof]
        o = data.outputs.index((node, dof))
        np.testing.assert_array_equal(s["data"], data.h[:, o, 0])
        np.testing.assert_array_equal(s["x"], data.freq)
    back = rfm.FrfData.from_pyuff(sets)
    assert back.outputs == data.outputs and back.inputs == data.inputs and back.kind == "accelerance"
    np.testing.assert_allclose(back.h, data.h, rtol=1e-12, atol=0)
    np.testing.assert_allclose(back.freq, data.freq, rtol=1e-12, atol=0)


def test_a_file_pyuff_writes_in_ascii_reads_back(tmp_path) -> None:
    pyuff = pytest.importorskip("pyuff")
    data = rfm.Case.from_toml(SPRING_MASS).simulate()
    path = tmp_path / "ascii.uff"
    pyuff.UFF(str(path)).write_sets([dict(s, binary=0) for s in data.to_pyuff()], mode="add")
    back = rfm.read_uff(path)
    # pyuff's ASCII keeps 12 significant digits or more
    np.testing.assert_allclose(back.h[:, 0, 0], data.h[:, 0, 0], rtol=1e-10)


def test_uff_files_keep_coherence_and_missing_pairs(tmp_path) -> None:
    data = rfm.Case.from_toml(SPRING_MASS).simulate()
    h = data.h.copy()
    h[:, 2, 0] = np.nan  # rz not measured
    coherence = np.linspace(0.5, 1.0, h.size).reshape(h.shape)
    measured = rfm.FrfData(data.freq, h, data.outputs, data.inputs, coherence=coherence)
    for binary in (False, True):
        path = tmp_path / f"c{binary}.uff"
        measured.write_uff(path, binary=binary)
        back = rfm.read_uff(path)
        assert back.outputs == [(1, "uy"), (1, "ux")]
        np.testing.assert_allclose(back.h, h[:, :2, :], rtol=1e-12)
        np.testing.assert_allclose(back.coherence, coherence[:, :2, :], rtol=1e-12)


def test_csv_keeps_every_digit(tmp_path) -> None:
    data = rfm.load_case(TUTORIAL).simulate(kind="mobility")
    data.write_csv(tmp_path / "m.csv")
    back = rfm.read_uff(tmp_path / "m.csv")
    np.testing.assert_array_equal(back.h, data.h)
    assert back.kind == "mobility"


def test_a_wrong_shape_is_a_data_error() -> None:
    with pytest.raises(rfm.DataError, match=r"\(n_freq, n_out, n_in\)"):
        rfm.FrfData(np.arange(1.0, 4.0), np.zeros((3, 2, 1)), [(1, "uy")], [(1, "uy")])


def test_to_sdynpy_needs_sdynpy_or_gives_its_array() -> None:
    import os

    # SDynPy imports Qt, which needs no display this way
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    data = rfm.Case.from_toml(SPRING_MASS).simulate()
    try:
        import sdynpy  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="pip install sdynpy"):
            data.to_sdynpy()
    else:
        tf = data.to_sdynpy()
        assert tf.shape == (3, 1)
        for o in range(3):
            np.testing.assert_array_equal(tf.ordinate[o, 0], data.h[:, o, 0])
            np.testing.assert_array_equal(tf.abscissa[o, 0], data.freq)
        assert "1X+" in str(tf.coordinate[1, 0]) and "1Y+" in str(tf.coordinate[1, 0])
        assert "1RZ+" in str(tf.coordinate[2, 0])
