"""The paper's formulation against the consistent one at 20 Hz: mid-point deflection of
link 1 along the circle, plotted with matplotlib when it is installed.

Run from the repository root:  python examples/python/compare_formulations.py [out.png]
"""

import pathlib
import sys

import numpy as np

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> int:
    base = flexprr.Scene.load(ROOT / "configs" / "paper_f20.toml")
    base.set("output.requests", ["deflections"]).set("output.plots", False)
    base.set("output.compare_without_axial_force", False)
    scenes = [base.copy().set("model.formulation", f) for f in ("paper", "consistent")]
    paper, consistent = flexprr.run_many(scenes)
    series = {}
    for name, r in (("paper", paper), ("consistent", consistent)):
        table = r.table("deflections")
        column = next(c for c in table.columns if c.startswith("w_1"))
        series[name] = (table["t_s"], table[column])
        print(f"{name:>10}: peak |w_1(l/2)| = {np.max(np.abs(table[column])) * 1e3:.5f} mm ({column})")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return 0
    out = sys.argv[1] if len(sys.argv) > 1 else "formulations_f20.png"
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, (t, w) in series.items():
        ax.plot(t, w * 1e3, label=name)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("mid-point deflection of link 1 (mm)")
    ax.set_title("3-PRR on the paper's circle at 20 Hz")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"plot written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
