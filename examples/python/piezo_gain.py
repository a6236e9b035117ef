"""Choosing the strain-rate gain of the piezoelectric patches: the largest damping of the
links' first mode within a voltage limit, on one model.

The scene is configs/piezo_coupled.toml: the paper's 20 Hz circle in the coupled model (the
platform follows the links) with one collocated PZT pair per link at mid-span (xi 0.45-0.55)
under strain-rate feedback V = -G dV_s/dt (docs/piezo.md). The same model is linearised and
run:

1. Damping (flexprr.linearize): the machine held at the circle's centre; the damping ratio
   of its first mode against the gain G. At rest the first mode is the links' first bending
   mode (116 Hz), and at small G its damping grows as the closed form (P3) of docs/piezo.md,
   zeta = G k_a k_s d^2 / (2 m omega). Beyond G of about 0.1 s the mode is overdamped (its
   pair of poles becomes real; damping ratio 1).
2. Voltage (flexprr.run): the largest voltage command over the 20 Hz circle at each gain
   (the summary's vibration_control.patches[].max_abs_command_V: above the limit the
   amplifier saturates).
3. The choice: the gain with the largest first-mode damping whose run stays under the
   limit (no command beyond it), and that run's reduction of the peak mid-point
   deflection against the same scene without control (the run makes that run itself).

Run from the repository root:  python examples/python/piezo_gain.py [voltage_limit_V]
"""

import pathlib
import sys

import numpy as np

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "configs" / "piezo_coupled.toml"
#: The circle's centre, where the damping is computed (x m, y m, phi deg).
POSE = (-0.05, 0.0, 45.0)
#: The gains tried (s).
GAINS = np.concatenate([[0.0], np.geomspace(2e-4, 0.3, 23)])


def scene(gain: float) -> flexprr.Scene:
    """The shipped scene with strain-rate gain `gain` (s)."""
    s = flexprr.Scene.load(SCENE)
    s.set("vibration_control.gain", float(gain))
    return s


def first_mode_damping(gain: float) -> float:
    """The damping ratio of the machine's first mode at rest: the scene's model (links,
    platform and patches together) linearised at POSE, its lowest mode."""
    modes = flexprr.linearize(scene(gain), pose=POSE).modes()
    return float(modes.damping_ratio[int(np.argmin(modes.frequency_hz))])


def max_command(gain: float) -> dict:
    """The run over the circle: the largest voltage command of any patch and the reduction
    of link 1's peak mid-point deflection (%)."""
    s = scene(gain)
    s.set("output.requests", ["deflections", "piezo"])
    s.set("output.plots", False)
    summary = flexprr.run(s).summary["vibration_control"]
    return {
        "max_command_V": max(p["max_abs_command_V"] for p in summary["patches"]),
        "peak_reduction_percent": summary["links"][0]["peak_reduction_percent"],
    }


def choose(limit: float, gains=GAINS) -> dict:
    """The gain with the largest first-mode damping among those whose run stays within
    `limit` volts, with the whole sweep."""
    zeta = np.array([first_mode_damping(g) for g in gains])
    runs = [max_command(g) for g in gains]
    volts = np.array([r["max_command_V"] for r in runs])
    admissible = volts <= limit
    if not admissible.any():
        raise ValueError(f"no gain keeps the patches within {limit} V")
    best = int(np.argmax(np.where(admissible, zeta, -np.inf)))
    return {
        "gains": np.asarray(gains),
        "zeta": zeta,
        "max_command_V": volts,
        "peak_reduction_percent": np.array([r["peak_reduction_percent"] for r in runs]),
        "best": best,
        "gain": float(gains[best]),
    }


def main(limit: float = 200.0) -> dict:
    out = choose(limit)
    print(f"{'G (s)':>10} {'zeta_1':>9} {'max |V_cmd| (V)':>16} {'peak reduction link 1':>22}")
    for k, g in enumerate(out["gains"]):
        mark = "  <- chosen" if k == out["best"] else ""
        print(
            f"{g:10.2e} {out['zeta'][k] + 0.0 if abs(out['zeta'][k]) >= 5e-6 else 0.0:9.5f} {out['max_command_V'][k]:16.1f} "
            f"{out['peak_reduction_percent'][k]:21.1f} %{mark}"
        )
    k = out["best"]
    print(
        f"within {limit:g} V: G = {out['gain']:.3g} s, first-mode damping ratio "
        f"{out['zeta'][k]:.4f}, max command {out['max_command_V'][k]:.1f} V"
    )
    return out


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 200.0)
