"""flexprr.plan: the plan of a scene's [plan] section from Python, checked against the
CLI's contract: the planned scene runs, and its slider speeds and rigid drive forces (the run
layer's kinematics and inverse dynamics) keep the plan's limits; a shaped move leaves a small
fraction of the unshaped move's residual vibration; bad settings raise SceneError at their
key."""

import pathlib

import numpy as np
import pytest

import flexprr

CONFIGS = pathlib.Path(__file__).resolve().parents[2] / "configs"


def test_plan_returns_duration_tables_and_a_runnable_scene():
    plan = flexprr.plan(CONFIGS / "plan_pick_and_place.toml")
    assert 0.09 < plan.duration < 0.11
    assert plan.frequency_hz is None
    report = plan.report
    assert report["duration_s"] == pytest.approx(plan.duration, rel=1e-15)
    assert report["flexible_check"]["shaped_over_unshaped"] < 0.05
    timing = plan.timing
    assert timing["s"][0] == 0.0 and np.all(np.diff(timing["s"]) > 0)
    assert timing["s_dot"][0] == 0.0 and timing["s_dot"][-1] == 0.0
    scene = plan.to_scene()
    scene.set("output.requests", ["kinematics", "driving_forces"])
    result = flexprr.run(scene)
    speeds = np.abs(np.stack([result["kinematics"][f"rho_dot_{i}_m_s"] for i in (1, 2, 3)]))
    forces = np.abs(np.stack([result["driving_forces"][f"F_a_{i}_rigid_N"] for i in (1, 2, 3)]))
    assert speeds.max() <= 1.001 and speeds.max() > 0.99
    assert forces.max() <= 400.4


def test_periodic_plan_has_a_frequency_and_bad_settings_raise_at_their_key():
    scene = flexprr.Scene.load(CONFIGS / "paper_f20.toml")
    scene.set("plan.boundary", "periodic")
    scene.set("plan.slider_speed", 1.0)
    plan = flexprr.plan(scene, flexible_check=False)
    assert plan.frequency_hz == pytest.approx(1.0 / plan.duration)
    assert "flexible_check" not in plan.report
    scene.set("plan.slider_speed", -1.0)
    with pytest.raises(flexprr.SceneError) as caught:
        flexprr.plan(scene)
    assert "plan.slider_speed" in str(caught.value)
