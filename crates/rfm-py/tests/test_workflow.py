"""The workflow against the rfm command on the tutorial: the same JSON, the
same files, the same leader, dBIC and final misfit."""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest

import rfm
from conftest import GUESS, TUTORIAL, assert_same, run_cli


def files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file() and not p.name.startswith("."))


def test_compare_is_the_cli_json_and_writes_its_files(rfm_bin, tutorial, tmp_path) -> None:
    result = rfm.compare(tutorial)
    cli = json.loads(run_cli(rfm_bin, "compare", TUTORIAL, "--json", "--out", tmp_path / "cli").stdout)
    assert_same(result.to_dict(), cli)
    saved = result.save(tmp_path / "py")
    assert files(tmp_path / "py") == files(tmp_path / "cli")
    assert len(saved) == len(files(tmp_path / "cli"))
    assert_same(json.loads((tmp_path / "py" / "compare.json").read_text()), cli)
    # the arrays behind it: the measured and the model's FRFs on the same grid
    m, x = result.measured, result.model
    assert m.h.shape == x.h.shape == (599, 8, 1) and m.kind == "receptance"
    assert result.misfit == cli["correlation"]["total"]["log_misfit"]
    # the tutorial's mesh is fine for its band: cutting every element in two
    # moves its FRFs by far less than the noise
    assert result.mesh == cli["mesh"] and result.mesh["parts"] == 2
    assert result.mesh["change"] < 0.2 * cli["misfit"]["noise"]


def test_measured_data_given_as_frfdata_are_read_as_a_file(rfm_bin, tutorial, tmp_path) -> None:
    # the truth's FRFs with 1 % noise, given in memory and as a file
    data = rfm.load_case(TUTORIAL.with_name("l-frame-truth.toml")).simulate(truth=True, noise=0.01, seed=4)
    data.write_csv(tmp_path / "m.csv")
    from_file = rfm.compare(tutorial, measured=tmp_path / "m.csv").to_dict()
    in_memory = rfm.compare(tutorial, measured=data).to_dict()
    cli = json.loads(run_cli(rfm_bin, "compare", TUTORIAL, "--measured", tmp_path / "m.csv", "--json").stdout)
    assert_same(from_file, cli)
    # the same numbers; only the name of the file read differs
    for doc in (from_file, in_memory):
        doc.pop("measured")
        doc["notes"] = []
    assert_same(in_memory, from_file)


def test_update_and_fix_read_measured_data_given_as_the_cli_takes_them(rfm_bin, tutorial, tmp_path) -> None:
    # the truth's FRFs with 1 % noise, as a file and in memory
    data = rfm.load_case(TUTORIAL.with_name("l-frame-truth.toml")).simulate(truth=True, noise=0.01, seed=6)
    data.write_uff(tmp_path / "run.uff", binary=True)
    fixed = rfm.fix(tutorial, measured=tmp_path / "run.uff", steps=1)
    cli = json.loads(
        run_cli(rfm_bin, "fix", TUTORIAL, "--measured", tmp_path / "run.uff", "--steps", "1", "--json",
                "--out", tmp_path / "cli").stdout
    )
    assert_same(fixed.to_dict(), cli)
    assert "joint at node 13" in fixed.steps[0].effect.description
    fixed.save(tmp_path / "py")
    step = (tmp_path / "py" / "step-1.toml").read_text()
    assert step == (tmp_path / "cli" / "step-1.toml").read_text() and 'data = "../run.uff"' in step
    # in memory: the same loop, its cases reading a file written for the data
    in_memory = rfm.fix(tutorial, measured=data, steps=1)
    assert abs(in_memory.final_misfit - fixed.final_misfit) <= 1e-9 * fixed.final_misfit
    np.testing.assert_array_equal(in_memory.case.measured().h, data.h)
    # update of the fixed case against the same data, from the file and from memory
    one = rfm.update(fixed.case, measured=tmp_path / "run.uff", check=False)
    two = rfm.update(fixed.case, measured=data, check=False)
    for a, b in zip(one.parameters, two.parameters):
        assert a.name == b.name and abs(a.value - b.value) <= 1e-9 * abs(a.value)


