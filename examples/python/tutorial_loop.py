"""The tutorial's loop from Python: compare the bolted L-frame's model with
its measured FRFs, diagnose what is missing, close the loop with `fix`, and
look at the result (docs/walkthrough.md does the same with the `rfm`
command).

Run from anywhere: python examples/python/tutorial_loop.py [OUT_FOLDER]
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; drop this line in a notebook
import matplotlib.pyplot as plt
import numpy as np

import rfm

HERE = Path(__file__).resolve().parent
CASE = HERE.parents[1] / "cases" / "tutorial" / "l-frame.toml"


def main(out: Path) -> None:
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    case = rfm.load_case(CASE)
    print(case.title)

    # 1. the model against the test: FRFs as complex (lines, outputs, inputs) arrays over Hz
    comparison = rfm.compare(case)
    measured = comparison.measured
    print(f"{measured.h.shape[0]} lines from {measured.freq[0]:g} to {measured.freq[-1]:g} Hz, "
          f"{len(measured.outputs)} outputs x {len(measured.inputs)} input(s), {measured.units}")
    print(f"misfit of the model as it is: {comparison.misfit:.4f}")

    # 2. what is missing
    diagnosis = rfm.diagnose(case)
    for c in diagnosis.ranking[:3]:
        print(f"  {c.rank}. {c.description}: dBIC {c.delta_bic:.1f}, explains {100 * c.explained:.1f} %")

    # 3. close the loop: add, update, again until only noise is left
    result = rfm.fix(case, steps=3)
    for k, step in enumerate(result.steps, 1):
        print(f"step {k}: {step.effect.description}: misfit {step.misfit_added:.4f} -> {step.misfit_updated:.4f}")
    print(f"final misfit {result.final_misfit:.4f} ({result.final_misfit / result.noise:.2f} times the noise)")
    for p in result.steps[-1].parameters:
        print(f"  {p.name} = {p.value:.6g} +- {p.std:.2g}")

    # 4. the files the command writes, and figures of our own
    result.save(out / "fix")
    fixed = result.case.simulate()
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    rfm.plot.frf(measured, {"initial": comparison.model, "fixed": fixed}, output=(23, "uy"), ax=axes)
    fig.savefig(out / "tip-frf.png", dpi=80)
    fig, ax = plt.subplots(figsize=(7, 4))
    rfm.plot.steps(result, ax=ax)
    fig.savefig(out / "misfit-per-step.png", dpi=80, bbox_inches="tight")
    fig, ax = plt.subplots(figsize=(5, 4))
    rfm.plot.mac(rfm.compare(result.case), ax=ax)
    fig.savefig(out / "mac.png", dpi=80, bbox_inches="tight")
    assert np.isfinite(result.final_misfit)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("tutorial-loop"))
