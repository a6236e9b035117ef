"""Collapse of the paper's 3-PRR near the buckling speed: the Exudyn reference (issue 18).

Runs the fully coupled ANCF model of `exudyn_3prr.py` (same links, sliders, platform, axial
damping) beyond the 0.2 s of the production runs and records, per frequency:

* the time the largest mid-point deflection first passes 10 % of the link length (20 mm),
* the time the platform rotation deviation first passes 0.3 rad,
* the smallest type-II measure of the chords over the run (the normalised determinant of the
  platform equilibrium matrix with columns (e_i, (r_i - centroid) x e_i / R_p), each column
  normalised: flexprr's `equilibrium_measure`),
* max |w_mid| and max |dphi|.

Usage:
    python3 exudyn_collapse.py --series           # f = 30 Hz to 0.1 s -> data/collapse_f30.csv
                                                  # + mesh/step check -> data/collapse_f30_convergence.json
    python3 exudyn_collapse.py --speeds 25 25.25 25.5 26 27 --end 0.5   # merged into data/collapse_speeds.json

Collapse is not a solver failure here: the ANCF links bend through the type-II pose. If the
Newton iteration fails anyway, the data up to that time is kept and `solver_ok` is false.
"""

import argparse
import json
import os

import numpy as np

from exudyn_3prr import AXIAL_DAMPING_TIME, COLUMNS, simulate, write_csv
from scene import Scene, rotation

HERE = os.path.dirname(os.path.abspath(__file__))
DEFLECTION_LIMIT = 0.02  # m: 10 % of the link length
ROTATION_LIMIT = 0.3  # rad


def type_ii_measure(scene, pose, chords):
    """|det| of the normalised platform equilibrium matrix for each sample.

    pose: (n, 3) platform poses; chords: (n, 3, 2) unit chord directions e_i (B_i -> C_i).
    """
    out = np.zeros(len(pose))
    radius = scene.platform_radius
    for k in range(len(pose)):
        rot = rotation(pose[k, 2])
        cols = []
        for i in range(3):
            r = rot @ scene.platform_point(i)  # the centroid is the platform's reference point
            e = chords[k, i]
            col = np.array([e[0], e[1], (r[0] * e[1] - r[1] * e[0]) / radius])
            cols.append(col / np.linalg.norm(col))
        out[k] = abs(np.linalg.det(np.array(cols).T))
    return out


def first_crossing(t, values, limit):
    """First sample time at which values passes limit (None if never)."""
    idx = np.nonzero(values > limit)[0]
    return float(t[idx[0]]) if len(idx) else None


def run(frequency, elements, step, end):
    """One run; returns (table, summary dict)."""
    scene = Scene(frequency=frequency)
    table, ex = simulate(
        scene, elements, step, axial_damping_time=AXIAL_DAMPING_TIME, end_time=end,
        allow_failure=True,
    )
    t = table[:, 0]
    w = np.abs(table[:, 1:4]).max(axis=1)
    dphi = np.abs(table[:, 6])
    # chord directions from the platform pose and the solved slider points: e = (C - B) / |C - B|
    pose = ex["platform_pose"]
    chords = np.zeros((len(t), 3, 2))
    for i in range(3):
        u = scene.guide_direction(i)
        b = scene.guide_centre(i)[None, :] + table[:, 13 + i][:, None] * u[None, :]
        c = np.array([pose[k, :2] + rotation(pose[k, 2]) @ scene.platform_point(i) for k in range(len(t))])
        d = c - b
        chords[:, i, :] = d / np.linalg.norm(d, axis=1)[:, None]
    measure = type_ii_measure(scene, pose, chords)
    summary = {
        "frequency_Hz": frequency,
        "elements_per_link": elements,
        "step_s": step,
        "end_s": float(t[-1]),
        "solver_ok": ex["solver_ok"],
        "wall_s": ex["wall_s"],
        "t_deflection_10pct_s": first_crossing(t, w, DEFLECTION_LIMIT),
        "t_rotation_0.3rad_s": first_crossing(t, dphi, ROTATION_LIMIT),
        "max_abs_w_mid_m": float(w.max()),
        "max_abs_dphi_rad": float(dphi.max()),
        "min_type_ii_measure": float(measure.min()),
        "t_min_type_ii_measure_s": float(t[np.argmin(measure)]),
    }
    return table, measure, summary


def rel_l2(a, b):
    """||a - b|| / ||b||."""
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def main(argv=None):
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--series", action="store_true", help="30 Hz time series + convergence")
    parser.add_argument("--speeds", type=float, nargs="*", default=[])
    parser.add_argument("--end", type=float, default=0.5)
    parser.add_argument("--elements", type=int, default=16)
    parser.add_argument("--step", type=float, default=6.25e-6)
    args = parser.parse_args(argv)
    data = os.path.join(HERE, "data")
    if args.series:
        end = 0.1
        runs = {}
        for ne, h in ((16, 6.25e-6), (32, 6.25e-6), (16, 3.125e-6), (16, 1.25e-5)):
            table, measure, summary = run(30.0, ne, h, end)
            runs[(ne, h)] = (table, summary)
            print(json.dumps(summary))
        table, summary = runs[(16, 6.25e-6)]
        write_csv(os.path.join(data, "collapse_f30.csv"), table)
        ref = runs[(16, 3.125e-6)][0]
        conv = {"reference": "16 elements, h = 3.125e-6 s", "runs": {}}
        for (ne, h), (tab, summ) in runs.items():
            n = min(len(tab), len(ref))
            entry = {"summary": summ}
            for window in (0.032, 0.05, 0.064, 0.1):
                k = int(np.searchsorted(ref[:n, 0], window + 1e-12))
                entry[f"w_mid_rel_l2_to_{window:g}s"] = rel_l2(tab[:k, 1:4], ref[:k, 1:4])
                entry[f"dphi_rel_l2_to_{window:g}s"] = rel_l2(tab[:k, 6], ref[:k, 6])
            conv["runs"][f"ne{ne}_h{h:.4g}"] = entry
        with open(os.path.join(data, "collapse_f30_convergence.json"), "w") as fh:
            json.dump(conv, fh, indent=1)
    if args.speeds:
        # New runs are merged into the file: a run at the same frequency, mesh, step and
        # window replaces the old one, the others are kept, sorted by frequency.
        path = os.path.join(data, "collapse_speeds.json")
        runs = []
        if os.path.exists(path):
            with open(path) as fh:
                runs = json.load(fh).get("runs", [])
        out = {
            "criteria": {
                "deflection": f"max_i |w_mid_i| > {DEFLECTION_LIMIT} m",
                "rotation": f"|dphi| > {ROTATION_LIMIT} rad",
            },
            "columns_of_series": COLUMNS,
            "runs": runs,
        }

        def same(a, b):
            keys = ("frequency_Hz", "elements_per_link", "step_s", "end_s")
            return all(a.get(k) == b.get(k) for k in keys)

        for f in args.speeds:
            _table, _measure, summary = run(f, args.elements, args.step, args.end)
            print(json.dumps(summary))
            out["runs"] = [r for r in out["runs"] if not same(r, summary)] + [summary]
            out["runs"].sort(key=lambda r: (r["frequency_Hz"], r["elements_per_link"], r["step_s"]))
            with open(path, "w") as fh:
                json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
