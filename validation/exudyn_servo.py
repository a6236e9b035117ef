"""The paper's 3-PRR under PD control with rigid feedforward: an external reference (Exudyn).

The coupled model of `exudyn_3prr.py` (16 ANCF cable elements per link, axially elastic, free
rigid platform pinned at C_i, the same parameters, initial state convention, integrator and
axial damping), with only the sliders changed: each slider is a rigid body of mass m_s on a
prismatic joint along its guide, pinned (position only) to the first node of its link, and
driven along the guide by the actuator force

    F_i = kp (rho_ref_i - rho_i) + kd (rho_ref_i' - rho_i') + F_ff_i(t),

rho_ref_i(t) the closed-form inverse kinematics of the trajectory (docs/model.md section 3) and
F_ff_i(t) the rigid-body inverse-dynamics driving force of the reference motion (section 4,
F_ai = m_s rho_i'' + F_Bi . u_i). The PD part is a linear spring-damper (kp, kd) between the
slider and the fixed point B_i(0) on the guide, plus the time-only load
kp (rho_ref_i(t) - rho_ref_i(0)) + kd rho_ref_i'(t) along u_i: the same force as a spring-damper
to a point moving with rho_ref_i(t), with an exact (analytic) Jacobian for Newton's method.

Outputs (sampled every 2.5e-4 s, 0-0.2 s; columns in README.md): data/servo_f10.csv,
data/servo_f20.csv, data/servo_meta.json; `--convergence` -> data/servo_convergence.json;
`--stiff-check` -> data/servo_stiff_check.json (kp = 1e9, kd = 1e5 against the prescribed-slider
model's data/coupled_f20.csv).

Usage:
    python3 exudyn_servo.py                      # production runs f = 10 and 20 Hz
    python3 exudyn_servo.py --convergence        # 16 vs 32 elements, h vs h/2 at 20 Hz
    python3 exudyn_servo.py --stiff-check        # very stiff servo against the prescribed model
    python3 exudyn_servo.py --freq 20 --kp 1e6 --kd 1e3 --out /some/file.csv
"""

import argparse
import json
import os
import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    LoadForceVector,
    MarkerBodyPosition,
    MarkerBodyRigid,
    NodeRigidBody2D,
    ObjectConnectorCartesianSpringDamper,
    ObjectJointPrismatic2D,
    ObjectJointRevolute2D,
    ObjectRigidBody2D,
    SensorLoad,
    SensorNode,
    SensorObject,
)

from exudyn_3prr import (
    AXIAL_DAMPING_TIME,
    END_TIME,
    SAMPLE_PERIOD,
    add_ground,
    add_link,
    add_platform,
    add_platform_pin,
    check_elements,
    chord_frame,
    rel_l2,
    sample_rows,
    solver_settings,
)
from scene import Scene, leg_kinematics, rigid_inverse_dynamics

HERE = os.path.dirname(os.path.abspath(__file__))
KP = 2e5  # N/m, configs/servo_f20.toml
KD = 400.0  # N s/m
STEP = 6.25e-6  # s, as the prescribed model's production runs
# The slider's rotation is locked by its prismatic joint, so its rotary inertia never enters;
# any positive value does (a 0.5 kg block 50 mm long: m_s (0.05^2) / 12 ~ 1e-4 kg m^2).
SLIDER_INERTIA = 1e-4

COLUMNS = (
    ["t_s"]
    + [f"w_mid_{i}_m" for i in (1, 2, 3)]
    + [f"slider_error_{i}_m" for i in (1, 2, 3)]
    + ["dx_m", "dy_m", "dphi_rad"]
    + [f"F_{i}_N" for i in (1, 2, 3)]
)


class ServoReference:
    """Reference slider motion rho_ref(t), rho_ref'(t) and the rigid feedforward F_ff(t) of the
    three legs (model.md sections 3-4), cached per time value."""

    def __init__(self, scene):
        self.scene = scene
        self._t = None
        self._val = None

    def __call__(self, t):
        """(rho_ref (3,), rho_ref' (3,), F_ff (3,)) at time t."""
        if self._t is None or t != self._t:
            legs, _f_b, _f_c, f_a = rigid_inverse_dynamics(self.scene, t)
            rho = np.array([k.rho for k in legs])
            rho_d = np.array([k.rho_d for k in legs])
            self._val = (rho, rho_d, f_a)
            self._t = t
        return self._val


