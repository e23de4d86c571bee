"""Every exception class, with the rfm command's message and exit code."""

from __future__ import annotations

import re

import numpy as np
import pytest

import rfm
from conftest import ROOT, TUTORIAL, run_cli

BEAM = ROOT / "cases" / "two-material-beam.toml"


def test_the_hierarchy() -> None:
    for cls in (rfm.CaseError, rfm.DataError, rfm.ArgumentError, rfm.NumericsError, rfm.OutputError, rfm.NotConverged):
        assert issubclass(cls, rfm.RfmError)
    for cls in (rfm.CaseError, rfm.DataError, rfm.ArgumentError):
        assert issubclass(cls, ValueError)
    assert issubclass(rfm.OutputError, OSError) and issubclass(rfm.NumericsError, ArithmeticError)


def test_a_misspelt_table_is_a_case_error_naming_file_and_line(rfm_bin, tmp_path) -> None:
    text = TUTORIAL.read_text().replace("[materials]", "[materails]")
    path = tmp_path / "typo.toml"
    path.write_text(text)
    line = text.splitlines().index("[materails]") + 1
    with pytest.raises(rfm.CaseError) as caught:
        rfm.load_case(path)
    assert isinstance(caught.value, ValueError) and caught.value.exit_code == 3
    message = str(caught.value)
    assert re.match(rf"{re.escape(str(path))}:{line}:\d+: ", message), message
    assert "materials" in message  # the suggestion
    done = run_cli(rfm_bin, "compare", path, check=False)
    assert done.returncode == 3 and done.stderr == f"error: {message}\n"


def test_a_case_from_text_names_its_path(tmp_path) -> None:
    with pytest.raises(rfm.CaseError, match=r"^here\.toml:3:"):
        rfm.Case.from_toml('title = "x"\n\n[grups.a]\nalpha = 1\n', path="here.toml")


def test_a_value_that_is_not_finite_is_a_data_error(rfm_bin, tutorial, tmp_path) -> None:
    data = tutorial.simulate()
    data.h[10, 2, 0] = np.nan + 0j
    data.write_csv(tmp_path / "bad.csv")
    with pytest.raises(rfm.DataError) as caught:
        rfm.compare(tutorial, measured=tmp_path / "bad.csv")
    assert isinstance(caught.value, ValueError) and caught.value.exit_code == 3
    done = run_cli(rfm_bin, "compare", TUTORIAL, "--measured", tmp_path / "bad.csv", check=False)
    assert done.returncode == 3 and done.stderr == f"error: {caught.value}\n"
    assert "bad.csv" in str(caught.value)


def test_a_model_singular_at_a_line_is_a_numerics_error(rfm_bin, tmp_path) -> None:
    # an undamped mass on a spring measured exactly at its resonance,
    # sqrt(k / m) = 2 pi 10 rad/s
    k = (2 * np.pi * 10.0) ** 2
    text = f"""
title = "undamped"
nodes = [[1, 0.0, 0.0]]
[groups.g]
[[springs]]
name = "s"
node = 1
kx = {k!r}
ky = {k!r}
kr = {k!r}
group = "g"
[[masses]]
name = "m"
node = 1
m = 1.0
j = 1.0
group = "g"
[measurement]
frequencies = [5.0, 10.0, 15.0]
references = ["1:uy"]
responses = ["1:uy"]
[truth]
noise = 0.0
"""
    path = tmp_path / "undamped.toml"
    path.write_text(text)
    with pytest.raises(rfm.NumericsError) as caught:
        rfm.load_case(path).simulate()
    assert caught.value.exit_code == 4 and "10" in str(caught.value)
    done = run_cli(rfm_bin, "simulate", path, "--out", tmp_path / "x.csv", check=False)
    assert done.returncode == 4 and done.stderr == f"error: {caught.value}\n"


def test_an_output_over_an_input_is_an_output_error(tutorial) -> None:
    with pytest.raises(rfm.OutputError) as caught:
        tutorial.save(TUTORIAL)
    assert isinstance(caught.value, OSError) and caught.value.exit_code == 6
    assert "input" in str(caught.value)


def test_a_wrong_argument_is_an_argument_error(tutorial) -> None:
    with pytest.raises(rfm.ArgumentError, match="steps 0"):
        rfm.fix(tutorial, steps=0)
    # as the command, which exits with 3 (invalid input) for it
    with pytest.raises(ValueError, match="fifty") as caught:
        rfm.compare(tutorial, bands="0,fifty")
    assert isinstance(caught.value, rfm.RfmError) and caught.value.exit_code == 3


def test_an_update_that_stops_short_raises_not_converged_with_its_result(rfm_bin) -> None:
    # the paper's beam needs 6 to 8 iterations of the RFM
    case = rfm.load_case(BEAM)
    with pytest.raises(rfm.NotConverged) as caught:
        rfm.update(case, iterations=1)
    result = caught.value.result
    assert isinstance(result, rfm.UpdateResult) and result.status == "max_iterations"
    done = run_cli(rfm_bin, "update", BEAM, "--iterations", "1", "--json", check=False)
    assert caught.value.exit_code == result.exit_code == done.returncode == 5
    unchecked = rfm.update(case, iterations=1, check=False)
    assert unchecked.exit_code == 5 and unchecked.parameters[0].value == result.parameters[0].value
