"""flexprr.linearize and the state-space export: the CLI's statespace.npz read by numpy as
is, the arrays taken by scipy.signal and python-control as they are, the modes against
LAPACK's eigenvalues, the frequency response against the CLI's Hessenberg one, errors, and
the servo-damping example (a kd designed on the linear model, checked in a closed-loop run).
"""

import json
import pickle
import subprocess

import numpy as np
import pytest

import flexprr

POSE = (-0.05, 0.02, 40.0)
INPUTS = ["slider_force:1", "point_force:2@0.25"]
OUTPUTS = ["slider:1", "platform:phi", "deflection:2@0.5", "acceleration:2@0.5"]


@pytest.fixture(scope="module")
def servo(root):
    return flexprr.linearize(root / "configs" / "servo_f20.toml", pose=POSE, inputs=INPUTS, outputs=OUTPUTS)


def test_the_cli_npz_loads_with_numpy_and_holds_the_same_model(root, cli, tmp_path, servo):
    out = tmp_path / "ss"
    args = [str(cli), "statespace", str(root / "configs" / "servo_f20.toml"), "--pose", "-0.05,0.02,40"]
    for name in INPUTS:
        args += ["--input", name]
    for name in OUTPUTS:
        args += ["--output", name]
    subprocess.run(args + ["--out", str(out)], check=True, capture_output=True)
    with np.load(out / "statespace.npz") as npz:
        assert set(npz.files) >= {"A", "B", "C", "D", "x0", "y0", "inputs", "outputs", "states"}
        for key in "ABCD":
            assert npz[key].dtype == np.float64 and npz[key].ndim == 2
            np.testing.assert_array_equal(npz[key], getattr(servo, key))
        assert list(npz["inputs"]) == INPUTS and list(npz["outputs"]) == OUTPUTS
        assert npz["inputs"].dtype.kind == "U"
        assert list(npz["output_units"]) == ["m", "rad", "m", "m/s^2"]
        assert list(npz["states"]) == servo.states
        np.testing.assert_array_equal(npz["x0"], servo.x0)
    data = json.loads((out / "statespace.json").read_text())
    np.testing.assert_allclose(np.array(data["A"]), servo.A, rtol=1e-15, atol=0)
    assert data["operating_point"]["pose"]["phi_deg"] == pytest.approx(40.0)


def test_scipy_and_python_control_take_the_arrays_as_they_are(servo):
    signal = pytest.importorskip("scipy.signal")
    control = pytest.importorskip("control")
    sys_scipy = signal.StateSpace(servo.A, servo.B, servo.C, servo.D)
    sys_control = control.ss(servo.A, servo.B, servo.C, servo.D)
    assert sys_scipy.A.shape == servo.A.shape and sys_control.ninputs == 2 and sys_control.noutputs == 4
    # python-control's damp (LAPACK) against flexprr's modes (faer, balanced).
    wn, zeta, _ = control.damp(sys_control, doprint=False)
    keep = wn > 2 * np.pi * 1e-3
    pairs = sorted(set(zip(np.round(wn[keep] / (2 * np.pi), 9), np.round(zeta[keep], 12))))
    modes = servo.modes()
    assert len(pairs) == len(modes.frequency_hz)
    np.testing.assert_allclose([p[0] for p in pairs], modes.frequency_hz, rtol=1e-8)
    np.testing.assert_allclose([p[1] for p in pairs], modes.damping_ratio, atol=1e-8)
    assert np.all(modes.eigenvalue.imag >= 0)
    # The static gain of slider 1 per its own force: 1 / kp (the chord tensions vanish at
    # equilibrium, docs/linear.md).
    dc = control.dcgain(sys_control)
    assert dc[0, 0] == pytest.approx(1 / 2e5, rel=1e-9)


def test_frequency_response_matches_the_cli(root, cli, tmp_path, servo):
    out = tmp_path / "frf"
    args = [str(cli), "frf", str(root / "configs" / "servo_f20.toml"), "--pose", "-0.05,0.02,40"]
    for name in INPUTS:
        args += ["--input", name]
    for name in OUTPUTS:
        args += ["--output", name]
    args += ["--from", "5", "--to", "1500", "--points", "300", "--out", str(out)]
    subprocess.run(args, check=True, capture_output=True)
    table = np.loadtxt(out / "frf.csv", delimiter=",", skiprows=1)
    header = (out / "frf.csv").read_text().splitlines()[0].split(",")
    # python-control's conventions: rad/s in, (outputs, inputs, frequencies) out.
    h = servo.frequency_response(2 * np.pi * table[:, 0])
    assert h.shape == (len(OUTPUTS), len(INPUTS), table.shape[0])
    for o, output in enumerate(OUTPUTS):
        for i, inp in enumerate(INPUTS):
            stem = f"{output.replace(':', '_').replace('@', '_xi')}_per_{inp.replace(':', '_').replace('@', '_xi')}"
            mag = table[:, [k for k, name in enumerate(header) if name.startswith(stem + "_mag")][0]]
            phase = table[:, header.index(stem + "_phase_deg")]
            cli_h = mag * np.exp(1j * np.radians(phase))
            scale = np.maximum(np.abs(h[o, i, :]), abs(servo.D[o, i]))
            # The CSV keeps 11 significant digits.
            assert np.max(np.abs(cli_h - h[o, i, :]) / np.maximum(scale, 1e-300)) < 1e-8


