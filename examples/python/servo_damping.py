"""Choosing the servo's derivative gain from the linear model, and checking it in a run.

The scene is configs/servo_f20.toml: the paper's machine, coupled model (flexible links),
each slider driven by an ideal force under PD control, kp = 2e5 N/m. Its three servo modes
(80-96 Hz, below the links' 116 Hz) are what kd damps.

1. Design (python-control): flexprr.linearize gives the machine at rest at the circle's
   centre with kd = 0 (kp inside) as A, B, C, D from the slider forces to the slider
   positions. Adding the slider velocities as outputs (y' = C A x + C B u), the velocity
   feedback u = -kd y' is closed with control.feedback, and scipy's brentq finds the kd
   that gives the least-damped servo mode the target damping ratio (control.damp).
2. Cross-check: flexprr.linearize of the scene with that kd has the same poles (the
   scene's own PD law, linearised by flexprr).
3. Verification in a closed-loop run: a small, quick rest-to-rest move (0.5 mm in 5 ms,
   feedforward off, so that the feedback does all the work) run by flexprr against the
   linear prediction: scipy.signal.lsim of the closed-loop linear model, driven by the
   forces the PD law adds to the linear model's own when its reference moves,
   u = kp r + kd r' (r the commanded slider displacement, from the run's kinematics table).
   The tracking errors rho_ref - rho of the run and of the linear model agree to about 1 %
   of their peak (the move is small: the rest is geometric nonlinearity).

Run from the repository root:  python examples/python/servo_damping.py [target_zeta]
"""

import pathlib
import sys

import control
import numpy as np
from scipy.optimize import brentq
from scipy.signal import StateSpace, lsim

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "configs" / "servo_f20.toml"
#: The circle's centre, where the design is made (x m, y m, phi deg).
POSE = (-0.05, 0.0, 45.0)
SLIDERS = [1, 2, 3]
INPUTS = [f"slider_force:{i}" for i in SLIDERS]
OUTPUTS = [f"slider:{i}" for i in SLIDERS]


def scene(kd: float) -> flexprr.Scene:
    """The servo scene with derivative gain kd (N s/m)."""
    s = flexprr.Scene.load(SCENE)
    s.set("control.kd", float(kd))
    return s


def servo_modes(sys) -> tuple:
    """(natural frequencies in Hz, damping ratios) of the three lowest modes: the servo
    modes, below the links' first bending modes (116 Hz)."""
    wn, zeta, _ = control.damp(sys, doprint=False)
    order = np.argsort(wn)
    # damp lists each complex pair twice; keep one of each.
    seen, modes = set(), []
    for k in order:
        key = round(float(wn[k]), 6)
        if key not in seen:
            seen.add(key)
            modes.append((wn[k] / (2 * np.pi), zeta[k]))
    modes = modes[:3]
    return np.array([m[0] for m in modes]), np.array([m[1] for m in modes])


def closed_loop(plant: flexprr.LinearModel, kd: float):
    """The plant (kp inside, kd = 0) with the velocity feedback u = -kd rho' closed."""
    a, b, c = plant.A, plant.B, plant.C
    # Outputs: positions, then velocities y' = C A x + C B u.
    both = control.ss(a, b, np.vstack([c, c @ a]), np.vstack([plant.D, c @ b]))
    gain = np.hstack([np.zeros((3, 3)), kd * np.eye(3)])
    return control.feedback(both, gain)


def design(target_zeta: float, plant: flexprr.LinearModel) -> float:
    """kd (N s/m) that gives the least-damped servo mode the damping ratio target_zeta."""
    def margin(kd):
        return servo_modes(closed_loop(plant, kd))[1].min() - target_zeta

    return brentq(margin, 1.0, 5000.0, xtol=1e-6)


def step_scene(kd: float, end: float = 0.06) -> flexprr.Scene:
    """A 0.5 mm, 0.2 deg rest-to-rest move in 5 ms from POSE, feedforward off."""
    s = scene(kd)
    s.set("control.feedforward", "none")
    s.set(
        "trajectory",
        {
            "kind": "point-to-point",
            "from": list(POSE),
            "to": [POSE[0] + 5e-4, POSE[1] + 3e-4, POSE[2] + 0.2],
            "start": 0.002,
            "duration": 0.005,
        },
    )
    s.set("time.end", end)
    s.set("time.output_step", 1e-4)
    s.set("output.requests", ["tracking", "kinematics"])
    s.set("output.plots", False)
    return s


def verify(kd: float) -> dict:
    """The run's slider tracking errors against the linear prediction; returns the largest
    difference relative to the run's peak error and both series."""
    s = step_scene(kd)
    result = flexprr.run(s)
    kin, tracking = result.table("kinematics"), result.table("tracking")
    t = kin["t_s"]
    r = np.column_stack([kin[f"rho_{i}_m"] - kin[f"rho_{i}_m"][0] for i in SLIDERS])
    r_dot = np.column_stack([kin[f"rho_dot_{i}_m_s"] for i in SLIDERS])
    kp = float(s.get("control.kp"))
    # The linear model at the start pose with the scene's own PD (kp, kd) about a fixed
    # reference; the moving reference adds the forces kp r + kd r'.
    lin = flexprr.linearize(s, pose=POSE, inputs=INPUTS, outputs=OUTPUTS)
    _, y, _ = lsim(StateSpace(lin.A, lin.B, lin.C, lin.D), kp * r + kd * r_dot, t)
    predicted = r - y
    measured = np.column_stack([tracking[f"slider_error_{i}_m"] for i in SLIDERS])
    peak = np.abs(measured).max()
    return {
        "t": t,
        "measured": measured,
        "predicted": predicted,
        "peak_error_m": float(peak),
        "difference": float(np.abs(measured - predicted).max() / peak),
    }


def main(target_zeta: float = 0.3) -> dict:
    plant = flexprr.linearize(scene(0.0), pose=POSE, inputs=INPUTS, outputs=OUTPUTS)
    f0, z0 = servo_modes(control.ss(plant.A, plant.B, plant.C, plant.D))
    print(f"kd = 0: servo modes {np.round(f0, 2)} Hz, damping ratios {np.round(np.abs(z0), 4)}")
    kd = design(target_zeta, plant)
    f1, z1 = servo_modes(closed_loop(plant, kd))
    print(f"kd = {kd:.2f} N s/m: servo modes {np.round(f1, 2)} Hz, damping ratios {np.round(z1, 4)}")
    # flexprr's own linearisation of the scene with this kd: the same poles.
    check = flexprr.linearize(scene(kd), pose=POSE, inputs=INPUTS, outputs=OUTPUTS)
    f2, z2 = check.modes().frequency_hz[:3], check.modes().damping_ratio[:3]
    pole_difference = float(max(np.abs(f2 - f1).max() / f1.min(), np.abs(z2 - z1).max()))
    print(f"flexprr.linearize with kd: {np.round(f2, 2)} Hz, {np.round(z2, 4)} (difference {pole_difference:.1e})")
    run = verify(kd)
    print(
        f"closed-loop run, 0.5 mm move in 5 ms: peak slider error {run['peak_error_m'] * 1e6:.1f} um, "
        f"run against the linear prediction {100 * run['difference']:.2f} % of the peak"
    )
    return {
        "kd": kd,
        "frequency_hz": f1,
        "damping_ratio": z1,
        "pole_difference": pole_difference,
        **run,
    }


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 0.3)
