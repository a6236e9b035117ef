"""An LQR with an observer, designed in python-control on flexprr's linear model of the whole
flexible machine, and run in the loop on the coupled and the nonlinear machine (docs/control.md,
"Your controller in the loop").

1. The plant (flexprr.linearize): configs/servo_f20.toml with its law's gains at zero, at the
   centre of its circle, from the three slider forces to the three slider positions: the
   sliders, the platform and the links' bending modes (1 % modal damping), every state.
2. The design (python-control): a linear-quadratic regulator on every state of the plant
   (control.lqr; Bryson's rule: 20 um of slider error is worth 200 N of force) and a
   steady-state Kalman filter as its observer (control.lqr on the dual: force disturbances of
   50 N against 1 um of encoder noise). The law reads the slider errors e = rho_ref - rho (the
   plant's output is -e about the commanded motion) and commands the slider forces beside the
   rigid feedforward:

       z' = (A - B K - L C) z - L e,        F = F_ff - K z

3. The law as data: an npz with A, B, C, D, and a scene with `[control] kind = "statespace"`
   reading it, written into the output directory.
4. The check at small amplitude: a 10 um move from the design pose (no feedforward), run on the
   coupled machine with the law; the slider errors of the run against the linear closed loop's
   prediction (flexprr.linearize of the designed scene, from the three references to the three
   errors, control.forced_response with the run's own references).
5. The 20 Hz circle with the LQR and with the scene's PD law, on the coupled and the nonlinear
   machine: RMS and peak tracking error, peak deflection, peak force.

Run from the repository root:  python examples/python/lqr_in_the_loop.py [out_dir]
"""

import pathlib
import sys
import tempfile

import control
import numpy as np

import flexprr

ROOT = pathlib.Path(__file__).resolve().parents[2]
BASE = ROOT / "configs" / "servo_f20.toml"
#: The design pose: the circle's centre (x m, y m, phi deg).
POSE = (-0.05, 0.0, 45.0)
SLIDERS = (1, 2, 3)
#: The machines the law is designed on and run on.
MODELS = ("coupled", "nonlinear")
#: Bryson's rule: the largest acceptable slider error (m) and force (N).
ERROR_SCALE, FORCE_SCALE = 20e-6, 200.0
#: The observer's noise model: force disturbances (N) and encoder noise (m).
FORCE_NOISE, ENCODER_NOISE = 50.0, 1e-6


def base_text(control_table: str, trajectory: str | None = None, extra: str = "") -> str:
    """servo_f20.toml with its [control] table replaced, optionally its trajectory and time."""
    text = BASE.read_text()

    def table(name: str) -> int:
        return text.index(f"\n[{name}]") + 1

    text = text[: table("control")] + control_table + "\n\n" + text[table("integrator") :]
    if trajectory is not None:
        text = text[: table("trajectory")] + trajectory + "\n\n" + text[table("model") :]
    return text + extra


def configure(scene: flexprr.Scene, coupling: str) -> flexprr.Scene:
    """The model `coupling`, with 1 % modal damping where the model has modes."""
    scene.set("model.coupling", coupling)
    if coupling != "nonlinear":  # the co-rotational links have no modes to damp
        scene.set("model.damping", [0.01])
    return scene


def plant(coupling: str) -> control.StateSpace:
    """The machine (model `coupling`) with its sliders free, from the slider forces to the
    slider positions."""
    scene = flexprr.Scene.load(BASE)
    scene.set("control.kp", 0.0)
    scene.set("control.kd", 0.0)
    configure(scene, coupling)
    model = flexprr.linearize(
        scene,
        pose=POSE,
        inputs=[f"slider_force:{i}" for i in SLIDERS],
        outputs=[f"slider:{i}" for i in SLIDERS],
    )
    return model.to_control()


def design(p: control.StateSpace) -> dict:
    """The LQR gain K, the observer gain L and the law from the errors to the forces."""
    a, b, c = p.A, p.B, p.C
    q = c.T @ c / ERROR_SCALE**2
    r = np.eye(b.shape[1]) / FORCE_SCALE**2
    k, _, regulator_poles = control.lqr(a, b, q, r)
    qo = b @ b.T * FORCE_NOISE**2
    ro = np.eye(c.shape[0]) * ENCODER_NOISE**2
    lt, _, observer_poles = control.lqr(a.T, c.T, qo, ro)
    l = lt.T
    law = {
        "A": a - b @ k - l @ c,
        "B": -l,
        "C": -k,
        "D": np.zeros((b.shape[1], c.shape[0])),
    }
    return {
        "K": k,
        "L": l,
        "law": law,
        "regulator_poles": regulator_poles,
        "observer_poles": observer_poles,
    }


def statespace_table(feedforward: str, file: str) -> str:
    errors = ", ".join(f'"slider_error:{i}"' for i in SLIDERS)
    forces = ", ".join(f'"slider_force:{i}"' for i in SLIDERS)
    return "\n".join(
        [
            "[control]",
            'kind = "statespace"',
            f'file = "{file}"',
            f"measurements = [{errors}]",
            f"commands = [{forces}]",
            f'feedforward = "{feedforward}"',
            "period = 0",
        ]
    )


