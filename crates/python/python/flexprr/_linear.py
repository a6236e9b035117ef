"""Linear models of the whole machine in Python (docs/linear.md, docs/python.md).

:func:`linearize` returns a :class:`LinearModel` (or, along a motion at several times, a
:class:`LinearModels`): the state-space arrays of ``flexprr statespace``, with names that
python-control and MATLAB accept as signal names, the period ``dt`` of a sampled control
law (0 in continuous time), and conversions to python-control (:meth:`LinearModel.to_control`)
and SciPy (:meth:`LinearModel.to_scipy`). :func:`slider_loop` breaks one slider's loop at
its actuator and gives its loop gain, margins and sensitivity peak.
"""

from typing import NamedTuple as _NamedTuple

import numpy as _np

from ._flexprr import _frequency_response, _linearize


class Modes(_NamedTuple):
    """The modes of a :class:`LinearModel`, sorted by frequency, rigid-body (zero) modes left
    out.

    Attributes
    ----------
    frequency_hz : numpy.ndarray
        ``|lambda| / 2 pi``, the undamped natural frequency (Hz).
    damping_ratio : numpy.ndarray
        ``-Re(lambda) / |lambda|``, as MATLAB's and python-control's ``damp``.
    eigenvalue : numpy.ndarray
        ``lambda`` (1/s, upper half-plane); of a discrete-time model the equivalent
        continuous eigenvalue ``ln(z) / dt`` of its pole ``z``.
    """

    frequency_hz: "_np.ndarray"
    damping_ratio: "_np.ndarray"
    eigenvalue: "_np.ndarray"


