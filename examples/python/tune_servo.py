"""Servo tuning with scipy.optimize: the PD gains kp, kd that give the smallest RMS slider
tracking error while the motor torque stays under a limit.

The scene is configs/servo_motor_f2.toml (BM200-like servo motors on 10 mm-lead ball screws,
the paper's circle at 2 Hz, coupled model) with the feedforward switched off, so that the
feedback does all the work: a stiffer loop tracks better, but a lightly damped one overshoots
when the motion starts and needs more torque than the motion itself. The optimiser (COBYLA,
derivative-free, with the torque limit as an inequality constraint) works on log10 kp and
log10 kd inside bounds; each evaluation is one flexprr run (Rust, GIL released), cached so
that the objective and the constraint share it.

Run from the repository root:  python examples/python/tune_servo.py [torque_limit_N_m]
"""

import functools
import math
import pathlib
import sys

import numpy as np
from scipy.optimize import minimize

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]

#: Search box of log10 kp (N/m) and log10 kd (N s/m).
BOUNDS = ((4.0, 6.0), (1.5, 3.5))


def base_scene(end: float = 0.1) -> flexprr.Scene:
    """The 2 Hz motor scene without feedforward, tracking and actuators only, over `end` s."""
    scene = flexprr.Scene.load(ROOT / "configs" / "servo_motor_f2.toml")
    scene.set("control.feedforward", "none")
    scene.set("time.end", end)
    scene.set("output.requests", ["tracking", "actuators"])
    scene.set("output.plots", False)
    return scene


def rms_error(result: flexprr.RunResult) -> float:
    """Mean over the sliders of the RMS tracking error rho_ref - rho (m)."""
    table = result.table("tracking")
    return float(np.mean([np.sqrt(np.mean(table[f"slider_error_{i}_m"] ** 2)) for i in (1, 2, 3)]))


def peak_torque(result: flexprr.RunResult) -> float:
    """Largest |motor torque| of any slider (N m)."""
    table = result.table("actuators")
    return max(float(np.max(np.abs(table[f"motor_torque_{i}_N_m"]))) for i in (1, 2, 3))


class Servo:
    """The scene's RMS error and peak torque as functions of (log10 kp, log10 kd), cached."""

    def __init__(self, scene: flexprr.Scene):
        self.scene = scene
        self.runs = 0

    @functools.lru_cache(maxsize=None)
    def evaluate(self, log_kp: float, log_kd: float) -> tuple[float, float]:
        self.runs += 1
        scene = self.scene.copy().set("control.kp", 10.0**log_kp).set("control.kd", 10.0**log_kd)
        result = flexprr.run(scene)
        return rms_error(result), peak_torque(result)

    def at(self, x) -> tuple[float, float]:
        # rounded so that the objective's and the constraint's calls share the cache
        return self.evaluate(round(float(x[0]), 12), round(float(x[1]), 12))


def tune(torque_limit: float, end: float = 0.1, start=(4.5, 2.5), maxiter: int = 60):
    """The gains (kp, kd) with the smallest RMS error whose peak torque is at most
    `torque_limit`, their RMS error and peak torque, and the number of runs.

    Raises ValueError when no admissible point was found.
    """
    servo = Servo(base_scene(end))
    constraints = [{"type": "ineq", "fun": lambda x: 1.0 - servo.at(x)[1] / torque_limit}]
    for k, (lo, hi) in enumerate(BOUNDS):
        constraints.append({"type": "ineq", "fun": lambda x, k=k, lo=lo: x[k] - lo})
        constraints.append({"type": "ineq", "fun": lambda x, k=k, hi=hi: hi - x[k]})
    solution = minimize(
        lambda x: math.log(servo.at(x)[0]),
        np.array(start, dtype=float),
        method="COBYLA",
        constraints=constraints,
        options={"rhobeg": 0.5, "maxiter": maxiter, "tol": 1e-3},
    )
    x = solution.x
    error, torque = servo.at(x)
    inside = all(lo - 1e-9 <= v <= hi + 1e-9 for v, (lo, hi) in zip(x, BOUNDS))
    if torque > torque_limit * (1 + 1e-6) or not inside:
        raise ValueError(f"no admissible gains found: {solution.message} (peak torque {torque:.4g} N m)")
    return (10.0 ** x[0], 10.0 ** x[1]), error, torque, servo.runs


def main() -> int:
    limit = float(sys.argv[1]) if len(sys.argv) > 1 else 0.2
    (kp, kd), error, torque, runs = tune(limit)
    print(f"torque limit {limit} N m: kp = {kp:.4g} N/m, kd = {kd:.4g} N s/m")
    print(f"  RMS tracking error {error * 1e6:.2f} um, peak torque {torque:.4f} N m ({runs} runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
