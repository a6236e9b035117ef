"""Control laws in Python (control.kind = "python"), delay and quantisation of the measurements,
and flexprr.margins (docs/control.md). Checked against the built-in sampled PD, the closed-form
phase lag -w d of a transport delay, the encoder's step, `flexprr margins --json` and
python-control's stability_margins."""

import json
import re
import subprocess

import numpy as np
import pytest

import flexprr

KP, KD, PERIOD = 2e5, 400.0, 5e-4
ERRORS = [f"slider_error:{i}" for i in (1, 2, 3)] + [f"slider_error_rate:{i}" for i in (1, 2, 3)]
FORCES = [f"slider_force:{i}" for i in (1, 2, 3)]


def servo_text(root, control, end=0.03):
    """configs/servo_f20.toml with its [control] table replaced by `control` (TOML lines) and a
    shorter time span."""
    text = (root / "configs" / "servo_f20.toml").read_text()
    head, rest = text.split("\n[control]\n", 1)
    tail = rest[rest.index("\n[integrator]") + 1:]
    tail = re.sub(r"end = [0-9.e-]+", f"end = {end}", tail)
    return head + "\n[control]\n" + control + "\n\n" + tail


def pd_control(period=PERIOD, extra=""):
    return f'kind = "pd"\nkp = {KP}\nkd = {KD}\nfeedforward = "rigid"\nperiod = {period}\n' + extra


def python_control(period=PERIOD, extra=""):
    return (
        f'kind = "python"\nmeasurements = {json.dumps(ERRORS)}\ncommands = {json.dumps(FORCES)}\n'
        f'feedforward = "rigid"\nperiod = {period}\n' + extra
    )


def scene(root, control, end=0.03):
    return flexprr.Scene.from_toml(servo_text(root, control, end), "servo")


def pd_law(t, y):
    return KP * y[:3] + KD * y[3:]


def test_a_python_pd_reproduces_the_sampled_pd_run(root):
    pd = flexprr.run(scene(root, pd_control()))
    calls = []

    def law(t, y):
        calls.append(t)
        assert isinstance(y, np.ndarray) and y.dtype == np.float64 and y.shape == (6,)
        return pd_law(t, y)

    py = flexprr.run(scene(root, python_control()), controller=law)
    # One call per sample, at t0 + k T.
    k = np.round(np.array(calls) / PERIOD)
    np.testing.assert_allclose(calls, k * PERIOD, atol=1e-12)
    assert len(calls) == int(round(0.03 / PERIOD))
    for table, prefix in (("tracking", "slider_error_"), ("actuators", "actuator_force_")):
        for i in (1, 2, 3):
            col = prefix + str(i) + ("_m" if table == "tracking" else "_N")
            a, b = pd[table][col], py[table][col]
            assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(a)), (table, col)


def test_a_python_law_that_raises_stops_the_run_with_its_traceback_and_keeps_the_data(root):
    def law(t, y):
        if t > 0.01:
            return 1.0 / 0.0
        return pd_law(t, y)

    with pytest.raises(flexprr.RunError) as info:
        flexprr.run(scene(root, python_control()), controller=law)
    e = info.value
    message = str(e)
    assert "ZeroDivisionError" in message and "in law" in message and "t = 0.0105 s" in message
    rows = e.partial["tracking"]["t_s"]
    assert rows[-1] <= 0.0105 + 1e-12 and rows[-1] >= 0.0104
    assert len(rows) > 100


@pytest.mark.parametrize(
    "law, words",
    [
        (lambda t, y: [1.0, 2.0], ["returned 2 commands, expected 3", "t = 0 s"]),
        (lambda t, y: [1.0, float("nan"), 0.0], ["slider_force:2", "finite"]),
        (lambda t, y: None, ["returned None", "3 numbers"]),
    ],
)
def test_bad_commands_name_the_sample(root, law, words):
    with pytest.raises(flexprr.RunError) as info:
        flexprr.run(scene(root, python_control()), controller=law)
    for w in words:
        assert w in str(info.value), str(info.value)


