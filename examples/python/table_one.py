"""Reproduce Table I of Zhang, Mills & Cleghorn: the first natural frequency of link 1 over
the circle at 10, 20 and 30 Hz, with and without the axial force.

Run from the repository root:  python examples/python/table_one.py
"""

import pathlib
import sys

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]


def table_one(frequency_hz: int) -> str:
    scene = flexprr.Scene.load(ROOT / "configs" / f"paper_f{frequency_hz}.toml")
    scene.set("output.requests", ["frequencies"]).set("output.plots", False)
    text = flexprr.run(scene).table_one
    if text is None:
        raise RuntimeError(f"paper_f{frequency_hz}: the run produced no Table I")
    return text


def main() -> int:
    for f in (10, 20, 30):
        print(f"f = {f} Hz\n{table_one(f)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