def test_operating_points_and_errors(root):
    scene = flexprr.Scene.load(root / "configs" / "coupled_f20.toml")
    along = flexprr.linearize(scene, t=0.01, inputs=["slider_force:1"], outputs=["deflection:1@0.5"])
    assert along.operating_point == {"kind": "time", "t": 0.01} and along.t == pytest.approx(0.01)
    # The locked machine at rest with rigid chords: nine pinned-pinned bending modes,
    # 116.39 Hz three times first.
    rigid = flexprr.linearize(scene, pose=(0.0, 0.0, 45.0), rigid_chords=True)
    assert rigid.A.shape == (18, 18) and rigid.B.shape == (18, 0) and rigid.C.shape == (0, 18)
    assert not rigid.elastic_chords
    np.testing.assert_allclose(rigid.modes().frequency_hz[:3], 116.3914, rtol=1e-6)
    # By default the chords are the links' axial springs: the platform's three deviations
    # and their rates join the state, and the first bending family moves by 1e-4 at most.
    rest = flexprr.linearize(scene, pose=(0.0, 0.0, 45.0))
    assert rest.elastic_chords and rest.A.shape == (42, 42)
    assert sum("platform deviation" in s for s in rest.states) == 6
    np.testing.assert_allclose(rest.modes().frequency_hz[:3], 116.3914, rtol=1e-4)
    default = flexprr.linearize(scene)
    assert default.operating_point["kind"] == "rest"
    with pytest.raises(flexprr.SceneError) as bad:
        flexprr.linearize(scene, inputs=["slider_force:4"])
    assert bad.value.key == "inputs" and "slider must be 1, 2 or 3" in str(bad.value)
    with pytest.raises(flexprr.SceneError):
        flexprr.linearize(scene, pose=(0.0, 0.0, 45.0), t=0.01)
    with pytest.raises(flexprr.SceneError) as singular:
        flexprr.linearize(scene, pose=(0.0, 0.0, 0.0))
    assert "type-II" in str(singular.value)
    with pytest.raises(flexprr.SceneError) as ked:
        flexprr.linearize(root / "configs" / "paper_f20.toml")
    assert ked.value.key == "model.coupling"
    with pytest.raises(TypeError):
        flexprr.linearize(scene, inputs="slider_force:1")
    copy = pickle.loads(pickle.dumps(rest))
    np.testing.assert_array_equal(copy.A, rest.A)
    assert copy.modes().frequency_hz[0] == rest.modes().frequency_hz[0]