def test_a_python_law_needs_its_function_and_its_period(root, cli, tmp_path):
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.run(scene(root, python_control()))
    assert info.value.key == "control.kind" and "controller=f" in str(info.value)
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.run(scene(root, pd_control()), controller=pd_law)
    assert "control.kind" in str(info.value)
    no_period = python_control().replace(f"period = {PERIOD}\n", "")
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.run(scene(root, no_period), controller=pd_law)
    assert info.value.key == "control.period" and "> 0" in str(info.value)
    path = tmp_path / "python_law.toml"
    path.write_text(servo_text(root, python_control()))
    done = subprocess.run([str(cli), "run", str(path), "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert done.returncode != 0
    assert "control.kind" in done.stderr and "flexprr.run(scene, controller=f)" in done.stderr
    assert not (tmp_path / "out").exists()


def one_loop(root, tmp_path, period, extra=""):
    """The servo with a PD feedback on slider 1 only (a state-space law with D = [kp, kd]; the
    other sliders get the feedforward alone), so that slider 1's loop holds the whole delay."""
    np.savez(tmp_path / "pd1.npz", D=np.array([[KP, KD]]))
    control = (
        'kind = "statespace"\nfile = "pd1.npz"\n'
        'measurements = ["slider_error:1", "slider_error_rate:1"]\ncommands = ["slider_force:1"]\n'
        f"period = {period}\n" + extra
    )
    name = f"one_loop_{len(list(tmp_path.glob('*.toml')))}.toml"
    (tmp_path / name).write_text(servo_text(root, control))
    return tmp_path / name


def loop_phase_shift(plain, delayed, w):
    """The phase of slider 1's loop gain with the delay minus without, at w (rad/s)."""
    plain = flexprr.slider_loop(plain, 1).response(w)
    delayed = flexprr.slider_loop(delayed, 1).response(w)
    np.testing.assert_allclose(np.abs(delayed), np.abs(plain), rtol=1e-6)
    return np.angle(delayed / plain)


def test_a_delay_lags_the_loop_by_w_d(root, tmp_path):
    d = 2 * PERIOD
    w = np.geomspace(10.0, 0.9 * np.pi / PERIOD, 40)
    # Sampled law: a shift of two samples, z^-2 = exp(-j w d) exactly.
    plain, late = one_loop(root, tmp_path, PERIOD), one_loop(root, tmp_path, PERIOD, f"delay = {d}\n")
    shift = loop_phase_shift(plain, late, w)
    np.testing.assert_allclose(shift, np.angle(np.exp(-1j * w * d)), atol=1e-7)
    assert any("shift of 2 samples" in n for n in flexprr.linearize(late).notes)
    # Continuous law: the Pade approximation of order 4, within 1e-3 rad for w d < 2.
    w = w[w * d < 2.0]
    plain = one_loop(root, tmp_path, 0.0)
    late = one_loop(root, tmp_path, 0.0, f"delay = {d}\ndelay_order = 4\n")
    np.testing.assert_allclose(loop_phase_shift(plain, late, w), -w * d, atol=1e-3)


def test_quantisation_moves_the_run_by_at_most_its_step_and_the_linear_model_ignores_it(root):
    base = flexprr.run(scene(root, pd_control(0), end=0.05))["tracking"]
    for q in (1e-6, 1e-5):
        quantised = pd_control(0, f"quantisation = [{q}, {q}, {q}]\n")
        run = flexprr.run(scene(root, quantised, end=0.05))["tracking"]
        for i in (1, 2, 3):
            diff = np.abs(run[f"slider_error_{i}_m"] - base[f"slider_error_{i}_m"])
            # The loop's complementary sensitivity peaks near 1.1: the rounding (at most q / 2)
            # moves the slider by less than q.
            assert 0 < diff.max() <= q, (q, i, diff.max())
        model = flexprr.linearize(scene(root, quantised))
        assert any("quantisation left out" in n for n in model.notes), model.notes
        plain = flexprr.linearize(scene(root, pd_control(0)))
        np.testing.assert_allclose(model.A, plain.A, rtol=1e-12, atol=0)


def test_bad_sensor_keys_are_refused_at_their_key(root):
    for extra, key in [
        ("delay = -1e-3\n", "control.delay"),
        ("delay = nan\n", "control.delay"),
        ("quantisation = [1e-6, 1e-6]\n", "control.quantisation"),
        ("delay_order = 3\n", "control.delay_order"),
    ]:
        with pytest.raises(flexprr.SceneError) as info:
            scene(root, pd_control(extra=extra)).validate()
        assert info.value.key == key, (extra, str(info.value))
    with pytest.raises(flexprr.SceneError) as info:
        scene(root, python_control(extra="quantisation = [1e-6]\n")).validate()
    assert info.value.key == "control.quantisation" and "expected 6" in str(info.value)


def test_margins_equal_the_cli_and_python_control(root, cli):
    path = root / "configs" / "servo_f20.toml"
    ours = flexprr.margins(path)
    done = subprocess.run([str(cli), "margins", str(path), "--json"], capture_output=True, text=True, check=True)
    assert ours == json.loads(done.stdout)
    control = pytest.importorskip("control")
    for row in ours["loops"]:
        loop = flexprr.slider_loop(path, row["slider"])
        w = loop.grid()
        gm, pm, sm, wpc, wgc, _ = control.stability_margins(control.frd(loop.response(w), w))
        assert row["phase_margin_deg"] == pytest.approx(pm, abs=0.05)
        assert 2 * np.pi * row["gain_crossover_hz"] == pytest.approx(wgc, rel=1e-3)
        assert row["sensitivity_peak"] == pytest.approx(1 / sm, rel=1e-3)
    with pytest.raises(flexprr.SceneError):
        flexprr.margins(root / "configs" / "paper_f20.toml")