class LinearModel:
    """A scene's linear model about an operating point (:func:`linearize`).

    In continuous time (``dt == 0``) ``x' = A x + B u``, ``y = C x + D u``; for a scene whose
    control law is sampled (``dt > 0``, the law's period) the exact discrete-time model
    ``x[k+1] = A x[k] + B u[k]``, ``y[k] = C x[k] + D u[k]`` of the sampled loop (zero-order
    hold). ``x`` is the model's state less ``x0``, divided by ``state_scale`` in the scaled
    realisation (the default; ``realization="physical"`` keeps the physical state); ``u``
    the inputs, ``y`` the outputs less ``y0``. Plain data: pickles.

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        The state-space matrices (float64).
    dt : float
        0 in continuous time, else the sample period (s).
    x0, y0 : numpy.ndarray
        The state and the outputs at the operating point.
    state_scale : numpy.ndarray
        Physical state deviation ``= state_scale * x`` (powers of two; all 1 when physical).
    inputs, outputs, states : list of str
        The channels' names (``slider_force:1``, ``deflection:1@0.5``) and the states'.
    input_signals, output_signals, state_signals : list of str
        The same as identifiers (``slider_force_1``, ``deflection_1_at_0p5``, ``rho_1_rate``):
        the signal names of :meth:`to_control`.
    input_units, output_units : list of str
        SI units of the channels.
    notes : list of str
        What the linearisation left out or found (Coulomb friction held, a saturated
        actuator, discrete time).
    realization : str
        ``"scaled"`` or ``"physical"``.
    operating_point : dict
        ``{"kind": "rest", "pose": (x_m, y_m, phi_deg)}`` or ``{"kind": "time", "t": t}``.
    t : float
        Time of the operating point (s).
    model, scene : str
        The model kind and the scene's name.
    elastic_chords : bool
        Whether the coupled model's chords are the links' axial springs (at rest).
    """

    def __init__(self, data):
        self.A = data["A"]
        self.B = data["B"]
        self.C = data["C"]
        self.D = data["D"]
        self.x0 = data["x0"]
        self.y0 = data["y0"]
        self.dt = float(data.get("dt", 0.0))
        self.state_scale = _np.asarray(data.get("state_scale", _np.ones(self.A.shape[0])))
        self.realization = data.get("realization", "physical")
        self.inputs = list(data["inputs"])
        self.outputs = list(data["outputs"])
        self.states = list(data["states"])
        self.input_signals = list(data.get("input_signals", self.inputs))
        self.output_signals = list(data.get("output_signals", self.outputs))
        self.state_signals = list(data.get("state_signals", [f"x_{k + 1}" for k in range(len(self.states))]))
        self.input_units = list(data["input_units"])
        self.output_units = list(data["output_units"])
        self.notes = list(data.get("notes", []))
        self.operating_point = dict(data["operating_point"])
        self.t = data["t"]
        self.model = data["model"]
        self.scene = data["scene"]
        self.elastic_chords = bool(data["elastic_chords"])
        self._modes = Modes(
            _np.asarray(data["frequency_hz"]),
            _np.asarray(data["damping_ratio"]),
            _np.asarray(data["eigenvalue_re"]) + 1j * _np.asarray(data["eigenvalue_im"]),
        )

    def modes(self) -> Modes:
        """The natural frequencies (Hz), damping ratios and eigenvalues, by frequency.

        Returns
        -------
        Modes
            Of a discrete-time model: from its poles ``z`` by ``lambda = ln(z) / dt``
            (frequencies above the Nyquist frequency ``1 / 2 dt`` fold below it).
        """
        return self._modes

    def is_discrete(self) -> bool:
        """Whether the model is in discrete time (``dt > 0``)."""
        return self.dt > 0

    def frequency_response(self, omega):
        """The frequency response in python-control's conventions.

        Parameters
        ----------
        omega : array_like
            Angular frequencies (rad/s); of a discrete-time model at most the Nyquist
            frequency ``pi / dt``.

        Returns
        -------
        numpy.ndarray
            Complex, shape ``(outputs, inputs, len(omega))``: ``C (s I - A)^-1 B + D`` at
            ``s = i omega`` (at ``z = exp(i omega dt)`` in discrete time), by the Hessenberg
            method of ``flexprr frf`` (Laub 1981), which stays exact at repeated modes.

        Raises
        ------
        ValueError
            A frequency above the Nyquist frequency, or at an undamped pole.
        """
        w = _np.atleast_1d(_np.asarray(omega, dtype=float))
        return _frequency_response(
            _np.ascontiguousarray(self.A),
            _np.ascontiguousarray(self.B),
            _np.ascontiguousarray(self.C),
            _np.ascontiguousarray(self.D),
            self.dt,
            _np.ascontiguousarray(w),
        )

    def to_control(self, name=None):
        """The model as a python-control ``StateSpace`` with its signal names and ``dt``.

        Parameters
        ----------
        name : str, optional
            The system's name (default: the scene's name).

        Returns
        -------
        control.StateSpace
            Inputs, outputs and states named by ``input_signals``, ``output_signals`` and
            ``state_signals``; ``dt`` 0 (continuous) or the law's period.
        """
        import control

        return control.ss(
            self.A,
            self.B,
            self.C,
            self.D,
            self.dt,
            inputs=self.input_signals,
            outputs=self.output_signals,
            states=self.state_signals,
            name=name or self.scene,
        )

    def to_scipy(self):
        """The model as ``scipy.signal.StateSpace`` (with ``dt`` in discrete time).

        Returns
        -------
        scipy.signal.StateSpace
        """
        from scipy import signal

        if self.dt > 0:
            return signal.StateSpace(self.A, self.B, self.C, self.D, dt=self.dt)
        return signal.StateSpace(self.A, self.B, self.C, self.D)

    def physical(self):
        """The same model in the physical state (``x = state_scale * x~``).

        Returns
        -------
        LinearModel
        """
        s = self.state_scale
        data = dict(self.__dict__)
        data.update(
            A=self.A * s[:, None] / s[None, :],
            B=self.B * s[:, None],
            C=self.C / s[None, :],
            x0=self.x0 * s,
            state_scale=_np.ones_like(s),
            realization="physical",
            frequency_hz=self._modes.frequency_hz,
            damping_ratio=self._modes.damping_ratio,
            eigenvalue_re=self._modes.eigenvalue.real,
            eigenvalue_im=self._modes.eigenvalue.imag,
        )
        return LinearModel(data)

    def __repr__(self):
        lowest = ", ".join(f"{f:.2f} Hz" for f in self._modes.frequency_hz[:3])
        time = f", discrete dt = {self.dt} s" if self.dt > 0 else ""
        return (
            f"LinearModel({self.scene!r}, {self.model} model, {self.A.shape[0]} states{time}, "
            f"inputs {self.inputs}, outputs {self.outputs}, lowest modes {lowest})"
        )


