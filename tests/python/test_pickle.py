"""Scenes, results and exceptions pickle, so they cross process boundaries whole."""

import copy
import pickle

import numpy as np
import pytest

import flexprr


def round_trip(value):
    return pickle.loads(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))


@pytest.fixture(scope="module")
def short_scene(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    scene.set("time.end", 0.02)
    return scene


def test_scene_round_trip_keeps_table_origin_and_changes(root, short_scene):
    loaded = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    back = round_trip(loaded)
    # unmodified: the original text, so errors keep their file locations
    assert back.to_toml() == loaded.to_toml() == (root / "configs" / "paper_f20.toml").read_text()
    assert repr(back) == repr(loaded)
    back2 = round_trip(short_scene)
    assert back2.to_dict() == short_scene.to_dict()
    assert back2.changed_keys == ["time.end"]
    assert back2.name == short_scene.name
    from_dict = flexprr.Scene.from_dict(short_scene.to_dict(), name="d")
    assert round_trip(from_dict).to_dict() == from_dict.to_dict()
    assert copy.deepcopy(short_scene).to_dict() == short_scene.to_dict()


def test_a_set_error_after_a_round_trip_still_names_the_key(short_scene):
    bad = round_trip(short_scene.copy().set("links.section.thickness", -1.0))
    with pytest.raises(flexprr.SceneError) as info:
        bad.validate()
    assert info.value.key == "links.section.thickness" and info.value.line is None


def test_run_result_round_trip_is_exact(short_scene):
    result = flexprr.run(short_scene)
    back = round_trip(result)
    assert back.tables == result.tables and back.scene == result.scene
    for name in result.tables:
        a, b = result.table(name), back.table(name)
        assert a.columns == b.columns
        np.testing.assert_array_equal(a.to_numpy(), b.to_numpy())
    # floats in the summary keep every bit
    assert back.summary == result.summary
    assert back.stats == result.stats
    assert back.table_one == result.table_one


def test_scene_error_round_trip_keeps_its_attributes(short_scene):
    with pytest.raises(flexprr.SceneError) as info:
        short_scene.set("links.nope", 1.0)
    back = round_trip(info.value)
    assert type(back) is flexprr.SceneError and isinstance(back, ValueError)
    assert str(back) == str(info.value)
    for attr in ("key", "message", "file", "line", "column"):
        assert getattr(back, attr) == getattr(info.value, attr)


def test_run_error_round_trip_keeps_the_partial_result(short_scene):
    scene = short_scene.copy().set("output.requests", ["deflections"]).set("integrator.max_steps", 50)
    with pytest.raises(flexprr.RunError) as info:
        flexprr.run(scene)
    back = round_trip(info.value)
    assert type(back) is flexprr.RunError
    assert (back.kind, back.time, back.link) == (info.value.kind, info.value.time, info.value.link)
    np.testing.assert_array_equal(
        back.partial.table("deflections").to_numpy(), info.value.partial.table("deflections").to_numpy()
    )
    assert back.partial.summary["status"] == "failed"


def test_other_exceptions_pickle():
    for cls in (flexprr.KinematicsError, flexprr.StudyError):
        e = cls("message")
        assert type(round_trip(e)) is cls and str(round_trip(e)) == "message"
    with pytest.raises(flexprr.KinematicsError) as info:
        flexprr.inverse_kinematics([[0.0, 0.0, 0.785], [5.0, 5.0, 0.0]])
    assert round_trip(info.value).index == 1


def test_a_damaged_result_state_is_a_value_error():
    with pytest.raises((ValueError, TypeError)):
        flexprr.RunResult._restore(("x", [("t", ["t_s"], [b"\x00" * 7])], {}, (True, 0, 0, None, None, None, 0.0), None))
