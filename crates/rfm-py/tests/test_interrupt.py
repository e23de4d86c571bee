"""Long calls release the GIL, and Ctrl-C stops them cleanly."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import rfm
from conftest import ROOT, TUTORIAL

# A process started with SIGINT ignored (a background job of a shell
# without job control, nohup) keeps it ignored, and Python then installs no
# KeyboardInterrupt handler: the child and the test install Python's own,
# as an interactive session has it.
CHILD = r"""
import signal, sys, time
import rfm

signal.signal(signal.SIGINT, signal.default_int_handler)

case = rfm.load_case(sys.argv[1])
def progress(message):
    print("stage:", message, flush=True)
try:
    rfm.diagnose(case, progress=progress)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    # the process goes on: nothing is left half done
    print("after:", rfm.compare(case).misfit > 0, flush=True)
    sys.exit(0)
print("finished", flush=True)
sys.exit(1)
"""


def test_sigint_stops_a_diagnosis_at_its_next_stage(tmp_path: Path) -> None:
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    child = subprocess.Popen(
        [sys.executable, str(script), str(TUTORIAL)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    assert child.stdout is not None
    first = child.stdout.readline()
    assert first.startswith("stage:"), first + child.stderr.read()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=600)
    lines = (first + out).splitlines()
    assert child.returncode == 0, err
    assert "interrupted" in lines and "finished" not in lines, lines
    assert "after: True" in lines
    # the stages after the interrupt are not reported: the work stopped
    assert lines.index("interrupted") <= 3, lines


def test_the_gil_is_released_while_rust_works(tutorial) -> None:
    ticks = []
    running = threading.Event()

    def count() -> None:
        running.wait()
        while running.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=count)
    thread.start()
    seen = []

    def progress(message: str) -> None:
        # from the first stage on, Python code may run beside the Rust work
        running.set()
        seen.append(len(ticks))

    try:
        rfm.diagnose(tutorial, progress=progress)
    finally:
        running.set()
        running.clear()
        thread.join()
    # between the first and the last stage the other thread ran, many
    # times, not only in the moments the callbacks hold the GIL
    assert seen[-1] - seen[0] > 10, seen


def test_an_exception_in_the_progress_callback_stops_the_work(tutorial) -> None:
    calls = []

    def progress(message: str) -> None:
        calls.append(message)
        raise RuntimeError("stop here")

    try:
        rfm.diagnose(tutorial, progress=progress)
    except RuntimeError as e:
        assert str(e) == "stop here"
    else:
        raise AssertionError("the callback's exception was swallowed")
    assert len(calls) == 1


def test_interrupt_main_stops_an_update() -> None:
    import _thread

    case = rfm.load_case(ROOT / "cases" / "tutorial" / "l-frame-guess.toml")
    calls = []

    def progress(message: str) -> None:
        calls.append(message)
        if len(calls) == 1:
            # as a Ctrl-C would, while the update's first iteration reports;
            # the waiting thread sees it within its 50 ms
            _thread.interrupt_main()
            time.sleep(0.5)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        rfm.update(case, progress=progress, check=False)
    except KeyboardInterrupt:
        pass
    else:
        raise AssertionError("not interrupted")
    finally:
        signal.signal(signal.SIGINT, previous)
    assert calls == [calls[0]] and calls[0].startswith("iteration 0"), calls


def test_progress_true_draws_a_tqdm_bar_of_the_stages(tutorial, monkeypatch) -> None:
    import sys
    import types

    bars = []

    class Bar:
        def __init__(self, desc: str, unit: str) -> None:
            self.desc, self.n, self.postfix, self.closed = desc, 0, [], False
            bars.append(self)

        def update(self, n: int) -> None:
            self.n += n

        def set_postfix_str(self, s: str) -> None:
            self.postfix.append(s)

        def close(self) -> None:
            self.closed = True

    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = Bar  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    messages = []
    rfm.update(rfm.load_case(ROOT / "cases" / "tutorial" / "l-frame-guess.toml"), progress=messages.append, check=False)
    rfm.update(rfm.load_case(ROOT / "cases" / "tutorial" / "l-frame-guess.toml"), progress=True, check=False)
    (bar,) = bars
    assert bar.desc == "update" and bar.closed
    assert bar.n == len(messages) and bar.postfix == [m[:60] for m in messages]