class LinearModels:
    """Linear models along a motion from one integration (:func:`linearize` with a list of
    times): ``models[k]`` is the :class:`LinearModel` at ``t[k]``, all realised with the
    state scales of the first, and ``A``, ``B``, ``C``, ``D`` stack them on a leading time
    axis (as ``statespace.npz`` of ``flexprr statespace --times``).
    """

    def __init__(self, models):
        self.models = list(models)
        self.t = _np.array([m.t for m in self.models])

    def __len__(self):
        return len(self.models)

    def __getitem__(self, k):
        return self.models[k]

    def __iter__(self):
        return iter(self.models)

    @property
    def A(self):
        """``A(t)``, shape ``(times, n, n)``."""
        return _np.stack([m.A for m in self.models])

    @property
    def B(self):
        """``B(t)``, shape ``(times, n, inputs)``."""
        return _np.stack([m.B for m in self.models])

    @property
    def C(self):
        """``C(t)``, shape ``(times, outputs, n)``."""
        return _np.stack([m.C for m in self.models])

    @property
    def D(self):
        """``D(t)``, shape ``(times, outputs, inputs)``."""
        return _np.stack([m.D for m in self.models])

    def __repr__(self):
        return f"LinearModels({len(self.models)} times from {self.t[0]} to {self.t[-1]} s)"


def linearize(
    scene,
    pose=None,
    t=None,
    inputs=(),
    outputs=(),
    rigid_chords=False,
    coulomb="left-out",
    realization="scaled",
):
    """The linear model of ``scene`` about an operating point.

    Parameters
    ----------
    scene : Scene or path
        A :class:`Scene` or the path of a scene file (coupled or nonlinear model).
    pose : tuple of float, optional
        ``(x_m, y_m, phi_deg)``: the platform at rest there, sliders locked, or held by the
        scene's ``[control]`` law.
    t : float or sequence of float, optional
        The state of the scene's motion at that time (s); a sequence gives one model per
        time from one integration (a :class:`LinearModels`). Neither ``pose`` nor ``t``:
        at rest where the motion starts.
    inputs, outputs : sequence of str
        Channel names of ``flexprr frf``/``flexprr statespace`` (docs/linear.md, "Channels"):
        inputs ``slider_force:I``, ``point_force:LINK@XI``, ``reference:I``,
        ``reference_rate:I``, ``patch_voltage:P``, ``actuator_command:I``; outputs
        ``slider:I``, ``slider_velocity:I``, ``slider_error:I``, ``slider_error_rate:I``,
        ``motor_torque:I``, ``slider_command:I``, ``platform:x|y|phi``,
        ``platform_velocity:x|y|phi``, ``deflection:LINK@XI``, ``slope:LINK@XI``,
        ``acceleration:LINK@XI``, ``patch_sensor:P``.
    rigid_chords : bool
        Keep the coupled model's chords rigid at rest (the paper's pinned-pinned links).
    coulomb : {"left-out", "smoothed"}
        The actuators' Coulomb friction: held at its value at the operating point (the
        default) or with its smoothed slope.
    realization : {"scaled", "physical"}
        The state divided by powers of two that balance ``A`` (the default) or physical.

    Returns
    -------
    LinearModel or LinearModels
        Discrete-time (``dt > 0``) when the scene's control law is sampled.

    Raises
    ------
    SceneError
        A bad name, pose, time or scene (a KED scene has no whole-machine model).
    RunError
        The model fails (along the motion: a failed run).
    TypeError
        ``inputs`` or ``outputs`` given as one string.
    """
    if isinstance(inputs, str) or isinstance(outputs, str):
        raise TypeError("inputs and outputs are lists of names, e.g. inputs=['slider_force:1']")
    several = t is not None and not isinstance(t, (int, float, _np.floating, _np.integer))
    data = _linearize(
        scene,
        pose=pose,
        t=[float(v) for v in t] if several else (None if t is None else float(t)),
        inputs=list(inputs),
        outputs=list(outputs),
        rigid_chords=bool(rigid_chords),
        coulomb=str(coulomb),
        realization=str(realization),
    )
    if several:
        return LinearModels(LinearModel(d) for d in data)
    return LinearModel(data)


