"""The converged external reference through the 30 Hz collapse (issue 26).

The production runs of `exudyn_collapse.py` carry a small axial damping and the
generalized-alpha numerical damping (spectral radius 0.98): fine for checking a model that has
the same damping, not a convergence reference. This script runs the same Exudyn model
(`exudyn_3prr.simulate`: ANCF cable links, prescribed sliders, free platform) **undamped**:

* no axial damping (`axial_damping_time = 0`),
* generalized-alpha with spectral radius 1 (no numerical damping: the trapezoidal rule in
  Exudyn's index-3 form),
* h = 5e-6 s, 16 and 32 ANCF elements per link,
* the paper scene at 30 Hz over 0-64 ms (up to the collapse; `collapse_deflection = 1` in
  flexprr, i.e. no deflection stop).

and checks that the two meshes agree (relative L2 of the mid-point deflections over growing
windows), that halving the step (32 elements, h = 2.5e-6 s, not committed) changes the
reference by as little, and how far the damped production run (`collapse_f30.csv`) is from it.
Outputs (sampled every 2.5e-4 s, the columns of `coupled_f*.csv`):

    data/collapse_f30_undamped_ne32.csv   the reference (32 elements)
    data/collapse_f30_undamped_ne16.csv   the mesh check (16 elements)
    data/collapse_f30_undamped.json       settings, wall times, agreement per window
                                          (mesh, step, damped production run)

Usage:
    python3 exudyn_converged.py              # both meshes, one after the other (~2-4 min each)
    python3 exudyn_converged.py --elements 32  # one mesh only (the JSON is rewritten only
                                               # when both CSV files exist)
"""

import argparse
import json
import os

import exudyn as exu
import numpy as np

from exudyn_3prr import SAMPLE_PERIOD, simulate, write_csv
from exudyn_collapse import rel_l2
from scene import Scene

HERE = os.path.dirname(os.path.abspath(__file__))
FREQUENCY = 30.0  # Hz
END = 0.064  # s
STEP = 5e-6  # s
MESHES = (16, 32)
WINDOWS = (0.020, 0.033, 0.050, 0.064)  # s


def csv_path(elements):
    """Where the run with `elements` per link is written."""
    return os.path.join(HERE, "data", f"collapse_f30_undamped_ne{elements}.csv")


def run(elements, step=STEP, path=None):
    """One undamped run; writes its CSV (to `path` if given) and returns its summary and table."""
    table, ex = simulate(
        Scene(frequency=FREQUENCY), elements, step, spectral_radius=1.0,
        axial_damping_time=0.0, end_time=END,
    )
    if path is not None:
        write_csv(path, table)
    return table, {
        "elements_per_link": elements,
        "step_s": step,
        "rows": int(table.shape[0]),
        "end_s": float(table[-1, 0]),
        "steps": ex["n_steps"],
        "solver_ok": ex["solver_ok"],
        "wall_s": ex["wall_s"],
        "max_abs_w_mid_m": float(np.abs(table[:, 1:4]).max()),
        "max_abs_dphi_rad": float(np.abs(table[:, 6]).max()),
    }


def agreement(coarse, fine):
    """Relative L2 of the mid-point deflections (all links) and of dphi over each window."""
    out = {}
    for window in WINDOWS:
        k = int(np.searchsorted(fine[:, 0], window + 1e-12))
        out[f"0-{window * 1e3:g}ms"] = {
            "w_mid_rel_l2": rel_l2(coarse[:k, 1:4], fine[:k, 1:4]),
            "dphi_rel_l2": rel_l2(coarse[:k, 6], fine[:k, 6]),
        }
    return out


def main(argv=None):
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--elements", type=int, nargs="*", default=list(MESHES))
    parser.add_argument("--no-step-check", action="store_true", help="skip the h/2 run")
    args = parser.parse_args(argv)
    path = os.path.join(HERE, "data", "collapse_f30_undamped.json")
    old = {}
    if os.path.exists(path):
        with open(path) as fh:
            old = json.load(fh)
    summary = old.get("runs", {})
    for ne in args.elements:
        _table, summary[f"ne{ne}"] = run(ne, path=csv_path(ne))
        print(json.dumps(summary[f"ne{ne}"]))
    if not all(os.path.exists(csv_path(ne)) for ne in MESHES):
        return
    tables = {ne: np.loadtxt(csv_path(ne), delimiter=",", skiprows=1) for ne in MESHES}
    step_check = old.get("ne32_h2.5e-6_vs_ne32")
    if not args.no_step_check:
        half, summary["ne32_h2.5e-6"] = run(32, step=0.5 * STEP)
        print(json.dumps(summary["ne32_h2.5e-6"]))
        step_check = agreement(half, tables[32])
    damped = np.loadtxt(os.path.join(HERE, "data", "collapse_f30.csv"), delimiter=",", skiprows=1)
    out = {
        "model": "exudyn_3prr.simulate: ANCF cable links, prescribed sliders, free platform",
        "exudyn_version": exu.__version__,
        "frequency_Hz": FREQUENCY,
        "end_s": END,
        "step_s": STEP,
        "solver": "generalized-alpha (index 3), spectral radius 1 (no numerical damping)",
        "axial_damping_time_s": 0.0,
        "sample_period_s": SAMPLE_PERIOD,
        "reference": "ne32",
        "runs": summary,
        "ne16_vs_ne32": agreement(tables[16], tables[32]),
        "ne32_h2.5e-6_vs_ne32": step_check,
        "damped_production_vs_ne32": agreement(damped[: len(tables[32])], tables[32]),
    }
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
    for key in ("ne16_vs_ne32", "ne32_h2.5e-6_vs_ne32", "damped_production_vs_ne32"):
        print(key, json.dumps(out[key], indent=1))


if __name__ == "__main__":
    main()