def small_move_check(out: pathlib.Path, design_model: str) -> dict:
    """The run of a 10 um move on the design model against the linear closed loop's
    prediction."""
    x, y, phi = POSE
    move = "\n".join(
        [
            "[trajectory]",
            'kind = "point-to-point"',
            f"from = [{x}, {y}, {phi}]",
            f"to = [{x + 1e-5}, {y}, {phi}]",
            "start = 0.002",
            "duration = 0.01",
            'profile = "quintic"',
        ]
    )
    text = base_text(statespace_table("none", f"lqr_{design_model}.npz"), move)
    text = text.replace("end = 0.2", "end = 0.03").replace("output_step = 1e-4", "output_step = 1e-5")
    path = out / f"lqr_{design_model}_small_move.toml"
    path.write_text(text)
    scene = configure(flexprr.Scene.load(path), design_model)
    scene.set("output.requests", ["tracking", "kinematics"])
    scene.set("output.plots", False)
    result = flexprr.run(scene)
    tracking = result.table("tracking")
    t = np.asarray(tracking["t_s"])
    # The commanded slider positions: the kinematics of the commanded motion.
    commanded = result.table("kinematics")
    reference = np.vstack([np.asarray(commanded[f"rho_{i}_m"]) for i in SLIDERS])
    error = np.vstack([np.asarray(tracking[f"slider_error_{i}_m"]) for i in SLIDERS])
    loop = flexprr.linearize(
        scene,
        pose=POSE,
        inputs=[f"reference:{i}" for i in SLIDERS],
        outputs=[f"slider_error:{i}" for i in SLIDERS],
    ).to_control()
    predicted = control.forced_response(loop, T=t, U=reference - reference[:, :1]).outputs
    peak = float(np.abs(predicted).max())
    difference = float(np.abs(error - predicted).max())
    return {"peak_error_m": peak, "difference_m": difference, "relative": difference / peak}


def circle(out: pathlib.Path, law: str, coupling: str) -> dict:
    """The 20 Hz circle under `law` ("pd", or "lqr_<model>": the LQR designed on that model)
    on the `coupling` model, with the linear closed loop's largest growth rate at the design
    pose (its eigenvalue of largest real part: > 0 predicts an unstable loop)."""
    if law == "pd":
        text = BASE.read_text()
    else:
        text = base_text(statespace_table("rigid", f"{law}.npz"))
    path = out / f"circle_{law}_{coupling}.toml"
    path.write_text(text)
    scene = configure(flexprr.Scene.load(path), coupling)
    scene.set("time.end", 0.1)
    scene.set("output.requests", ["tracking", "deflections", "actuators"])
    scene.set("output.plots", False)
    loop = flexprr.linearize(scene, pose=POSE, inputs=["reference:1"], outputs=["slider:1"])
    eigenvalues = np.linalg.eigvals(loop.A)
    worst = eigenvalues[np.argmax(eigenvalues.real)]
    result = flexprr.run(scene)
    tracking = result.table("tracking")
    error = np.vstack([np.asarray(tracking[f"slider_error_{i}_m"]) for i in SLIDERS])
    deflections = result.table("deflections")
    w = [np.asarray(v) for k, v in deflections.to_dict().items() if k.startswith("w_")]
    actuators = result.table("actuators")
    force = [np.asarray(actuators[f"actuator_force_{i}_N"]) for i in SLIDERS]
    return {
        "growth_rate": float(worst.real),
        "growth_hz": float(abs(worst.imag) / (2 * np.pi)),
        "rms_error_m": float(np.sqrt(np.mean(error**2))),
        "peak_error_m": float(np.abs(error).max()),
        "peak_deflection_m": float(max(np.abs(v).max() for v in w)),
        "peak_force_N": float(max(np.abs(f).max() for f in force)),
    }


def main(out: pathlib.Path) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    designs, checks = {}, {}
    for model in MODELS:
        p = plant(model)
        d = design(p)
        designs[model] = d
        print(
            f"LQR on the {model} machine ({p.nstates} states): regulator poles "
            f"{-d['regulator_poles'].real.max():.3g} to {-d['regulator_poles'].real.min():.3g} 1/s, "
            f"observer poles {-d['observer_poles'].real.max():.3g} to "
            f"{-d['observer_poles'].real.min():.3g} 1/s"
        )
        # C-ordered float64 arrays (the npz reader refuses Fortran order rather than guess).
        law = {k: np.ascontiguousarray(v, dtype=float) for k, v in d["law"].items()}
        np.savez(out / f"lqr_{model}.npz", **law)
        checks[model] = small_move_check(out, model)
        print(
            f"  10 um move on the {model} machine: peak slider error "
            f"{checks[model]['peak_error_m'] * 1e9:.3f} nm; the run within "
            f"{100 * checks[model]['relative']:.3f} % of the linear closed loop's prediction"
        )
    rows = {}
    for law in [f"lqr_{m}" for m in MODELS] + ["pd"]:
        for coupling in MODELS:
            rows[(law, coupling)] = circle(out, law, coupling)
    print("20 Hz circle, 0-0.1 s (growth: the linear closed loop's largest real part at the centre):")
    print("| law | run on | growth (1/s) at (Hz) | RMS error (um) | peak error (um) | peak deflection (mm) | peak force (N) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for (law, coupling), r in rows.items():
        print(
            f"| {law} | {coupling} | {r['growth_rate']:.3g} at {r['growth_hz']:.0f} | "
            f"{r['rms_error_m'] * 1e6:.2f} | {r['peak_error_m'] * 1e6:.2f} | "
            f"{r['peak_deflection_m'] * 1e3:.3f} | {r['peak_force_N']:.1f} |"
        )
    return {"designs": designs, "checks": checks, "circle": rows}


if __name__ == "__main__":
    if len(sys.argv) > 1:
        main(pathlib.Path(sys.argv[1]))
    else:
        with tempfile.TemporaryDirectory() as tmp:
            main(pathlib.Path(tmp))
