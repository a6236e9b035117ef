"""Every file input goes through the CLI's checks: regular files of at most 4 MiB, refused
at once (never read) otherwise. Each call runs in a child process with a timeout, so that a
regression that reads /dev/zero or blocks on a FIFO fails instead of hanging the suite (the
timeout detects a hang; it is no performance limit)."""

import json
import os
import subprocess
import sys
import textwrap

import pytest

import flexprr

# The calls that take a path, each given the path as its only file.
CALLS = {
    "Scene.load": "flexprr.Scene.load(path)",
    "run": "flexprr.run(path)",
    "run_many": "flexprr.run_many([path])",
    "run_many_processes": "flexprr.run_many([path], processes=1)",
    "link_frequencies": "flexprr.link_frequencies(path)",
    "run_study": "flexprr.run_study(path, out)",
}

CHILD = textwrap.dedent(
    """
    import json, sys
    import flexprr
    path, out, call = sys.argv[1], sys.argv[2], sys.argv[3]
    try:
        eval(call)
        print(json.dumps({"error": None}))
    except Exception as e:
        print(json.dumps({"error": type(e).__name__, "text": str(e)}))
    """
)


def call_in_child(call, path, out):
    """Runs `call` on `path` in a fresh interpreter; its error type and text."""
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(path), str(out), call],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, f"the interpreter died ({done.returncode}): {done.stderr[-2000:]}"
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "scene.toml"
    os.mkfifo(path)
    return path


@pytest.fixture
def too_big(tmp_path):
    path = tmp_path / "big.toml"
    with open(path, "w") as f:
        f.write("# padding\n" * (450 * 1024))  # 4.6 MB of comments: valid TOML, too large
    return path


@pytest.mark.parametrize("call", sorted(CALLS))
@pytest.mark.parametrize(
    "target, expected",
    [("dev_zero", "not a regular file"), ("fifo", "not a regular file"), ("directory", "directory"), ("too_big", "MiB")],
)
def test_non_files_and_huge_files_are_refused_at_once(call, target, expected, fifo, too_big, tmp_path):
    path = {"dev_zero": "/dev/zero", "fifo": fifo, "directory": tmp_path, "too_big": too_big}[target]
    outcome = call_in_child(CALLS[call], path, tmp_path / "out")
    assert outcome["error"] in ("SceneError", "StudyError"), outcome
    assert str(path) in outcome["text"]
    # the studies crate words it its own way
    assert expected in outcome["text"] or (call == "run_study" and target != "too_big"), outcome
    assert "\n" not in outcome["text"]


def test_missing_file_is_a_scene_error_naming_it(tmp_path):
    with pytest.raises(flexprr.SceneError, match="nothing.toml"):
        flexprr.Scene.load(tmp_path / "nothing.toml")
    with pytest.raises(flexprr.SceneError, match="nothing.toml"):
        flexprr.run(str(tmp_path / "nothing.toml"))


def test_run_accepts_str_and_pathlike(root):
    import numpy as np

    path = root / "configs" / "paper_f20.toml"
    from_scene = flexprr.run(flexprr.Scene.load(path))
    for given in (path, str(path)):
        r = flexprr.run(given)
        assert r.tables == from_scene.tables
        np.testing.assert_array_equal(r.table("deflections").to_numpy(), from_scene.table("deflections").to_numpy())
    with pytest.raises(TypeError, match="Scene or the path"):
        flexprr.run(42)
    with pytest.raises(TypeError, match="sequence of scenes"):
        flexprr.run_many(str(path))


def test_link_frequencies_refuses_like_flexprr_beam(tmp_path, cli):
    path = tmp_path / "link.toml"
    path.write_text("length = 0.2\nmodes = 3\nlenght = 1\n")
    beam = subprocess.run([str(cli), "beam", str(path)], capture_output=True, text=True)
    assert beam.returncode == 2
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.link_frequencies(path)
    assert str(info.value) in beam.stderr
    assert info.value.line == 3 and info.value.key == "lenght"
