"""Errors: the CLI's located messages as SceneError, failed runs as RunError with partial data."""

import subprocess

import numpy as np
import pytest

import flexprr


def test_unknown_key_is_located_like_the_cli(tmp_path, root, cli):
    text = (root / "configs" / "paper_f20.toml").read_text().replace("[links]\n", "[links]\nlenght = 1.0\n", 1)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    check = subprocess.run([str(cli), "check", str(path)], capture_output=True, text=True)
    assert check.returncode == 2
    scene = flexprr.Scene.load(path)
    with pytest.raises(flexprr.SceneError) as info:
        scene.validate()
    e = info.value
    assert "lenght" in e.key
    assert e.file == str(path)
    expected_line = text.splitlines().index("lenght = 1.0") + 1
    assert e.line == expected_line
    # the same message as `flexprr check`
    assert str(e) in check.stderr


def test_bad_value_set_from_python_names_the_key(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    scene.set("links.section.thickness", -1.0)
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.run(scene)
    assert info.value.key == "links.section.thickness"
    assert isinstance(info.value, ValueError)


def test_syntax_error_is_located():
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.Scene.from_toml("name = \"x\"\n[machine\n", name="broken")
    assert info.value.line == 2


def test_set_into_a_scalar_is_refused(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    with pytest.raises(flexprr.SceneError) as info:
        scene.set("name.first", 1)
    assert info.value.key == "name.first"


def test_get_and_set_round_trip(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    scene["links.section.thickness"] = 3  # int over float becomes float
    assert scene.get("links.section.thickness") == pytest.approx(3.0)
    assert isinstance(scene["links.section.thickness"], float)
    assert scene["machine.alpha_deg.1"] == pytest.approx(270.0)
    with pytest.raises(KeyError):
        scene.get("links.nothing")


def test_failed_run_keeps_partial_data(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    scene.set("output.requests", ["deflections"]).set("output.plots", False)
    scene.set("integrator.max_steps", 50)
    with pytest.raises(flexprr.RunError) as info:
        flexprr.run(scene)
    e = info.value
    assert e.kind == "too-many-steps"
    assert e.time is not None and 0.0 < e.time < 0.2
    partial = e.partial
    assert partial.summary["status"] == "failed"
    t = partial.table("deflections")["t_s"]
    # samples up to the failure only, and some were computed
    assert len(t) > 0
    assert t[-1] <= e.time + 1e-12
    assert np.all(np.diff(t) > 0)


def test_run_many_returns_exceptions_in_place(root):
    good = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    good.set("output.requests", ["kinematics"]).set("output.plots", False)
    bad = good.copy().set("time.end", -1.0)
    out = flexprr.run_many([good, bad], return_exceptions=True)
    assert isinstance(out[0], flexprr.RunResult)
    assert isinstance(out[1], flexprr.SceneError) and out[1].key.startswith("time")
    with pytest.raises(flexprr.SceneError):
        flexprr.run_many([good, bad])
