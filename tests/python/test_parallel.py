"""Scenes spread over processes (run_many(processes=), a ProcessPoolExecutor, a Dask
LocalCluster) give the same results as runs in this process, bit for bit."""

import importlib.util
import multiprocessing
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import flexprr


@pytest.fixture(scope="module")
def scenes(root):
    base = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    base.set("output.requests", ["deflections"]).set("output.plots", False).set("time.end", 0.02)
    good = [base.copy().set("links.section.thickness", t) for t in (2e-3, 3e-3, 4e-3)]
    return good + [base.copy().set("time.end", -1.0)]


@pytest.fixture(scope="module")
def in_process(scenes):
    return flexprr.run_many(scenes, return_exceptions=True)


def assert_same(results, reference):
    assert len(results) == len(reference)
    for r, ref in zip(results, reference):
        if isinstance(ref, Exception):
            assert type(r) is type(ref) and str(r) == str(ref) and r.key == ref.key
        else:
            np.testing.assert_array_equal(r.table("deflections").to_numpy(), ref.table("deflections").to_numpy())
            assert r.summary["status"] == "ok"


def test_run_many_with_processes(scenes, in_process):
    calls = []
    out = flexprr.run_many(scenes, processes=2, return_exceptions=True, progress=calls.append)
    assert_same(out, in_process)
    assert calls == pytest.approx([0.25, 0.5, 0.75, 1.0])
    with pytest.raises(flexprr.SceneError) as info:
        flexprr.run_many(scenes, processes=2)
    assert info.value.key == "time.end"


def test_run_many_on_a_process_pool_executor(scenes, in_process):
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
        assert_same(flexprr.run_many(scenes, executor=pool, return_exceptions=True), in_process)
        # the plain executor API works as well: scenes and results pickle
        direct = list(pool.map(flexprr.run, scenes[:3]))
    assert_same(direct, in_process[:3])


def test_run_many_refuses_contradictory_options(scenes):
    for bad in (0, 10_000, True, 2.0):
        with pytest.raises(ValueError, match="processes"):
            flexprr.run_many(scenes, processes=bad)
    assert flexprr.run_many([], processes=2) == []
    with pytest.raises(ValueError, match="not both"):
        flexprr.run_many(scenes, processes=2, executor=object())
    with pytest.raises(ValueError, match="threads"):
        flexprr.run_many(scenes, threads=10_000)


def test_dask_local_cluster(scenes, in_process):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        futures = client.map(flexprr.run, scenes[:3], pure=False)
        assert_same(client.gather(futures), in_process[:3])
        assert_same(flexprr.run_many(scenes, executor=client.get_executor(), return_exceptions=True), in_process)
    assert cluster.status.name == "closed"


def test_parallel_example_agrees_three_ways(root):
    spec = importlib.util.spec_from_file_location("parallel_scenes", root / "examples" / "python" / "parallel_scenes.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    thickness, scenes = example.sweep_scenes(3, end_s=0.02)
    threads = example.with_threads(scenes)
    assert example.with_processes(scenes) == threads
    dask = example.with_dask(scenes)
    assert dask is None or dask == threads
    # thicker links deflect less (stiffness grows as t^3, mass as t)
    assert threads == sorted(threads, reverse=True)