def add_servo_slider(mbs, scene, i, leg, ground, first_element, kp, kd):
    """Slider i: a rigid body (mass m_s) on a prismatic joint along guide i, at B_i = leg's slider
    point with velocity rho' u_i, pinned (position only) to the start of the link's first
    element, and held by a spring-damper (kp, kd, isotropic in the plane) to the fixed point
    B_i on the guide. first_element None: no pin (a slider alone, for checks).

    ObjectJointPrismatic2D (ground frame at B_i, axis u_i; slider normal v_i; rotation locked):
    (p - B_i) . v_i = 0 and the slider's angle stays 0. Along the guide the spring-damper gives
    -kp (rho - rho_i) - kd rho'; across it its force is kp times the constraint violation (~1e-12
    m): nothing. Returns a dict of the items.
    """
    u = scene.guide_direction(i)
    v = scene.guide_normal(i)
    b = leg.slider_point
    node = mbs.AddNode(
        NodeRigidBody2D(
            referenceCoordinates=[b[0], b[1], 0.0],
            initialVelocities=[leg.rho_d * u[0], leg.rho_d * u[1], 0.0],
        )
    )
    body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=scene.slider_mass, inertia=SLIDER_INERTIA))
    guide_frame = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[b[0], b[1], 0.0]))
    slider_frame = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[0.0, 0.0, 0.0]))
    prismatic = mbs.AddObject(
        ObjectJointPrismatic2D(
            markerNumbers=[guide_frame, slider_frame],
            axisMarker0=[u[0], u[1], 0.0],
            normalMarker1=[v[0], v[1], 0.0],
            constrainRotation=True,
        )
    )
    anchor = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[b[0], b[1], 0.0]))
    slider_point = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0.0, 0.0, 0.0]))
    spring = mbs.AddObject(
        ObjectConnectorCartesianSpringDamper(
            markerNumbers=[anchor, slider_point],
            stiffness=[kp, kp, 0.0],
            damping=[kd, kd, 0.0],
            offset=[0.0, 0.0, 0.0],
        )
    )
    pin = None
    if first_element is not None:
        link_start = mbs.AddMarker(MarkerBodyPosition(bodyNumber=first_element, localPosition=[0.0, 0.0, 0.0]))
        pin = mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[slider_point, link_start]))
    return {
        "node": node,
        "body": body,
        "marker": slider_point,
        "prismatic": prismatic,
        "spring": spring,
        "pin": pin,
        "anchor_rho": leg.rho,
    }


def add_servo_load(mbs, scene, i, slider, reference, kp, kd, feedforward=True):
    """The time-only part of the actuator force along u_i:
    kp (rho_ref_i(t) - rho_i(0)) + kd rho_ref_i'(t) + F_ff_i(t) (F_ff off with feedforward=False).
    With the spring-damper of add_servo_slider the slider feels exactly
    F_i = kp (rho_ref - rho) + kd (rho_ref' - rho') + F_ff."""
    u = scene.guide_direction(i)
    rho0 = slider["anchor_rho"]
    ff = 1.0 if feedforward else 0.0

    def load(mbs_, t, load_vector, i=i, u=u, rho0=rho0):
        rho, rho_d, f_ff = reference(t)
        f = kp * (rho[i] - rho0) + kd * rho_d[i] + ff * f_ff[i]
        return [f * u[0], f * u[1], 0.0]

    return mbs.AddLoad(LoadForceVector(markerNumber=slider["marker"], loadVectorUserFunction=load))


