"""Progress callbacks: in the caller's thread, monotone in [0, 1], at most about once per
percent, ending at 1; an exception in the callback propagates; the GIL stays released."""

import threading
import time

import pytest

import flexprr


@pytest.fixture
def scene(root):
    s = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    s.set("output.requests", ["deflections"]).set("output.plots", False)
    return s


def test_run_reports_fractions_in_the_calling_thread(scene):
    calls = []
    caller = threading.get_ident()
    flexprr.run(scene, progress=lambda f: calls.append((f, threading.get_ident())))
    fractions = [f for f, _ in calls]
    assert all(t == caller for _, t in calls)
    assert fractions == sorted(fractions) and 0.0 <= fractions[0] and fractions[-1] == 1.0
    # at most once per percent (plus the final 1.0), and more than a handful
    assert 10 <= len(fractions) <= 102
    assert all(b - a >= 0.01 - 1e-12 for a, b in zip(fractions[:-2], fractions[1:-1]))


def test_an_exception_in_the_callback_propagates(scene):
    seen = []

    def stop(fraction):
        seen.append(fraction)
        if fraction > 0.2:
            raise KeyboardInterrupt("stop at 20 %")

    with pytest.raises(KeyboardInterrupt, match="stop at 20 %"):
        flexprr.run(scene, progress=stop)
    # no call after the one that raised
    assert seen[-1] > 0.2 and all(f <= 0.2 for f in seen[:-1])
    # the extension is still usable
    assert flexprr.run(scene).tables == ["deflections"]


def test_a_failed_run_does_not_report_one(scene):
    calls = []
    with pytest.raises(flexprr.RunError):
        flexprr.run(scene.copy().set("integrator.max_steps", 50), progress=calls.append)
    assert all(f < 1.0 for f in calls)


def test_run_many_reports_each_finished_scene(scene):
    scenes = [scene.copy().set("time.end", t) for t in (0.01, 0.02, 0.03)]
    calls = []
    flexprr.run_many(scenes, threads=2, progress=calls.append)
    assert calls == pytest.approx([1 / 3, 2 / 3, 1.0])
    with pytest.raises(ZeroDivisionError):
        flexprr.run_many(scenes, progress=lambda f: 1 / 0)


def test_run_study_reports_each_finished_case(root, tmp_path):
    study = tmp_path / "thickness.toml"
    study.write_text(
        f'base = "{(root / "configs" / "paper_f20.toml").as_posix()}"\n'
        'quantities = [{ kind = "peak_deflection", link = 1 }]\n'
        "[set.time]\nend = 0.01\n"
        '[set.output]\nrequests = ["deflections"]\nplots = false\n'
        '[[axis]]\nkey = "links.section.thickness"\nvalues = [0.002, 0.003, 0.004, 0.005]\n'
    )
    calls = []
    summary = flexprr.run_study(study, tmp_path / "out", threads=2, progress=calls.append)
    assert summary["total"] == 4 and summary["failed"] == 0
    assert calls[-1] == 1.0 and calls == sorted(calls)
    assert set(calls) == {0.25, 0.5, 0.75, 1.0}


def test_the_gil_is_released_during_a_run_with_a_callback(scene):
    span, ticks, done = {}, [], threading.Event()

    def worker():
        span["start"] = time.perf_counter()
        flexprr.run(scene, progress=lambda f: None)
        span["end"] = time.perf_counter()
        done.set()

    thread = threading.Thread(target=worker)
    thread.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.0005)
    thread.join()
    lo = span["start"] + 0.25 * (span["end"] - span["start"])
    hi = span["start"] + 0.75 * (span["end"] - span["start"])
    assert len([t for t in ticks if lo < t < hi]) >= 5


def test_run_study_reports_each_pose_of_a_map_and_each_probe_of_a_search(root, tmp_path):
    """Issue 34: run_study on a map reported progress once, at the end. It reports after each
    pose of a map, and after each probe of a speed search."""
    study = tmp_path / "map.toml"
    study.write_text(
        f'base = "{(root / "configs" / "servo_f20.toml").as_posix()}"\n'
        "[map]\n"
        "x = { start = -0.05, end = 0.05, count = 3 }\n"
        "y = { start = -0.05, end = 0.05, count = 2 }\n"
        "phi_deg = 45.0\n"
        'quantity = "lowest_frequency"\n'
    )
    calls = []
    flexprr.run_study(study, tmp_path / "map_out", threads=2, progress=calls.append)
    assert calls[-1] == 1.0 and calls == sorted(calls)
    assert {round(c * 6) for c in calls[:-1]} >= {1, 2, 3, 4, 5}
    search = tmp_path / "search.toml"
    search.write_text(
        f'base = "{(root / "configs" / "coupled_f20.toml").as_posix()}"\n'
        '[set.model]\ncoupling = "ked"\n'
        '[search]\nkey = "trajectory.frequency"\nlow = 20.0\nhigh = 34.0\ntolerance = 0.5\ntime = 0.5\n'
    )
    calls = []
    summary = flexprr.run_study(search, tmp_path / "search_out", threads=2, progress=calls.append)
    # Bisection over 14 Hz to 0.5 Hz: the two ends and 5 halvings, one call per probe.
    assert summary["total"] == 7
    assert len(calls) == 8 and calls[-1] == 1.0 and calls == sorted(calls)
