"""Piezoelectric patches from Python (docs/piezo.md): the scene keys through Scene.set, the
piezo table and the vibration_control summary of a run, and the gain-choosing example
(its damping against the closed form P3, its choice against the voltage limit)."""

import importlib.util
import math

import numpy as np
import pytest

import flexprr

# The shipped scene's link and patch (configs/piezo_f20.toml).
E, RHO, B, T, L = 7.3e10, 2770.0, 0.03, 0.002, 0.2
K_A, K_S = 3.7e-4, 8.0e3
XI = (0.45, 0.55)


@pytest.fixture
def piezo(root):
    s = flexprr.Scene.load(root / "configs" / "piezo_f20.toml")
    s.set("time.end", 0.05)
    s.set("output.plots", False)
    return s


def load_example(root):
    spec = importlib.util.spec_from_file_location("piezo_gain", root / "examples" / "python" / "piezo_gain.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_scene_keys_set_and_check(piezo):
    piezo.set("vibration_control.gain", 2e-3)
    piezo.set("links.patches.0.voltage_limit", 150.0)
    piezo.validate()
    assert piezo["links.patches"][0]["voltage_limit"] == 150.0
    piezo.set("links.patches", [{"links": [2], "xi_start": 0.3, "xi_end": 0.4, "actuator_constant": K_A,
                                  "sensor_constant": K_S, "voltage_limit": 100.0}])
    piezo.validate()
    with pytest.raises(flexprr.SceneError) as info:
        piezo.set("links.patches.0.nope", 1.0)
    assert info.value.key == "links.patches.0.nope"
    piezo.set("links.patches.0.xi_end", 0.2)  # before its start: refused by the checker
    with pytest.raises(flexprr.SceneError) as info:
        piezo.validate()
    assert "links.patches.0" in str(info.value)
    # A law's own keys are checked when the scene is built.
    piezo.set("links.patches.0.xi_end", 0.4)
    piezo.set("vibration_control.kind", "modal_velocity")
    with pytest.raises(flexprr.SceneError) as info:
        piezo.validate()
    assert "vibration_control.gain" in str(info.value)


def test_the_run_exposes_the_piezo_table_and_the_reduction(piezo):
    piezo.set("output.requests", ["deflections", "piezo"])
    piezo.set("links.patches.0.voltage_limit", 60.0)
    result = flexprr.run(piezo)
    table = result.table("piezo")
    assert table.columns[0] == "t_s"
    applied, command = table["V_applied_1_1_V"], table["V_command_1_1_V"]
    np.testing.assert_array_equal(applied, np.clip(command, -60.0, 60.0))
    np.testing.assert_array_equal(table["patch_saturated_1_1_flag"], (np.abs(command) > 60.0).astype(float))
    section = result.summary["vibration_control"]
    assert section["law"] == "strain_rate" and section["uncontrolled_run"] is True
    assert section["any_saturated"] is True and section["max_abs_voltage_V"] == 60.0
    deflections = result.table("deflections")
    w, free = deflections["w_1_xi0.5_m"], deflections["w_1_xi0.5_uncontrolled_m"]
    reduction = 100 * (1 - np.abs(w).max() / np.abs(free).max())
    assert section["links"][0]["peak_reduction_percent"] == pytest.approx(reduction, abs=1e-9)
    assert reduction > 5


def test_the_example_damping_follows_the_closed_form_and_the_choice_the_limit(root):
    example = load_example(root)
    # P3 with the first sine mode of the pinned-pinned link (the ratio d^2 / m does not
    # depend on how the mode is scaled): m = rho A l / 2, d = psi'(x2) - psi'(x1).
    area = B * T
    omega = (math.pi / L) ** 2 * math.sqrt(E * B * T**3 / 12 / (RHO * area))
    d = math.pi / L * (math.cos(math.pi * XI[0]) - math.cos(math.pi * XI[1]))
    gain = 1e-3
    zeta = gain * K_A * K_S * d**2 / (2 * RHO * area * L / 2 * omega)
    got = example.first_mode_damping(gain)
    # At rest the coupled machine's first mode is the links' first mode (no axial load);
    # P3 is first order in G (measured: 1.4e-5 apart at G = 1 ms).
    assert got == pytest.approx(zeta, rel=1e-3)
    gains = [0.0, 1e-3, 2e-3, 3e-3, 4e-3, 6e-3]
    out = example.choose(120.0, gains)
    volts = out["max_command_V"]
    assert volts[out["best"]] <= 120.0
    # The damping grows with the gain here, so the choice is the largest gain within the limit.
    assert np.all(np.diff(out["zeta"]) > 0)
    assert out["best"] == max(k for k, v in enumerate(volts) if v <= 120.0)
    assert volts[out["best"] + 1] > 120.0
