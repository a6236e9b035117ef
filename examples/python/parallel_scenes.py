"""Spread scenes over processes: a sweep of the link thickness on the paper's circle at
20 Hz, run three ways with the same answer.

1. `flexprr.run_many(scenes)`: threads of this process (the GIL is released; the fastest on
   one machine);
2. `concurrent.futures.ProcessPoolExecutor`: worker processes (`flexprr.run_many(scenes,
   executor=pool)`, or `pool.map(flexprr.run, scenes)` directly);
3. a Dask `LocalCluster` (`client.map(flexprr.run, scenes)`): the same code spreads over the
   machines of a real cluster when `Client` is given its scheduler's address.

Scenes, results and errors travel between processes by pickle. Worker processes start clean
(`forkserver` or `spawn`), so the script's work sits under `if __name__ == "__main__":`.

Run from the repository root:  python examples/python/parallel_scenes.py [count]
(Dask is optional: pip install "dask[distributed]").
"""

import multiprocessing
import pathlib
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]


def sweep_scenes(count: int, end_s: float = 0.05):
    """`count` copies of the paper scene at 20 Hz with thicknesses from 2 to 4 mm."""
    base = flexprr.Scene.load(ROOT / "configs" / "paper_f20.toml")
    base.set("output.requests", ["deflections"]).set("output.plots", False)
    base.set("output.compare_without_axial_force", False).set("time.end", end_s)
    thickness = np.linspace(2e-3, 4e-3, count)
    return thickness, [base.copy().set("links.section.thickness", float(t)) for t in thickness]


def peak_deflection(result: flexprr.RunResult) -> float:
    """Largest |w(l/2)| of any link over the output times (m)."""
    table = result.table("deflections")
    return max(float(np.max(np.abs(table[c]))) for c in table.columns if c != "t_s")


def clean_context():
    """A start method that does not fork a process holding Rust worker threads."""
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def with_threads(scenes):
    return [peak_deflection(r) for r in flexprr.run_many(scenes)]


def with_processes(scenes, workers: int = 2):
    with ProcessPoolExecutor(max_workers=workers, mp_context=clean_context()) as pool:
        return [peak_deflection(r) for r in flexprr.run_many(scenes, executor=pool)]


def with_dask(scenes, workers: int = 2):
    """On a local Dask cluster of `workers` processes; None when Dask is not installed."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        return None
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            futures = client.map(flexprr.run, scenes, pure=False)
            return [peak_deflection(r) for r in client.gather(futures)]


def main() -> int:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 8
    thickness, scenes = sweep_scenes(count)
    threads = with_threads(scenes)
    processes = with_processes(scenes)
    dask = with_dask(scenes)
    print(" thickness (mm)   peak |w(l/2)| (mm): threads   processes   dask")
    for i, t in enumerate(thickness):
        d = "-" if dask is None else f"{dask[i] * 1e3:.6f}"
        print(f"{t * 1e3:15.3f}   {threads[i] * 1e3:26.6f}   {processes[i] * 1e3:9.6f}   {d}")
    same = threads == processes and (dask is None or dask == threads)
    print("the three agree bit for bit" if same else "the results differ")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
