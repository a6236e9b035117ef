"""flexprr: the flexible-link 3-PRR planar parallel manipulator (Zhang, Mills & Cleghorn).

Scenes are the CLI's TOML scene files: load one with :meth:`Scene.load`,
:meth:`Scene.from_toml` or :meth:`Scene.from_dict`, change dotted keys with
:meth:`Scene.set`, and :func:`run` it (or pass :func:`run` the file's path). The work is
done in Rust with the GIL released. Scenes, results and exceptions pickle, so
:func:`run_many` spreads scenes over threads, processes or any
``concurrent.futures.Executor`` (a Dask ``Client.get_executor()`` included). A scene's linear model (:func:`linearize`, a :class:`LinearModel`) gives the state-space
arrays that ``scipy.signal`` and python-control take as they are. See docs/python.md and
docs/linear.md.
"""

import os as _os
from concurrent.futures import Executor as _Executor

import numpy as _np

from ._flexprr import (
    KinematicsError,
    RunError,
    RunResult,
    Scene,
    SceneError,
    StudyError,
    Table,
    __version__,
    forward_kinematics,
    inverse_kinematics,
    link_frequencies,
    margins,
    plan,
    Plan,
    run,
    run_study,
    singularity,
)
from ._linear import LinearModel, LinearModels, LoopMargins, Modes, SliderLoop, linearize, slider_loop
from ._flexprr import run_many_threads as _run_many_threads

__all__ = [
    "KinematicsError",
    "LinearModel",
    "LinearModels",
    "LoopMargins",
    "Modes",
    "Plan",
    "RunError",
    "RunResult",
    "Scene",
    "SceneError",
    "SliderLoop",
    "StudyError",
    "Table",
    "__version__",
    "forward_kinematics",
    "inverse_kinematics",
    "link_frequencies",
    "linearize",
    "margins",
    "plan",
    "run",
    "run_many",
    "run_study",
    "singularity",
    "slider_loop",
]


# Most worker processes run_many starts (as for threads: far more than any machine's cores).
_MAX_WORKERS = 256


def _process_pool(processes):
    """A process pool whose workers start clean (forkserver, or spawn where there is none).

    A plain fork would copy this process's Rayon thread pool without its threads, and a
    forked worker that runs in parallel would wait for them forever.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    return ProcessPoolExecutor(max_workers=processes, mp_context=context)


def _load_each(scenes, return_exceptions):
    """Each entry as a :class:`Scene` read here (workers need no files); with
    ``return_exceptions`` an entry that cannot be read (a missing or unparsable file, an
    entry that is not a scene or a path) keeps its exception in its place, otherwise it is
    raised at once."""
    loaded = []
    for s in scenes:
        if isinstance(s, Scene):
            loaded.append(s)
            continue
        try:
            loaded.append(Scene.load(s))
        except Exception as e:  # noqa: BLE001 - returned in its slot, as asked
            if not return_exceptions:
                raise
            loaded.append(e)
    return loaded


def _run_on_executor(scenes, executor, return_exceptions, progress):
    """Submits one :func:`run` per scene to ``executor``; results in order (an entry that is
    already an exception stays in its place)."""
    from concurrent.futures import as_completed

    results = list(scenes)
    futures = {executor.submit(run, scene): i for i, scene in enumerate(scenes) if isinstance(scene, Scene)}
    done = 0
    callback_error = None
    for future in as_completed(futures):
        i = futures[future]
        try:
            results[i] = future.result()
        except (SceneError, RunError) as e:
            results[i] = e
        done += 1
        if progress is not None and callback_error is None:
            try:
                progress(done / len(futures))
            except BaseException as e:  # noqa: BLE001 - raised once the runs ended
                callback_error = e
    if callback_error is not None:
        raise callback_error
    if not return_exceptions:
        for r in results:
            if isinstance(r, BaseException):
                raise r
    return results


def run_many(scenes, threads=None, return_exceptions=False, progress=None, processes=None, executor=None):
    """Runs several scenes and returns one entry per scene, in order.

    Each scene is a :class:`Scene` or the path of a scene file. Each entry is a
    :class:`RunResult`, or with ``return_exceptions=True`` the exception of that scene, in
    its place, while every other scene runs: the :class:`SceneError` of a file that cannot
    be read or parsed or of an invalid scene, the ``TypeError`` of an entry that is neither
    a scene nor a path, the :class:`RunError` (with ``.partial``) of a failed run. Without
    it, an entry that cannot be read is raised at once, and otherwise the first error (in
    scene order) is raised after all runs ended.

    Where the runs happen:

    - by default on ``threads`` threads of this process (Rayon, the GIL released; ``None``
      for all cores): the fastest on one machine;
    - with ``processes=n``, on a pool of ``n`` worker processes started clean (forkserver
      or spawn), closed before returning;
    - with ``executor=``, on any ``concurrent.futures.Executor``: a
      ``ProcessPoolExecutor`` of your own, or a Dask cluster's ``client.get_executor()``.
      Scenes, results and errors travel by pickle.

    ``progress(fraction)``, when given, is called in the calling thread after each finished
    scene with the fraction of scenes done. An exception it raises is raised once the runs
    ended.
    """
    if isinstance(scenes, (str, bytes, _os.PathLike, Scene)):
        raise TypeError("run_many expects a sequence of scenes or paths; use run() for one scene")
    scenes = list(scenes)
    if processes is not None and executor is not None:
        raise ValueError("give processes or executor, not both")
    if executor is not None:
        if not isinstance(executor, _Executor) and not hasattr(executor, "submit"):
            raise TypeError("executor must be a concurrent.futures.Executor (something with submit)")
        if threads is not None:
            raise ValueError("threads applies to runs in this process; with an executor, size the executor")
        # Paths are read here: workers need no files.
        loaded = _load_each(scenes, return_exceptions)
        return _run_on_executor(loaded, executor, return_exceptions, progress)
    if processes is not None:
        if isinstance(processes, bool) or not isinstance(processes, int) or not 1 <= processes <= _MAX_WORKERS:
            raise ValueError(f"processes = {processes!r}: expected 1 to {_MAX_WORKERS}")
        if threads is not None:
            raise ValueError("threads applies to runs in this process; with processes, each worker runs one scene")
        loaded = _load_each(scenes, return_exceptions)
        workers = sum(isinstance(s, Scene) for s in loaded)
        if not workers:
            return loaded
        with _process_pool(min(processes, workers)) as pool:
            return _run_on_executor(loaded, pool, return_exceptions, progress)
    return _run_many_threads(scenes, threads=threads, return_exceptions=return_exceptions, progress=progress)