def build_servo_model(scene, n_elements, kp, kd, axial_damping_time=0.0, feedforward=True):
    """The servo-driven machine at the rigid IK state at t = 0 (as build_model of exudyn_3prr.py,
    with the sliders of add_servo_slider / add_servo_load). Returns (SC, mbs, handles)."""
    check_elements(n_elements)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground, _ground_coordinate = add_ground(mbs)
    pose0, vel0, _acc0 = scene.platform_pose(0.0)
    platform_node, platform = add_platform(mbs, scene, pose0, vel0)
    reference = ServoReference(scene)
    handles = {"platform_node": platform_node, "links": [], "sliders": [], "reference": reference}
    for i in range(3):
        k = leg_kinematics(scene, i, 0.0)
        nodes, elements = add_link(mbs, scene, i, k, n_elements, axial_damping_time)
        slider = add_servo_slider(mbs, scene, i, k, ground, elements[0], kp, kd)
        slider["load"] = add_servo_load(mbs, scene, i, slider, reference, kp, kd, feedforward)
        platform_joint = add_platform_pin(mbs, scene, i, platform, elements[-1])
        handles["sliders"].append(slider)
        handles["links"].append({"nodes": nodes, "elements": elements, "platform_joint": platform_joint})
    mbs.Assemble()
    return sc, mbs, handles


def add_servo_sensors(mbs, handles, n_elements):
    """Sensors (stored in memory): platform pose, link end and mid-node positions, slider
    position, velocity and acceleration, and the slider's forces (spring-damper, load, pin)."""
    def sensor(item):
        return mbs.AddSensor(item)

    ovt = exu.OutputVariableType
    opts = {"storeInternal": True, "writeToFile": False}
    s = {"platform": sensor(SensorNode(nodeNumber=handles["platform_node"], outputVariableType=ovt.Coordinates, **opts))}
    mid_node = n_elements // 2
    for i, (link, slider) in enumerate(zip(handles["links"], handles["sliders"])):
        for key, node in (("B", link["nodes"][0]), ("M", link["nodes"][mid_node]), ("C", link["nodes"][-1])):
            s[f"{key}{i}"] = sensor(SensorNode(nodeNumber=node, outputVariableType=ovt.Position, **opts))
        for key, var in (("S", ovt.Position), ("Sv", ovt.Velocity), ("Sa", ovt.Acceleration)):
            s[f"{key}{i}"] = sensor(SensorNode(nodeNumber=slider["node"], outputVariableType=var, **opts))
        for key, obj in (("Fspring", slider["spring"]), ("Fpin", slider["pin"])):
            s[f"{key}{i}"] = sensor(SensorObject(objectNumber=obj, outputVariableType=ovt.Force, **opts))
        s[f"Fload{i}"] = sensor(SensorLoad(loadNumber=slider["load"], **opts))
    return s


def simulate_servo(scene, n_elements=16, step=STEP, kp=KP, kd=KD, spectral_radius=0.98, solver="alpha",
                   axial_damping_time=AXIAL_DAMPING_TIME, feedforward=True, end_time=END_TIME, verbose=False):
    """Run the servo model from 0 to end_time. Returns (table (rows x COLUMNS), extras dict)."""
    _sc, mbs, handles = build_servo_model(scene, n_elements, kp, kd, axial_damping_time, feedforward)
    sensors = add_servo_sensors(mbs, handles, n_elements)
    mbs.Assemble()
    settings, solver_type = solver_settings(end_time, step, spectral_radius, solver, verbose)
    t0 = time.time()
    ok = mbs.SolveDynamic(settings, solverType=solver_type, showHints=verbose)
    wall = time.time() - t0
    if not ok:
        raise RuntimeError(f"Exudyn failed: servo f = {scene.frequency} Hz, {n_elements} elements, h = {step}")
    table, extras = collect_servo(scene, mbs, sensors, handles["reference"], kp, kd, feedforward)
    extras["wall_s"] = wall
    extras["n_steps"] = int(settings.timeIntegration.numberOfSteps)
    return table, extras


