"""Type stubs of flexprr (the native module flexprr._flexprr, re-exported)."""

from concurrent.futures import Executor
from os import PathLike
from typing import Any, Callable, Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, "PathLike[str]"]
_Poses = npt.ArrayLike
_Progress = Callable[[float], Any]

class SceneError(ValueError):
    """An invalid scene, link or key; the text is the CLI's message."""

    key: str
    message: str
    file: Optional[str]
    line: Optional[int]
    column: Optional[int]

class RunError(RuntimeError):
    """A run that stopped early; `partial` holds the outputs up to the failure."""

    kind: str
    time: Optional[float]
    link: Optional[int]
    partial: "RunResult"

class KinematicsError(ValueError):
    """A pose that fails the kinematic checks; `index` is its row in the input."""

    index: int

class StudyError(RuntimeError):
    """A study that could not be read or run."""

class Scene:
    """A scene file's TOML table, editable by dotted keys checked at once against the schema.

    Pickles (multiprocessing, concurrent.futures, Dask)."""

    @staticmethod
    def load(path: _Path) -> "Scene": ...
    @staticmethod
    def from_toml(text: str, name: str = "scene") -> "Scene": ...
    @staticmethod
    def from_dict(data: Dict[str, Any], name: str = "scene") -> "Scene": ...
    def set(self, key: str, value: Any) -> "Scene": ...
    def get(self, key: str) -> Any: ...
    def __getitem__(self, key: str) -> Any: ...
    def __setitem__(self, key: str, value: Any) -> None: ...
    def validate(self) -> None: ...
    def copy(self) -> "Scene": ...
    def to_dict(self) -> Dict[str, Any]: ...
    def to_toml(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def changed_keys(self) -> List[str]: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

class Table:
    """One time-series table of a run, columns under the CLI's CSV headers."""

    @property
    def name(self) -> str: ...
    @property
    def columns(self) -> List[str]: ...
    def __len__(self) -> int: ...
    def __contains__(self, column: str) -> bool: ...
    def __getitem__(self, column: str) -> npt.NDArray[np.float64]: ...
    def to_numpy(self) -> npt.NDArray[np.float64]: ...
    def to_dict(self) -> Dict[str, npt.NDArray[np.float64]]: ...
    def to_pandas(self) -> Any: ...

class RunResult:
    """What a run produced (plain data: pickles whole)."""

    @property
    def scene(self) -> str: ...
    @property
    def tables(self) -> List[str]: ...
    def table(self, name: str) -> Table: ...
    def __getitem__(self, name: str) -> Table: ...
    @property
    def summary(self) -> Dict[str, Any]: ...
    @property
    def stats(self) -> Dict[str, Any]: ...
    @property
    def table_one(self) -> Optional[str]: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

def run(
    scene: Union[Scene, _Path],
    progress: Optional[_Progress] = None,
    controller: Optional[Callable[[float, npt.NDArray[np.float64]], npt.ArrayLike]] = None,
) -> RunResult: ...
def margins(
    scene: Union[Scene, _Path], pose: Optional[Tuple[float, float, float]] = None
) -> Dict[str, List[Dict[str, Any]]]: ...

class Plan:
    """The plan of a scene's [plan] section (what `flexprr plan` writes)."""

    @property
    def duration(self) -> float: ...
    @property
    def frequency_hz(self) -> Optional[float]: ...
    @property
    def report(self) -> Dict[str, Any]: ...
    @property
    def timing(self) -> Dict[str, Any]: ...
    def to_scene(self) -> Scene: ...
    def to_toml(self) -> str: ...

def plan(scene: Union[Scene, _Path], flexible_check: bool = True) -> Plan: ...
def run_many(
    scenes: Iterable[Union[Scene, _Path]],
    threads: Optional[int] = None,
    return_exceptions: bool = False,
    progress: Optional[_Progress] = None,
    processes: Optional[int] = None,
    executor: Optional[Executor] = None,
) -> List[Union[RunResult, SceneError, RunError, TypeError]]: ...
def inverse_kinematics(
    poses: _Poses, scene: Optional[Scene] = None
) -> Dict[str, npt.NDArray[np.float64]]: ...
def forward_kinematics(
    rho: _Poses, guess: Optional[_Poses] = None, scene: Optional[Scene] = None
) -> npt.NDArray[np.float64]: ...
def singularity(poses: _Poses, scene: Optional[Scene] = None) -> Dict[str, Any]: ...
def link_frequencies(
    link: Union[_Path, Dict[str, Any]], load: Optional[Tuple[float, float, float]] = None
) -> Dict[str, Any]: ...
def run_study(
    path: _Path,
    out: _Path,
    threads: Optional[int] = None,
    resume: bool = False,
    case_outputs: bool = False,
    progress: Optional[_Progress] = None,
) -> Dict[str, Any]: ...

class Modes(NamedTuple):
    """Modes of a LinearModel: frequencies (Hz), damping ratios, eigenvalues (1/s; of a
    discrete-time model ln(z) / dt)."""

    frequency_hz: npt.NDArray[np.float64]
    damping_ratio: npt.NDArray[np.float64]
    eigenvalue: npt.NDArray[np.complex128]

class LinearModel:
    """x' = A x + B u, y = C x + D u about an operating point (dt = 0), or the exact
    discrete-time model of a sampled loop (dt > 0); pickles."""

    A: npt.NDArray[np.float64]
    B: npt.NDArray[np.float64]
    C: npt.NDArray[np.float64]
    D: npt.NDArray[np.float64]
    dt: float
    x0: npt.NDArray[np.float64]
    y0: npt.NDArray[np.float64]
    state_scale: npt.NDArray[np.float64]
    realization: str
    inputs: List[str]
    outputs: List[str]
    states: List[str]
    input_signals: List[str]
    output_signals: List[str]
    state_signals: List[str]
    input_units: List[str]
    output_units: List[str]
    notes: List[str]
    operating_point: Dict[str, Any]
    t: float
    model: str
    scene: str
    elastic_chords: bool
    def modes(self) -> Modes: ...
    def is_discrete(self) -> bool: ...
    def frequency_response(self, omega: npt.ArrayLike) -> npt.NDArray[np.complex128]:
        """C (sI - A)^-1 B + D at s = i omega (z = exp(i omega dt)), omega in rad/s; shape
        (outputs, inputs, len(omega))."""
    def to_control(self, name: Optional[str] = None) -> Any:
        """A named control.StateSpace with dt."""
    def to_scipy(self) -> Any:
        """scipy.signal.StateSpace (with dt in discrete time)."""
    def physical(self) -> "LinearModel": ...

class LinearModels:
    """Linear models along a motion at several times, from one integration."""

    models: List[LinearModel]
    t: npt.NDArray[np.float64]
    A: npt.NDArray[np.float64]
    B: npt.NDArray[np.float64]
    C: npt.NDArray[np.float64]
    D: npt.NDArray[np.float64]
    def __len__(self) -> int: ...
    def __getitem__(self, k: int) -> LinearModel: ...
    def __iter__(self) -> Any: ...

@overload
def linearize(
    scene: Union[Scene, _Path],
    pose: Optional[Tuple[float, float, float]] = None,
    t: Optional[float] = None,
    inputs: Sequence[str] = (),
    outputs: Sequence[str] = (),
    rigid_chords: bool = False,
    coulomb: str = "left-out",
    realization: str = "scaled",
) -> LinearModel: ...
@overload
def linearize(
    scene: Union[Scene, _Path],
    pose: None = None,
    t: Sequence[float] = ...,
    inputs: Sequence[str] = (),
    outputs: Sequence[str] = (),
    rigid_chords: bool = False,
    coulomb: str = "left-out",
    realization: str = "scaled",
) -> LinearModels: ...

class LoopMargins(NamedTuple):
    """Gain and phase margins (python-control) and the sensitivity peak of one slider loop."""

    gain_margin: float
    phase_margin_deg: float
    gain_crossover_hz: float
    phase_crossover_hz: float
    sensitivity_peak: float
    sensitivity_peak_hz: float

class SliderLoop:
    """One slider's loop broken at its actuator."""

    slider: int
    model: LinearModel
    def loop_gain(self) -> Any:
        """L = -slider_command / actuator_command as a control.StateSpace."""
    def margins(self, omega: Optional[npt.ArrayLike] = None) -> LoopMargins: ...

def slider_loop(
    scene: Union[Scene, _Path],
    slider: int,
    pose: Optional[Tuple[float, float, float]] = None,
    t: Optional[float] = None,
    rigid_chords: bool = False,
    coulomb: str = "left-out",
) -> SliderLoop: ...
