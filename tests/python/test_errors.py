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


@pytest.mark.parametrize("where", [{}, {"processes": 2}])
def test_run_many_keeps_every_result_in_its_place(root, tmp_path, where):
    """Issue 34: one missing or unparsable path raised at once and every other scene's result
    was lost. Each entry now gets its own outcome in its place, and every other scene runs."""
    good = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    good.set("output.requests", ["kinematics"]).set("output.plots", False).set("time.end", 0.01)
    syntax = tmp_path / "syntax.toml"
    syntax.write_text("[trajectory\nkind = 1\n")
    bad_value = good.copy().set("time.end", -1.0)
    collapse = flexprr.Scene.load(root / "configs" / "coupled_f20.toml")
    collapse.set("trajectory.frequency", 30.0).set("time.end", 0.06).set("output.plots", False)
    entries = [good, tmp_path / "missing.toml", syntax, bad_value, collapse, 42, str(root / "configs" / "paper_f10.toml")]
    out = flexprr.run_many(entries, return_exceptions=True, **where)
    assert len(out) == len(entries)
    assert isinstance(out[0], flexprr.RunResult) and out[0].summary["status"] == "ok"
    assert isinstance(out[1], flexprr.SceneError) and "missing.toml" in str(out[1])
    assert isinstance(out[2], flexprr.SceneError) and "syntax.toml:1" in str(out[2])
    assert isinstance(out[3], flexprr.SceneError) and out[3].key.startswith("time")
    assert isinstance(out[4], flexprr.RunError) and out[4].kind == "collapse"
    assert out[4].partial.summary["status"] == "failed"
    assert isinstance(out[5], TypeError)
    assert isinstance(out[6], flexprr.RunResult)
    # The same good scene alone gives the same data.
    alone = flexprr.run(good)
    np.testing.assert_array_equal(out[0].table("kinematics").to_numpy(), alone.table("kinematics").to_numpy())
    # Without return_exceptions an entry that cannot be read is raised at once.
    with pytest.raises(flexprr.SceneError, match="missing.toml"):
        flexprr.run_many([good, tmp_path / "missing.toml"], **where)