def collect_servo(scene, mbs, sensors, reference, kp, kd, feedforward):
    """Output columns (README.md) and the force checks from the stored sensor data."""
    def data(key):
        return mbs.GetSensorStoredData(sensors[key])

    plat = data("platform")
    idx = sample_rows(plat[:, 0])
    t = plat[idx, 0]
    out = np.zeros((len(t), len(COLUMNS)))
    out[:, 0] = t
    pose0, _v, _a = scene.platform_pose(0.0)
    nominal = np.array([scene.platform_pose(tn)[0] for tn in t])
    out[:, 7:10] = pose0 + plat[idx, 1:4] - nominal
    refs = [reference(tn) for tn in t]
    rho_ref = np.array([r[0] for r in refs])
    rho_ref_d = np.array([r[1] for r in refs])
    f_ff = np.array([r[2] for r in refs]) * (1.0 if feedforward else 0.0)
    checks = {"pin_gap_max_m": 0.0, "guide_gap_max_m": 0.0, "force_sensor_minus_law_max_N": 0.0,
              "slider_momentum_residual_rel_rms": []}
    for i in range(3):
        b, m, c = (data(f"{key}{i}")[idx, 1:3] for key in ("B", "M", "C"))
        _e, n, _len = chord_frame(b, c)
        out[:, 1 + i] = np.sum((m - b) * n, axis=1)
        u, v, a_pt = scene.guide_direction(i), scene.guide_normal(i), scene.guide_centre(i)
        p = data(f"S{i}")[idx, 1:3]
        rho = (p - a_pt) @ u
        rho_d = data(f"Sv{i}")[idx, 1:3] @ u
        err, err_d = rho_ref[:, i] - rho, rho_ref_d[:, i] - rho_d
        out[:, 4 + i] = err
        force = kp * err + kd * err_d + f_ff[:, i]
        out[:, 10 + i] = force
        # the same force from Exudyn's own connector and load sensors: the spring-damper sensor
        # reports k (p1 - p0) + d (v1 - v0), which acts on marker 1 (the slider) with minus sign
        applied = (data(f"Fload{i}")[idx, 1:3] - data(f"Fspring{i}")[idx, 1:3]) @ u
        checks["force_sensor_minus_law_max_N"] = max(checks["force_sensor_minus_law_max_N"],
                                                     float(np.abs(applied - force).max()))
        checks["pin_gap_max_m"] = max(checks["pin_gap_max_m"], float(np.abs(p - b).max()))
        checks["guide_gap_max_m"] = max(checks["guide_gap_max_m"], float(np.abs((p - a_pt) @ v).max()))
        # slider along the guide: m_s rho'' = F_i + (force of the pin on the slider) . u; the
        # revolute joint reports the force on its marker 0, the slider
        acc = data(f"Sa{i}")[idx, 1:3] @ u
        res = scene.slider_mass * acc - force - data(f"Fpin{i}")[idx, 1:3] @ u
        checks["slider_momentum_residual_rel_rms"].append(
            float(np.sqrt(np.mean(res**2)) / np.sqrt(np.mean(force**2))))
    return out, checks


def write_csv(path, table):
    """Write the output table with a header row."""
    np.savetxt(path, table, delimiter=",", header=",".join(COLUMNS), comments="", fmt="%.6e")


def compare(a, b):
    """Relative L2 differences ||a - b|| / ||b|| per column group (all samples and legs)."""
    return {
        "w_mid": rel_l2(a[:, 1:4], b[:, 1:4]),
        "slider_error": rel_l2(a[:, 4:7], b[:, 4:7]),
        "platform_xy_deviation": rel_l2(a[:, 7:9], b[:, 7:9]),
        "platform_dphi": rel_l2(a[:, 9], b[:, 9]),
        "F": rel_l2(a[:, 10:13], b[:, 10:13]),
    }


