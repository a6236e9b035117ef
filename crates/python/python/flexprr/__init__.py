"""flexprr: the flexible-link 3-PRR planar parallel manipulator (Zhang, Mills & Cleghorn).

Scenes are the CLI's TOML scene files: load one with :meth:`Scene.load`,
:meth:`Scene.from_toml` or :meth:`Scene.from_dict`, change dotted keys with
:meth:`Scene.set`, and :func:`run` it. The work is done in Rust with the GIL released.
See docs/python.md.
"""

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
    run,
    run_many,
    run_study,
    singularity,
)

__all__ = [
    "KinematicsError",
    "RunError",
    "RunResult",
    "Scene",
    "SceneError",
    "StudyError",
    "Table",
    "__version__",
    "forward_kinematics",
    "inverse_kinematics",
    "link_frequencies",
    "run",
    "run_many",
    "run_study",
    "singularity",
]