class LoopMargins(_NamedTuple):
    """Stability margins of one slider loop (:meth:`SliderLoop.margins`).

    Attributes
    ----------
    gain_margin : float
        The factor by which the loop gain can grow before instability (inf if none).
    phase_margin_deg : float
        The phase margin (deg) at the gain crossover (inf if the gain never reaches 1).
    gain_crossover_hz : float
        Where ``|L| = 1`` (Hz; nan if none).
    phase_crossover_hz : float
        Where the phase of ``L`` is -180 deg (Hz; nan if none).
    sensitivity_peak : float
        ``max |1 / (1 + L)|`` over the grid (the inverse of the stability margin).
    sensitivity_peak_hz : float
        Where it is reached (Hz).
    """

    gain_margin: float
    phase_margin_deg: float
    gain_crossover_hz: float
    phase_crossover_hz: float
    sensitivity_peak: float
    sensitivity_peak_hz: float


class SliderLoop:
    """One slider's control loop broken at its actuator (:func:`slider_loop`).

    Attributes
    ----------
    slider : int
        The slider (1-based).
    model : LinearModel
        The open-loop model from ``actuator_command:I`` (the actuator's force command, N)
        to ``slider_command:I`` (the law's command, N), the other two loops closed.
    """

    def __init__(self, slider, model):
        self.slider = slider
        self.model = model

    def loop_gain(self):
        """The loop gain ``L = -slider_command / actuator_command`` (negative feedback).

        Returns
        -------
        control.StateSpace
            SISO, with the model's ``dt``.
        """
        import control

        return -self.model.to_control(name=f"loop_{self.slider}")

    def response(self, omega):
        """``L(i omega)`` (``L(exp(i omega dt))`` in discrete time) at ``omega`` (rad/s)."""
        return -self.model.frequency_response(omega)[0, 0, :]

    def grid(self):
        """The default frequencies (rad/s) of :meth:`margins`: 4000 log-spaced from 1 rad/s to
        ten times the fastest mode (the Nyquist frequency ``pi / dt`` of a discrete model),
        and 41 more about each mode within a quarter of its half-power bandwidth apart."""
        modes = self.model.modes()
        fastest = 2 * _np.pi * max(float(modes.frequency_hz.max(initial=1.0)), 1.0)
        top = _np.pi / self.model.dt if self.model.dt > 0 else 10 * fastest
        w = [_np.geomspace(1.0, top, 4000)]
        for f, zeta in zip(modes.frequency_hz, modes.damping_ratio):
            wn = 2 * _np.pi * f
            band = min(max(abs(zeta), 1e-4), 0.05)
            w.append(wn * (1 + 0.25 * band * _np.arange(-20, 21)))
        w = _np.unique(_np.concatenate(w))
        return w[(w > 0) & (w <= top)]

    def _refine(self, f, lo, hi, steps=60):
        """The root of ``f`` between ``lo`` and ``hi`` (rad/s, a sign change) by bisection in
        ``log omega``."""
        flo = f(lo)
        for _ in range(steps):
            mid = _np.sqrt(lo * hi)
            fm = f(mid)
            if _np.sign(fm) == _np.sign(flo):
                lo, flo = mid, fm
            else:
                hi = mid
            if hi / lo - 1 < 1e-12:
                break
        return _np.sqrt(lo * hi)

    def margins(self, omega=None):
        """Gain and phase margins and the sensitivity peak, from the exact frequency response.

        Every crossing of ``|L| = 1`` and of the negative real axis on the grid is refined by
        bisection on the response itself (the Hessenberg method of ``flexprr frf``), so the
        lightly damped bending modes of the links, which make a loop gain cross several times,
        are resolved. python-control's ``stability_margins`` gives the same numbers from the
        same response (``control.frd``); its polynomial method loses every digit on a
        machine's loop of twenty states and more.

        Parameters
        ----------
        omega : array_like, optional
            The grid (rad/s); default :meth:`grid`.

        Returns
        -------
        LoopMargins
            Of several crossings, the smallest phase margin (in absolute value) and the gain
            margin closest to 1; inf where there is no crossing.
        """
        w = self.grid() if omega is None else _np.asarray(omega, dtype=float)
        h = self.response(w)
        one = lambda x: float(_np.abs(self.response(_np.array([x]))[0]) - 1.0)
        imag = lambda x: float(self.response(_np.array([x]))[0].imag)
        pm, wgc = float("inf"), float("nan")
        for k in _np.where(_np.diff(_np.sign(_np.abs(h) - 1.0)) != 0)[0]:
            wc = self._refine(one, w[k], w[k + 1])
            margin = 180.0 + _np.degrees(_np.angle(self.response(_np.array([wc]))[0]))
            margin = margin - 360.0 if margin > 180.0 else margin
            if abs(margin) < abs(pm):
                pm, wgc = margin, wc
        gm, wpc = float("inf"), float("nan")
        for k in _np.where(_np.diff(_np.sign(h.imag)) != 0)[0]:
            if h.real[k] >= 0 and h.real[k + 1] >= 0:
                continue
            wc = self._refine(imag, w[k], w[k + 1])
            value = self.response(_np.array([wc]))[0]
            if value.real < 0:
                g = 1.0 / abs(value.real)
                if abs(_np.log(g)) < abs(_np.log(gm)):
                    gm, wpc = g, wc
        s = _np.abs(1.0 / (1.0 + h))
        k = int(_np.argmax(s))
        hz = lambda v: float(v) / (2 * _np.pi)
        return LoopMargins(float(gm), float(pm), hz(wgc), hz(wpc), float(s[k]), hz(w[k]))

    def __repr__(self):
        return f"SliderLoop(slider {self.slider}, {self.model!r})"


def slider_loop(scene, slider, pose=None, t=None, rigid_chords=False, coulomb="left-out"):
    """Slider ``slider``'s control loop broken at its actuator.

    The actuator of that slider takes the input ``actuator_command:I`` in place of the law's
    command; the law still runs and its command is the output ``slider_command:I``, so that
    ``L = -slider_command / actuator_command`` is the loop gain seen at the actuator, with
    the machine's dynamics (links, platform, the other two loops closed) and, for a sampled
    law, the zero-order hold (discrete time).

    Parameters
    ----------
    scene : Scene or path
        A scene with ``[control]``.
    slider : int
        1, 2 or 3.
    pose, t, rigid_chords, coulomb
        As :func:`linearize`.

    Returns
    -------
    SliderLoop
    """
    if slider not in (1, 2, 3):
        raise ValueError(f"slider = {slider!r}: expected 1, 2 or 3")
    model = linearize(
        scene,
        pose=pose,
        t=t,
        inputs=[f"actuator_command:{slider}"],
        outputs=[f"slider_command:{slider}"],
        rigid_chords=rigid_chords,
        coulomb=coulomb,
        realization="scaled",
    )
    return SliderLoop(slider, model)