def convergence(freqs, args, log):
    """Mesh (16 vs 32 elements at h) and step (h vs h/2 at 16 elements) at each frequency."""
    results = {"step_s": args.step, "kp_N_m": args.kp, "kd_N_s_m": args.kd}
    for f in freqs:
        scene = Scene(frequency=f)
        runs = {}
        for ne, h in ((16, args.step), (32, args.step), (16, args.step / 2)):
            table, ex = simulate_servo(scene, ne, h, args.kp, args.kd, axial_damping_time=args.axial_damping)
            runs[(ne, h)] = table
            log(f"f={f} ne={ne} h={h:g}: wall {ex['wall_s']:.1f} s, max|w| {np.abs(table[:, 1:4]).max():.4e}, "
                f"max|e| {np.abs(table[:, 4:7]).max():.4e}")
        base = runs[(16, args.step)]
        results[f"f{int(f)}"] = {
            "mesh_32_vs_16_elements_at_h": compare(base, runs[(32, args.step)]),
            "step_h_vs_h_half_at_16_elements": compare(base, runs[(16, args.step / 2)]),
            "note": "relative L2 ||committed - finer|| / ||finer|| over 0-0.2 s, all legs",
        }
        log(json.dumps(results[f"f{int(f)}"], indent=1))
    return results


def stiff_check(args, log, kp=1e9, kd=1e5):
    """Very stiff servo at 20 Hz against the prescribed-slider model (data/coupled_f20.csv)."""
    scene = Scene(frequency=20.0)
    table, ex = simulate_servo(scene, args.elements, args.step, kp, kd, axial_damping_time=args.axial_damping)
    ref = np.loadtxt(os.path.join(HERE, "data", "coupled_f20.csv"), delimiter=",", skiprows=1)
    if ref.shape[0] != table.shape[0] or np.abs(ref[:, 0] - table[:, 0]).max() > 1e-9:
        raise RuntimeError("coupled_f20.csv is not on the servo model's time grid")
    late = table[:, 0] >= 0.02
    res = {
        "kp_N_m": kp,
        "kd_N_s_m": kd,
        "elements_per_link": args.elements,
        "step_s": args.step,
        "wall_s": ex["wall_s"],
        "max_abs_slider_error_m": float(np.abs(table[:, 4:7]).max()),
        "reference": "data/coupled_f20.csv (sliders prescribed on the IK path)",
        "rel_l2_w_mid": rel_l2(table[:, 1:4], ref[:, 1:4]),
        "rel_l2_w_mid_per_link": [rel_l2(table[:, 1 + i], ref[:, 1 + i]) for i in range(3)],
        "rel_l2_platform_xy_deviation": rel_l2(table[:, 7:9], ref[:, 4:6]),
        "rel_l2_platform_dphi": rel_l2(table[:, 9], ref[:, 6]),
        "rel_l2_w_mid_t_ge_20ms": rel_l2(table[late, 1:4], ref[late, 1:4]),
        "rel_l2_platform_xy_deviation_t_ge_20ms": rel_l2(table[late, 7:9], ref[late, 4:6]),
        "checks": ex,
    }
    log(json.dumps(res, indent=1, default=float))
    return res


def parameters(scene, args):
    """Every model parameter, for the meta file."""
    return {
        "E_Pa": scene.youngs_modulus,
        "density_kg_m3": scene.density,
        "link_length_m": scene.link_length,
        "thickness_m": scene.thickness,
        "height_m": scene.height,
        "EA_N": scene.axial_stiffness,
        "EI_Nm2": scene.bending_stiffness,
        "mass_per_length_kg_m": scene.mass_per_length,
        "platform_side_m": scene.platform_side,
        "platform_mass_kg": scene.platform_mass,
        "platform_inertia_kgm2": scene.platform_inertia,
        "slider_mass_kg": scene.slider_mass,
        "slider_rotary_inertia_kgm2": SLIDER_INERTIA,
        "kp_N_m": args.kp,
        "kd_N_s_m": args.kd,
        "feedforward": "rigid inverse dynamics F_ai = m_s rho_i'' + F_Bi . u_i" if not args.no_feedforward else "none",
        "controller": "continuous: F_i = kp (rho_ref_i - rho_i) + kd (rho_ref_i' - rho_i') + F_ff_i(t)",
        "guide_angles_deg": list(scene.guide_angles_deg),
        "layout": "radial: R_p = s/sqrt(3), c_i = R_p u(a_i + pi), A_i = (R_p + l) u(a_i + pi)",
        "trajectory": "x = 0.05 cos(2 pi f t) - 0.05, y = 0.05 sin(2 pi f t), phi = 45 deg",
        "initial_state": "rigid IK at t = 0: sliders at rho_ref(0) with rho_ref'(0), straight unstrained links with the rigid velocity field, platform at the nominal pose and velocity",
        "gravity": "none (normal to the plane)",
        "damping": "bending undamped; axial d = beta EA on the axial strain rate, beta = axial_damping_time_s",
    }