def test_saved_results_of_frfs_given_in_memory_carry_a_copy_of_them(tutorial, tmp_path) -> None:
    # the truth's FRFs with 1 % noise, in memory only: the folders saved must
    # not name the temporary file written for them
    import shutil

    data = rfm.load_case(TUTORIAL.with_name("l-frame-truth.toml")).simulate(truth=True, noise=0.01, seed=6)
    fixed = rfm.fix(tutorial, measured=data, steps=1)
    fixed.save(tmp_path / "fix")
    updated = rfm.update(rfm.load_case(GUESS), measured=data, check=False)
    updated.save(tmp_path / "update")
    diagnosis = rfm.diagnose(tutorial, measured=data)
    beside = diagnosis.save(tmp_path / "applied" / "joint.toml", diagnosis.recommended.rank)
    assert beside == tmp_path / "applied" / "joint-measured.uff" and beside.is_file()
    # the case applied in memory reads the same data
    np.testing.assert_array_equal(diagnosis.apply().measured().h, data.h)
    # moved elsewhere, each saved case reads its own copy: the same FRFs
    moved = tmp_path / "moved"
    shutil.copytree(tmp_path / "fix", moved / "fix")
    shutil.copytree(tmp_path / "update", moved / "update")
    shutil.copytree(tmp_path / "applied", moved / "applied")
    for case, name in (("fix/step-1.toml", "measured.uff"), ("update/updated.toml", "measured.uff"),
                       ("applied/joint.toml", "joint-measured.uff")):
        assert f'data = "{name}"' in (moved / case).read_text(), case
        np.testing.assert_array_equal(rfm.load_case(moved / case).measured().h, data.h)
    # the fixed case as saved is the fixed case in memory: the same model
    np.testing.assert_array_equal(rfm.load_case(moved / "fix/step-1.toml").simulate().h, fixed.case.simulate().h)


def test_the_cases_a_fix_gives_outlive_it() -> None:
    # a case whose data are synthesised from its [truth]: the steps' cases
    # read them from a file written for the loop, which must outlive the result
    import gc

    case = rfm.load_case(TUTORIAL.with_name("l-frame-truth.toml"))
    fixed = rfm.fix(case, steps=1)
    expected = fixed.case.measured().h
    cases = [fixed.case] + [s.case for s in fixed.steps]
    del fixed
    gc.collect()
    for c in cases:
        np.testing.assert_array_equal(c.measured().h, expected)


def test_diagnose_names_the_clis_leader_with_its_dbic(rfm_bin, diagnosis) -> None:
    cli = json.loads(run_cli(rfm_bin, "diagnose", TUTORIAL, "--json").stdout)
    assert_same(diagnosis.to_dict(), cli)
    lead = diagnosis.leader
    assert lead.description == cli["ranking"][0]["description"]
    assert "joint at node 13" in lead.description
    assert abs(lead.delta_bic - cli["ranking"][0]["delta_bic"]) <= 1e-9 * abs(lead.delta_bic)
    assert diagnosis.recommended is not None and diagnosis.recommended.rank == cli["recommended"]
    assert lead.significant and lead.plausible and lead.kind == cli["ranking"][0]["kind"]
    assert set(lead.values) == {p["name"] for p in cli["ranking"][0]["parameters"]}


def test_apply_writes_the_case_the_cli_writes(rfm_bin, diagnosis, tmp_path) -> None:
    rank = diagnosis.recommended.rank
    run_cli(rfm_bin, "diagnose", TUTORIAL, "--apply", rank, "--out", tmp_path / "cli.toml")
    diagnosis.save(tmp_path / "py.toml")
    assert (tmp_path / "py.toml").read_text() == (tmp_path / "cli.toml").read_text()
    applied = diagnosis.apply()
    assert set(applied.parameters) >= set(diagnosis.recommended.values) - {"spring.corner.kx", "spring.corner.ky"}


