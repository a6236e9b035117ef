"""A sampled servo designed with python-control on flexprr's linear models (docs/linear.md,
"The python-control workflow").

1. The plant (flexprr.linearize): the servo scene configs/servo_f20.toml with its law's gains
   at zero, at the centre of its circle, from the three slider forces to the three sliders.
   Its response at low frequency is that of the rigid machine, -1 / (w^2 M): the sliders'
   mass matrix M (with the links and the platform seen through them).
2. The design (python-control): an LQR state feedback u = -K (rho, rho') on each slider as a
   mass M_ii, in continuous time (control.lqr), then again for the law's sampled form at the
   period T, the mass discretised with a zero-order hold (control.c2d, control.dlqr). The
   discrete gains are the PD law's kp and kd (the law commands kp e + kd e' at each sample).
3. The check (flexprr): the scene with those gains and period, linearised: the exact
   discrete-time model of the sampled loop on the flexible machine (links, platform, the
   three loops), its poles all inside the unit circle; its response to a setpoint step of
   slider 1 against the design's; slider 1's loop broken at its actuator
   (flexprr.slider_loop): gain and phase margins and the sensitivity peak.
4. The run: the 20 Hz circle with the designed law, its tracking error.

The links get 1 % modal damping (model.damping): without structural damping every aliased
bending or platform mode of a sampled loop sits on the unit circle.

Run from the repository root:  python examples/python/lqr_servo.py [period_s]
"""

import pathlib
import sys

import control
import numpy as np

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "configs" / "servo_f20.toml"
#: The circle's centre (x m, y m, phi deg).
POSE = (-0.05, 0.0, 45.0)
#: LQR weights: 1.25 mm of position error is worth 200 N of force (Bryson's rule); the
#: velocity is not weighted, so the continuous design is kp = 200 N / 1.25 mm = 1.6e5 N/m,
#: kd = sqrt(2 m kp), a damping ratio of 0.71.
Q = np.diag([1 / 1.25e-3**2, 0.0])
R = np.array([[1 / 200.0**2]])
SLIDERS = (1, 2, 3)


def scene(kp: float, kd: float, period: float) -> flexprr.Scene:
    """The servo scene with the PD gains, the law's period and 1 % link damping."""
    s = flexprr.Scene.load(SCENE)
    s.set("control.kp", float(kp))
    s.set("control.kd", float(kd))
    s.set("control.period", float(period))
    s.set("model.damping", [0.01])
    return s


def slider_masses() -> np.ndarray:
    """The sliders' mass matrix M (kg) from the plant's response at 2 Hz: H = -1 / (w^2 M)."""
    plant = flexprr.linearize(
        scene(0.0, 0.0, 0.0),
        pose=POSE,
        inputs=[f"slider_force:{i}" for i in SLIDERS],
        outputs=[f"slider:{i}" for i in SLIDERS],
    )
    w = 2 * np.pi * 2.0
    h = plant.frequency_response([w])[:, :, 0]
    return -np.linalg.inv(w**2 * h).real


def design(mass: float, period: float) -> dict:
    """The LQR gains of a slider of mass `mass`, continuous and sampled at `period`."""
    rigid = control.ss([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0 / mass]], [[1.0, 0.0]], 0.0)
    k_continuous, _, poles_continuous = control.lqr(rigid, Q, R)
    sampled = control.c2d(rigid, period, method="zoh")
    k_discrete, _, poles_discrete = control.dlqr(sampled, Q, R)
    return {
        "continuous": k_continuous[0],
        "discrete": k_discrete[0],
        "poles_continuous": poles_continuous,
        "poles_discrete": poles_discrete,
    }


def main(period: float = 5e-4) -> dict:
    masses = slider_masses()
    mass = float(np.mean(np.diag(masses)))
    print(f"slider mass matrix (kg):\n{np.round(masses, 4)}\ndesign mass {mass:.4f} kg")
    gains = design(mass, period)
    kp_c, kd_c = gains["continuous"]
    kp, kd = gains["discrete"]
    print(f"LQR, continuous: kp = {kp_c:.4g} N/m, kd = {kd_c:.4g} N s/m")
    print(f"LQR at T = {period * 1e3:g} ms: kp = {kp:.4g} N/m, kd = {kd:.4g} N s/m")
    designed = scene(kp, kd, period)
    machine = flexprr.linearize(designed, pose=POSE, inputs=["reference:1"], outputs=["slider:1"])
    largest = float(np.abs(np.linalg.eigvals(machine.A)).max())
    print(
        f"{machine.A.shape[0]}-state discrete model of the sampled loop (dt = {machine.dt} s): "
        f"largest |z| = {largest:.6f}"
    )
    # The design's own closed loop (the rigid slider, python-control) against the flexible
    # machine's (flexprr), from a setpoint step on slider 1: x[k+1] = (Ad - Bd K) x + Bd kp r.
    rigid = control.c2d(
        control.ss([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0 / mass]], [[1.0, 0.0]], 0.0), period
    )
    closed = control.ss(rigid.A - rigid.B @ gains["discrete"][None, :], rigid.B * kp, rigid.C, 0.0, period)
    t = np.arange(80) * period
    design_step = control.step_response(closed, T=t).outputs
    machine_step = control.step_response(machine.to_control(), T=t).outputs
    step_difference = float(np.abs(design_step - machine_step).max())
    print(
        f"setpoint step of slider 1 over {t[-1] * 1e3:.1f} ms: the flexible machine within "
        f"{step_difference:.3f} of the design (final value {machine_step[-1]:.4f})"
    )
    margins = flexprr.slider_loop(designed, 1, pose=POSE).margins()
    print(
        f"slider 1's loop: gain margin {margins.gain_margin:.3g}, phase margin "
        f"{margins.phase_margin_deg:.1f} deg at {margins.gain_crossover_hz:.0f} Hz, "
        f"sensitivity peak {margins.sensitivity_peak:.2f} at {margins.sensitivity_peak_hz:.0f} Hz"
    )
    run_scene = designed.copy()
    run_scene.set("time.end", 0.05)
    run_scene.set("output.requests", ["tracking"])
    run_scene.set("output.plots", False)
    tracking = flexprr.run(run_scene).table("tracking")
    error = np.column_stack([tracking[f"slider_error_{i}_m"] for i in SLIDERS])
    rms = float(np.sqrt(np.mean(error**2)))
    print(f"the 20 Hz circle with this law: RMS slider error {rms * 1e6:.2f} um")
    return {
        "kp": float(kp),
        "kd": float(kd),
        "largest_pole": largest,
        "step_difference": step_difference,
        "margins": margins,
        "rms_error_m": rms,
        "machine": machine,
    }


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 5e-4)