def test_servo_damping_example_is_verified_by_a_closed_loop_run(root):
    pytest.importorskip("control")
    import importlib.util

    spec = importlib.util.spec_from_file_location("servo_damping", root / "examples" / "python" / "servo_damping.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    found = example.main(0.3)
    # The design reaches its target, flexprr's own linearisation with that kd agrees with
    # the loop closed in python-control, and the run follows the linear prediction.
    assert found["damping_ratio"].min() == pytest.approx(0.3, abs=1e-6)
    assert 100 < found["kd"] < 400
    assert found["pole_difference"] < 1e-8
    assert found["difference"] < 0.01
    # A lighter kd rings longer: the same move with kd / 4 leaves a larger error at 30 ms.
    light = example.verify(found["kd"] / 4)
    late = found["t"] > 0.03
    assert np.abs(light["measured"][late]).max() > 2 * np.abs(found["measured"][late]).max()


# Issue 35: python-control and SciPy natively.

SHIPPED = ["coupled_f20.toml", "servo_f20.toml", "servo_motor_f2.toml", "servo_motor_f20.toml", "piezo_coupled.toml"]


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_exports_load_into_python_control_with_names_and_the_poles_of_modes(root, cli, tmp_path, name):
    control = pytest.importorskip("control")
    scene = root / "configs" / name
    if not scene.exists():
        pytest.skip(f"{name} is not shipped")
    out = tmp_path / "ss"
    subprocess.run(
        [str(cli), "statespace", str(scene), "--input", "slider_force:1", "--output", "slider:1", "--out", str(out)],
        check=True,
        capture_output=True,
    )
    with np.load(out / "statespace.npz") as npz:
        sys = control.ss(
            npz["A"],
            npz["B"],
            npz["C"],
            npz["D"],
            float(npz["dt"]),
            inputs=list(npz["input_signals"]),
            outputs=list(npz["output_signals"]),
            states=list(npz["state_signals"]),
        )
        assert np.linalg.cond(npz["A"]) <= 1e7
    assert sys.input_labels == ["slider_force_1"] and sys.output_labels == ["slider_1"]
    modes = json.loads(subprocess.run(
        [str(cli), "modes", str(scene), "--json", "--count", "1000"], check=True, capture_output=True
    ).stdout)["modes"]
    wn, zeta, _ = control.damp(sys, doprint=False)
    keep = wn > 2 * np.pi * 1e-3
    found = np.sort(wn[keep] / (2 * np.pi))
    ours = np.sort([m["frequency_hz"] for m in modes for _ in range(1 if abs(m["eigenvalue"][1]) < 1e-9 else 2)])
    np.testing.assert_allclose(found, ours, rtol=1e-7)


def test_to_control_and_to_scipy_agree_with_the_model(servo):
    control = pytest.importorskip("control")
    signal = pytest.importorskip("scipy.signal")
    sys = servo.to_control()
    assert sys.dt == 0 and sys.nstates == servo.A.shape[0]
    assert sys.input_labels == ["slider_force_1", "point_force_2_at_0p25"]
    assert sys.output_labels == ["slider_1", "platform_phi", "deflection_2_at_0p5", "acceleration_2_at_0p5"]
    assert sys.state_labels == servo.state_signals and "rho_1_rate" in sys.state_labels
    w = 2 * np.pi * np.array([3.0, 80.0, 116.0, 470.0, 1500.0])
    ours = servo.frequency_response(w)
    theirs = np.stack([sys(1j * wk) for wk in w], axis=-1)
    np.testing.assert_allclose(ours, theirs, rtol=1e-8, atol=1e-14 * np.abs(theirs).max())
    response = control.frequency_response(sys, w)
    np.testing.assert_allclose(np.abs(ours), response.magnitude, rtol=1e-8, atol=1e-14)
    # SciPy: the same matrices and the step response of python-control (scipy's freqresp and
    # poles go through polynomials, which lose every digit at this order).
    scipy_sys = servo.to_scipy()
    assert isinstance(scipy_sys, signal.StateSpace) and scipy_sys.dt is None
    np.testing.assert_array_equal(scipy_sys.A, servo.A)
    t = np.linspace(0, 0.02, 401)
    _, y_scipy = signal.step(signal.StateSpace(servo.A, servo.B[:, :1], servo.C[:1], servo.D[:1, :1]), T=t)
    y_control = control.step_response(sys[0, 0], T=t).outputs
    np.testing.assert_allclose(y_scipy, y_control, rtol=1e-6, atol=1e-6 * np.abs(y_control).max())
    # The physical realisation: the same transfer, a badly conditioned A.
    physical = servo.physical()
    np.testing.assert_allclose(physical.frequency_response(w), ours, rtol=1e-8, atol=1e-14)
    assert np.linalg.cond(physical.A) > 1e3 * np.linalg.cond(servo.A)


def test_signal_names_connect_in_python_control(root):
    control = pytest.importorskip("control")
    plant = flexprr.linearize(
        root / "configs" / "servo_f20.toml",
        pose=(-0.05, 0.0, 45.0),
        inputs=["reference:1"],
        outputs=["slider_error:1", "slider:1"],
    ).to_control(name="machine")
    # An outer integrator on the tracking error, connected by the signal names alone.
    outer = control.ss(0, 1, 1, 0, inputs="slider_error_1", outputs="u_outer", name="outer")
    closed = control.interconnect(
        [plant, outer], inplist=["machine.reference_1"], outlist=["machine.slider_1", "outer.u_outer"]
    )
    assert closed.ninputs == 1 and closed.noutputs == 2


def test_a_sampled_law_gives_a_discrete_python_control_system(root):
    control = pytest.importorskip("control")
    scene = flexprr.Scene.load(root / "configs" / "servo_f20.toml")
    scene.set("control.period", 0.001)
    lin = flexprr.linearize(scene, pose=(-0.05, 0.02, 40.0), inputs=["slider_force:1"], outputs=["slider:1"])
    assert lin.dt == pytest.approx(1e-3) and lin.is_discrete()
    sys = lin.to_control()
    assert sys.dt == pytest.approx(1e-3) and control.isdtime(sys)
    # Its poles are the modes' z, and its static gain is the continuous one (1 / kp).
    z = np.linalg.eigvals(lin.A)
    s = np.log(z.astype(complex)) / lin.dt
    s = s[(s.imag >= 0) & (np.abs(s) > 2 * np.pi * 1e-3)]
    np.testing.assert_allclose(np.sort(np.abs(s)) / (2 * np.pi), np.sort(lin.modes().frequency_hz), rtol=1e-7)
    assert control.dcgain(sys) == pytest.approx(5e-6, rel=1e-6)
    # The frequency response at z = exp(i w T), python-control's own evaluation.
    w = np.array([10.0, 600.0, 3000.0])
    ours = lin.frequency_response(w)[0, 0]
    theirs = np.array([sys(np.exp(1j * wk * lin.dt)) for wk in w]).ravel()
    np.testing.assert_allclose(ours, theirs, rtol=1e-8)
    with pytest.raises(ValueError):
        lin.frequency_response([np.pi / lin.dt * 1.01])
    # The scipy system is discrete too.
    assert lin.to_scipy().dt == pytest.approx(1e-3)


def _synthetic(a, b, c, d, dt=0.0):
    """A LinearModel of a given (A, B, C, D), as flexprr.linearize returns it."""
    n = a.shape[0]
    return flexprr.LinearModel({
        "A": a, "B": b, "C": c, "D": d, "x0": np.zeros(n), "y0": np.zeros(c.shape[0]), "dt": dt,
        "inputs": ["actuator_command:1"], "outputs": ["slider_command:1"], "states": [f"x{k}" for k in range(n)],
        "input_units": ["N"], "output_units": ["N"], "operating_point": {"kind": "rest"}, "t": 0.0,
        "model": "test", "scene": "test", "elastic_chords": False,
        "frequency_hz": np.abs(np.linalg.eigvals(a)) / (2 * np.pi), "damping_ratio": np.zeros(n),
        "eigenvalue_re": np.zeros(n), "eigenvalue_im": np.zeros(n),
    })


def test_slider_loop_margins_against_python_control(root):
    control = pytest.importorskip("control")
    # A low-order loop, where python-control's polynomial method is exact: L = 30 / ((s+1)(s+2)(s+3))
    # with the sign of a loop broken at its actuator (the model's output is -L).
    L = control.tf(30, np.poly([-1, -2, -3]))
    ss = control.ss(-L)
    loop = flexprr.SliderLoop(1, _synthetic(ss.A, ss.B, ss.C, ss.D))
    gm, pm, sm, wpc, wgc, _ = control.stability_margins(L, returnall=False)
    ours = loop.margins()
    assert ours.gain_margin == pytest.approx(gm, rel=1e-6)
    assert ours.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert 2 * np.pi * ours.gain_crossover_hz == pytest.approx(wgc, rel=1e-6)
    assert 2 * np.pi * ours.phase_crossover_hz == pytest.approx(wpc, rel=1e-6)
    assert ours.sensitivity_peak == pytest.approx(1 / sm, rel=1e-3)
    # The machine's loop at slider 1 (the servo scene): python-control's margins of the same
    # exact response (an FRD), its closed loop the machine's closed-loop poles.
    machine = flexprr.slider_loop(root / "configs" / "servo_f20.toml", 1, pose=(-0.05, 0.02, 40.0))
    w = machine.grid()
    frd = control.frd(machine.response(w), w)
    gm, pm, sm, wpc, wgc, _ = control.stability_margins(frd)
    ours = machine.margins()
    assert ours.phase_margin_deg == pytest.approx(pm, abs=0.05)
    assert 2 * np.pi * ours.gain_crossover_hz == pytest.approx(wgc, rel=1e-3)
    assert ours.sensitivity_peak == pytest.approx(1 / sm, rel=1e-3)
    closed = control.feedback(machine.loop_gain(), 1)
    full = flexprr.linearize(root / "configs" / "servo_f20.toml", pose=(-0.05, 0.02, 40.0))
    wn = np.abs(np.linalg.eigvals(closed.A))
    wn = np.sort(wn[wn > 2 * np.pi * 1e-3]) / (2 * np.pi)
    want = np.sort(np.repeat(full.modes().frequency_hz, 2))
    np.testing.assert_allclose(np.unique(np.round(wn, 6)), np.unique(np.round(want, 6)), rtol=1e-6)


def test_models_along_the_motion_from_one_integration(root):
    scene = root / "configs" / "servo_f20.toml"
    series = flexprr.linearize(scene, t=[0.002, 0.006, 0.01], inputs=["slider_force:1"], outputs=["slider:1"])
    assert isinstance(series, flexprr.LinearModels) and len(series) == 3
    assert series.A.shape == (3,) + series[0].A.shape
    np.testing.assert_allclose(series.t, [0.002, 0.006, 0.01])
    for k, t in enumerate(series.t):
        one = flexprr.linearize(scene, t=float(t), inputs=["slider_force:1"], outputs=["slider:1"]).physical()
        np.testing.assert_allclose(series[k].physical().A, one.A, rtol=1e-6, atol=1e-6 * np.abs(one.A).max())
