"""Design optimisation with scipy.optimize: the smallest in-plane link thickness that keeps
the peak mid-point deflection of every link under a bound along the paper's circle at 20 Hz.

The peak deflection falls as the links get thicker (stiffness grows as t^3, mass as t), so
the smallest admissible thickness is the root of  peak(t) - bound  found by Brent's method
(scipy.optimize.brentq) on log t. Each evaluation is one flexprr run (Rust, GIL released).

Run from the repository root:  python examples/python/optimise_thickness.py [bound_mm]
"""

import math
import pathlib
import sys

import numpy as np
from scipy.optimize import brentq

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]


def base_scene() -> flexprr.Scene:
    """The paper's scene at 20 Hz, consistent formulation, deflections only, one period."""
    scene = flexprr.Scene.load(ROOT / "configs" / "paper_f20.toml")
    scene.set("model.formulation", "consistent")
    scene.set("output.requests", ["deflections"])
    scene.set("output.deflection_xi", [0.5])
    scene.set("output.compare_without_axial_force", False)
    scene.set("output.plots", False)
    scene.set("time.end", 0.1)
    return scene


def peak_deflection(result: flexprr.RunResult) -> float:
    """Largest |w(l/2)| of any link over the output times (m)."""
    table = result.table("deflections")
    return max(float(np.max(np.abs(table[c]))) for c in table.columns if c != "t_s")


def peak_at(thickness: float, scene: flexprr.Scene) -> float:
    return peak_deflection(flexprr.run(scene.copy().set("links.section.thickness", thickness)))


def smallest_thickness(bound_m: float, lo: float = 2e-3, hi: float = 8e-3, xtol: float = 1e-4):
    """The smallest thickness (m) with peak mid-point deflection <= bound_m, and its peak.

    Raises ValueError when the bound is not crossed inside [lo, hi].
    """
    scene = base_scene()
    g = lambda log_t: peak_at(math.exp(log_t), scene) - bound_m  # noqa: E731
    g_lo, g_hi = g(math.log(lo)), g(math.log(hi))
    if not (g_lo > 0 > g_hi):
        raise ValueError(
            f"bound {bound_m:.3e} m not crossed in [{lo}, {hi}] m: peaks {g_lo + bound_m:.3e} and {g_hi + bound_m:.3e} m"
        )
    log_t = brentq(g, math.log(lo), math.log(hi), xtol=xtol)
    # brentq returns a point within xtol of the root; step to the admissible side
    t = math.exp(log_t)
    while peak_at(t, scene) > bound_m:
        t *= math.exp(xtol)
    return t, peak_at(t, scene)


def main() -> int:
    bound_mm = float(sys.argv[1]) if len(sys.argv) > 1 else 0.5
    t, peak = smallest_thickness(bound_mm * 1e-3)
    print(f"smallest thickness for a peak mid-point deflection <= {bound_mm} mm: {t * 1e3:.4f} mm (peak {peak * 1e3:.5f} mm)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