def test_fix_reaches_the_clis_final_misfit_and_writes_its_files(rfm_bin, fixed, tmp_path) -> None:
    done = run_cli(rfm_bin, "fix", TUTORIAL, "--out", tmp_path / "cli", "--json", check=False)
    assert done.returncode == fixed.exit_code == 0
    cli = json.loads(done.stdout)
    assert_same(fixed.to_dict(), cli)
    assert fixed.final_misfit == pytest.approx(cli["steps"][-1]["misfit_updated"], rel=1e-9)
    assert fixed.steps[0].effect.description == cli["steps"][0]["effect"]["description"]
    assert fixed.final_misfit <= 1.5 * fixed.noise
    fixed.save(tmp_path / "py")
    assert files(tmp_path / "py") == files(tmp_path / "cli")
    for name in ("step-1.toml", "results.json"):
        if name.endswith(".json"):
            assert_same(json.loads((tmp_path / "py" / name).read_text()), cli)
        else:
            assert (tmp_path / "py" / name).read_text() == (tmp_path / "cli" / name).read_text()
    # the fixed case in memory is the last step's
    assert fixed.case.to_toml() == fixed.steps[-1].case.to_toml()
    assert [s for s, _ in fixed.stages][0] == "nominal"


def test_update_is_the_cli_json_and_writes_its_files(rfm_bin, tmp_path, caplog) -> None:
    case = rfm.load_case(GUESS)
    messages = []
    with caplog.at_level(logging.INFO, logger="rfm"):
        result = rfm.update(case, progress=messages.append, check=False)
    done = run_cli(rfm_bin, "update", GUESS, "--json", "--out", tmp_path / "cli", check=False)
    assert done.returncode == result.exit_code
    cli = json.loads(done.stdout)
    assert_same(result.to_dict(), cli)
    assert messages and messages[0].startswith("iteration")
    assert [r.getMessage() for r in caplog.records if r.name == "rfm"] == messages
    result.save(tmp_path / "py")
    assert files(tmp_path / "py") == files(tmp_path / "cli")
    assert (tmp_path / "py" / "updated.toml").read_text() == (tmp_path / "cli" / "updated.toml").read_text()
    p = result.parameters
    assert [x.name for x in p] == ["spring.corner.kr", "group.corner.alpha"]
    for x, c in zip(p, cli["parameters"]):
        assert x.value == c["updated"] and x.initial == c["initial"] and x.std is not None and x.std > 0
    # the updated case holds the updated values, and reads the same data
    updated = result.case
    assert updated.parameters == case.parameters
    assert "Updated by rfm" in updated.to_toml()
    np.testing.assert_array_equal(updated.measured().h, case.measured().h)
    assert not np.array_equal(updated.simulate().h, case.simulate().h)


def test_thread_count_changes_nothing_but_the_threads(tutorial) -> None:
    before = rfm.get_num_threads()
    try:
        rfm.set_num_threads(1)
        assert rfm.get_num_threads() == 1
        one = rfm.compare(tutorial).to_dict()
        rfm.set_num_threads(2)
        assert rfm.get_num_threads() == 2
        two = rfm.compare(tutorial).to_dict()
    finally:
        rfm.set_num_threads(before)
    assert_same(one, two)


def test_a_case_from_a_dict_is_the_case_from_its_file(tutorial) -> None:
    import tomllib

    tables = tomllib.loads(TUTORIAL.read_text())
    case = rfm.Case.from_dict(tables, path=TUTORIAL)
    np.testing.assert_array_equal(case.simulate().h, tutorial.simulate().h)
    assert case.title == tutorial.title
