"""SciPy's solve_ivp on the paper's scene (f = 20 Hz, paper formulation, 3 sine modes per
link): work-precision rows in the format of flexprr's work_precision.csv.

The right-hand side is the independent numpy implementation of the KED model in
validation/ked_reference.py (same equations, written separately from the Rust code). Each
method (RK45, DOP853, LSODA, BDF) runs over the tolerance ladder with rtol = tol and
atol = tol * s, s the largest |eta| of the reference, exactly as flexprr does; the error is
measured against the reference written by flexprr (reference.csv), block by block relative to
the displacement and velocity sizes, at the end time and as the maximum over the output times.

Usage:
    python3 scipy_peers.py --reference reference.csv --out scipy.csv
           [--tolerances 1e-3,1e-4,...] [--repeats 3] [--methods RK45,DOP853,LSODA,BDF]
"""

import argparse
import csv
import os
import statistics
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "validation"))

from ked_reference import KedModel  # noqa: E402
from scene import Scene  # noqa: E402

COLUMNS = [
    "package",
    "method",
    "rtol",
    "atol",
    "time_median_s",
    "time_min_s",
    "repeats",
    "accepted_steps",
    "rejected_steps",
    "rhs_evaluations",
    "jacobian_evaluations",
    "end_error",
    "max_error",
]


def read_reference(path):
    """Times, states (rows) and the number of modes of a flexprr reference.csv."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    t, states = data[:, 0], data[:, 1:]
    modes = states.shape[1] // 2
    return t, states, modes


def errors(states, reference, modes):
    """(end, max) errors relative to the displacement and velocity sizes of the reference."""
    size = np.empty(2 * modes)
    size[:modes] = np.max(np.abs(reference[:, :modes]))
    size[modes:] = np.max(np.abs(reference[:, modes:]))
    rel = np.abs(states - reference) / size
    per_time = rel.max(axis=1)
    return float(per_time[-1]), float(per_time.max())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", required=True, help="reference.csv written by flexprr")
    parser.add_argument("--out", required=True, help="CSV file to write")
    parser.add_argument("--tolerances", default="1e-3,1e-4,1e-5,1e-6,1e-7,1e-8,1e-9")
    parser.add_argument("--methods", default="RK45,DOP853,LSODA,BDF")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--max-seconds", type=float, default=20.0,
        help="skip tighter tolerances of a method once one run takes longer than this",
    )
    args = parser.parse_args(argv)

    t_ref, y_ref, modes = read_reference(args.reference)
    if modes != 9:
        sys.exit(f"the reference has {modes} modes; this script models the paper's 3 x 3")
    disp_size = float(np.max(np.abs(y_ref[:, :modes])))
    model = KedModel(Scene(frequency=20.0), modes=3, formulation="paper")
    y0 = np.zeros(2 * modes)
    t_span = (float(t_ref[0]), float(t_ref[-1]))
    tolerances = [float(s) for s in args.tolerances.split(",")]

    rows = []
    for method in args.methods.split(","):
        for tol in tolerances:
            atol = tol * disp_size

            def run():
                model.evaluations = 0
                return solve_ivp(
                    model.rhs, t_span, y0, method=method, rtol=tol, atol=atol, t_eval=t_ref
                )

            # One untimed warm-up, then timed repeats; a slow run counts as its own repeat.
            start = time.perf_counter()
            sol = run()
            first = time.perf_counter() - start
            times = []
            if first < 1.0:
                for _ in range(max(args.repeats, 1)):
                    start = time.perf_counter()
                    sol = run()
                    times.append(time.perf_counter() - start)
            else:
                times.append(first)
            if not sol.success:
                print(f"scipy {method} at rtol {tol:g} failed: {sol.message}", file=sys.stderr)
                continue
            end, worst = errors(sol.y.T, y_ref, modes)
            row = {
                "package": "scipy",
                "method": method,
                "rtol": tol,
                "atol": atol,
                "time_median_s": statistics.median(times),
                "time_min_s": min(times),
                "repeats": len(times),
                "accepted_steps": "",
                "rejected_steps": "",
                "rhs_evaluations": sol.nfev,
                "jacobian_evaluations": sol.njev,
                "end_error": end,
                "max_error": worst,
            }
            rows.append(row)
            print(
                f"scipy {method:<7} {tol:7.0e} {1e3 * row['time_median_s']:12.1f} ms "
                f"{sol.nfev:9d} rhs {end:10.2e} {worst:10.2e}",
                flush=True,
            )
            if max(times) > args.max_seconds:
                break

    with open(args.out, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"{len(rows)} rows written to {args.out}")


if __name__ == "__main__":
    main()
