"""Shared fixtures: the repository's cases, the ``rfm`` binary (built by
cargo, or named by the RFM_BIN environment variable, as .ci/run sets it) and
the runs that several tests read, made once per session."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

import rfm

ROOT = Path(__file__).resolve().parents[3]
TUTORIAL = ROOT / "cases" / "tutorial" / "l-frame.toml"
GUESS = ROOT / "cases" / "tutorial" / "l-frame-guess.toml"


@pytest.fixture(scope="session")
def rfm_bin() -> Path:
    """The ``rfm`` command: $RFM_BIN, else the one cargo builds (honouring
    CARGO_TARGET_DIR)."""
    given = os.environ.get("RFM_BIN")
    if given:
        return Path(given)
    cargo = shutil.which("cargo")
    assert cargo, "set RFM_BIN to the rfm binary, or put cargo on PATH to build it"
    out = subprocess.run(
        [cargo, "build", "-p", "rfm-cli", "--bin", "rfm", "--message-format=json"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg.get("executable") and msg["target"]["name"] == "rfm":
            return Path(msg["executable"])
    raise AssertionError("cargo built no rfm binary")


def run_cli(rfm_bin: Path, *args: Any, check: bool = True) -> subprocess.CompletedProcess[str]:
    """Runs the rfm command from the repository's root."""
    done = subprocess.run([str(rfm_bin), *map(str, args)], cwd=ROOT, capture_output=True, text=True)
    if check and done.returncode != 0:
        raise AssertionError(f"rfm {args} exited {done.returncode}: {done.stderr}")
    return done


def assert_same(a: Any, b: Any, rel: float = 1e-9, path: str = "") -> None:
    """Two JSON documents alike: the same keys, lists and strings, numbers
    within ``rel`` (the parallel sums of a run may differ in the last bits)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), f"{path}: keys {sorted(a)} != {sorted(b)}"
        for k in a:
            assert_same(a[k], b[k], rel, f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, rel, f"{path}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        if a is None or b is None:
            assert a == b, f"{path}: {a} != {b}"
        elif math.isnan(a) or math.isnan(b):
            assert math.isnan(a) and math.isnan(b), f"{path}: {a} != {b}"
        else:
            assert math.isclose(a, b, rel_tol=rel, abs_tol=1e-300), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


@pytest.fixture(scope="session")
def tutorial() -> rfm.Case:
    # the CLI's JSON names the case by the path it is given: both get TUTORIAL
    return rfm.load_case(TUTORIAL)


@pytest.fixture(scope="session")
def diagnosis(tutorial: rfm.Case) -> rfm.Diagnosis:
    return rfm.diagnose(tutorial)


@pytest.fixture(scope="session")
def fixed(tutorial: rfm.Case) -> rfm.FixResult:
    return rfm.fix(tutorial, steps=3)