def main(argv=None):
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--freq", type=float, nargs="*", default=None)
    parser.add_argument("--elements", type=int, default=16)
    parser.add_argument("--step", type=float, default=STEP)
    parser.add_argument("--kp", type=float, default=KP)
    parser.add_argument("--kd", type=float, default=KD)
    parser.add_argument("--no-feedforward", action="store_true")
    parser.add_argument("--axial-damping", type=float, default=AXIAL_DAMPING_TIME)
    parser.add_argument("--out", default=None, help="CSV path (single frequency only)")
    parser.add_argument("--convergence", action="store_true")
    parser.add_argument("--stiff-check", action="store_true")
    args = parser.parse_args(argv)
    data_dir = os.path.join(HERE, "data")
    os.makedirs(data_dir, exist_ok=True)

    if args.convergence:
        res = convergence(args.freq or [20.0], args, print)
        with open(os.path.join(data_dir, "servo_convergence.json"), "w") as fh:
            json.dump(res, fh, indent=1)
        return
    if args.stiff_check:
        res = stiff_check(args, print)
        with open(os.path.join(data_dir, "servo_stiff_check.json"), "w") as fh:
            json.dump(res, fh, indent=1, default=float)
        return

    freqs = args.freq or [10.0, 20.0]
    meta = {
        "model": "Exudyn 2D ANCF cable links, slider bodies on prismatic joints under PD + rigid feedforward, free rigid platform, revolute joints",
        "exudyn_version": exu.__version__,
        "numpy_version": np.__version__,
        "elements_per_link": args.elements,
        "step_s": args.step,
        "solver": "generalized-alpha (index 3), rho_inf = 0.98, modified Newton with the Jacobian updated every step, abs. tol 1e-6 N, EigenSparse",
        "axial_damping_time_s": args.axial_damping,
        "sample_period_s": SAMPLE_PERIOD,
        "end_time_s": END_TIME,
        "runs": {},
    }
    for f in freqs:
        scene = Scene(frequency=f)
        table, ex = simulate_servo(scene, args.elements, args.step, args.kp, args.kd,
                                   axial_damping_time=args.axial_damping, feedforward=not args.no_feedforward)
        path = args.out or os.path.join(data_dir, f"servo_f{int(f)}.csv")
        write_csv(path, table)
        meta["runs"][f"f{int(f)}"] = {
            "frequency_Hz": f,
            "rows": int(table.shape[0]),
            "wall_s": ex.pop("wall_s"),
            "n_steps": ex.pop("n_steps"),
            "checks": ex,
            "max_abs_w_mid_m": float(np.abs(table[:, 1:4]).max()),
            "max_abs_slider_error_m": [float(np.abs(table[:, 4 + i]).max()) for i in range(3)],
            "rms_slider_error_m": [float(np.sqrt(np.mean(table[:, 4 + i] ** 2))) for i in range(3)],
            "max_abs_dx_m": float(np.abs(table[:, 7]).max()),
            "max_abs_dy_m": float(np.abs(table[:, 8]).max()),
            "max_abs_dphi_rad": float(np.abs(table[:, 9]).max()),
            "F_range_N": [[float(table[:, 10 + i].min()), float(table[:, 10 + i].max())] for i in range(3)],
        }
        print(json.dumps(meta["runs"][f"f{int(f)}"], indent=1))
    meta["parameters"] = parameters(scene, args)
    if args.out is None:
        with open(os.path.join(data_dir, "servo_meta.json"), "w") as fh:
            json.dump(meta, fh, indent=1)


if __name__ == "__main__":
    main()
