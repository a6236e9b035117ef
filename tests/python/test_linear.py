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
    h = servo.frequency_response(table[:, 0])
    for o, output in enumerate(OUTPUTS):
        for i, inp in enumerate(INPUTS):
            stem = f"{output.replace(':', '_').replace('@', '_xi')}_per_{inp.replace(':', '_').replace('@', '_xi')}"
            mag = table[:, [k for k, name in enumerate(header) if name.startswith(stem + "_mag")][0]]
            phase = table[:, header.index(stem + "_phase_deg")]
            cli_h = mag * np.exp(1j * np.radians(phase))
            scale = np.maximum(np.abs(h[:, o, i]), abs(servo.D[o, i]))
            # The CSV keeps 11 significant digits.
            assert np.max(np.abs(cli_h - h[:, o, i]) / np.maximum(scale, 1e-300)) < 1e-8


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
    assert rest.elastic_chords and rest.A.shape == (24, 24)
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
