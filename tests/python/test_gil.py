"""The GIL is released while Rust works: Python code in another thread runs during a run."""

import threading
import time

import flexprr


def test_python_runs_while_a_run_is_in_rust(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    scene.set("output.requests", ["deflections"]).set("output.plots", False)
    span = {}
    ticks = []
    done = threading.Event()

    def worker():
        span["start"] = time.perf_counter()
        flexprr.run(scene)
        span["end"] = time.perf_counter()
        done.set()

    thread = threading.Thread(target=worker)
    thread.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.0005)
    thread.join()
    start, end = span["start"], span["end"]
    # The middle half of the run: with the GIL held by the run, this thread could not
    # execute a single bytecode there.
    lo, hi = start + 0.25 * (end - start), start + 0.75 * (end - start)
    inside = [t for t in ticks if lo < t < hi]
    assert len(inside) >= 5, f"{len(inside)} ticks of the main thread in the middle of a {end - start:.3f} s run"

