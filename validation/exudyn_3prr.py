"""Fully coupled flexible-multibody reference model of the paper's 3-PRR (docs/model.md section 8).

Built with Exudyn (2D ANCF cable elements, index-3 constraints, implicit time integration):

* each link: `n_elements` ObjectANCFCable2D elements, axially elastic (EA = E t h), bending
  stiffness EI = E h t^3 / 12 (in-plane bending), mass per length rhoA = density t h;
* slider i: the first node of link i is a point whose position is prescribed along guide i,
  B_i(t) = A_i + rho_i(t) u_i (rho_i from the closed-form inverse kinematics), by two coordinate
  constraints on its x and y coordinates (position coupling only: a revolute joint at B_i);
* platform: a free rigid body (NodeRigidBody2D), pinned at C_i to the last node of each link by
  ObjectJointRevolute2D (position coupling only);
* initial state: the rigid inverse-kinematics solution at t = 0 (straight links with the rigid
  velocity field B' + x b' n, platform at the nominal pose with the nominal velocity); no
  gravity (it is normal to the plane), no physical damping.

Outputs (one CSV per frequency, sampled every 2.5e-4 s, 0-0.2 s; see README.md for columns).

Usage:
    python3 exudyn_3prr.py                        # production runs f = 10 and 20 Hz -> data/
    python3 exudyn_3prr.py --convergence          # mesh and step convergence study
    python3 exudyn_3prr.py --freq 20 --elements 16 --step 1.25e-5 --out /some/file.csv
"""

import argparse
import json
import os
import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    MarkerBodyPosition,
    MarkerNodeCoordinate,
    NodePoint2DSlope1,
    NodePointGround,
    NodeRigidBody2D,
    ObjectANCFCable2D,
    ObjectConnectorCoordinate,
    ObjectGround,
    ObjectJointRevolute2D,
    ObjectRigidBody2D,
    SensorBody,
    SensorNode,
    SensorObject,
)

from scene import Scene, leg_kinematics

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLE_PERIOD = 2.5e-4  # s
END_TIME = 0.2  # s
# Axial damping d = beta EA (beta in s) on the axial strain rate only: removes the undamped
# ringing of the ~1.9 kHz axial (platform bounce) mode that the rigid initial state (zero axial
# strain under non-zero inverse-dynamics axial forces) excites; see README.md.
AXIAL_DAMPING_TIME = 8e-6

COLUMNS = (
    ["t_s"]
    + [f"w_mid_{i}_m" for i in (1, 2, 3)]
    + ["dx_m", "dy_m", "dphi_rad"]
    + [f"P_B_{i}_N" for i in (1, 2, 3)]
    + [f"P_C_{i}_N" for i in (1, 2, 3)]
    + [f"rho_{i}_m" for i in (1, 2, 3)]
)


class SliderPath:
    """Prescribed slider point B_i(t) (and its velocity), cached per time value."""

    def __init__(self, scene, i):
        self.scene = scene
        self.i = i
        self._t = None
        self._val = None

    def _eval(self, t):
        if self._t is None or t != self._t:
            k = leg_kinematics(self.scene, self.i, t)
            u = self.scene.guide_direction(self.i)
            self._val = (k.slider_point, k.rho_d * u)
            self._t = t
        return self._val

    def position(self, t):
        """B_i(t)."""
        return self._eval(t)[0]

    def velocity(self, t):
        """B_i'(t) = rho_i'(t) u_i."""
        return self._eval(t)[1]


def add_ground(mbs):
    """Ground object and a ground coordinate marker (for coordinate constraints)."""
    ground = mbs.AddObject(ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    ground_node = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    ground_coordinate = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    return ground, ground_coordinate


def add_platform(mbs, scene, pose, vel):
    """The free rigid platform (m_p, I_p) at pose (x, y, phi) with velocity vel. Returns (node, body)."""
    node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=list(pose), initialVelocities=list(vel)))
    body = mbs.AddObject(
        ObjectRigidBody2D(nodeNumber=node, mass=scene.platform_mass, inertia=scene.platform_inertia)
    )
    return node, body


def add_link(mbs, scene, i, leg, n_elements, axial_damping_time=0.0):
    """Link i as n_elements ANCF cable elements, straight and unstrained along the rigid chord
    of `leg` (scene.LegKinematics), with the rigid velocity field B' + x b' n (nodal slope
    rates b' n). Returns (nodes, elements).

    axial_damping_time beta (s): axial damping d = beta EA of the cable elements (stiffness
    proportional, on the axial strain rate only; bending is undamped). 0 = no damping.
    """
    le = scene.link_length / n_elements
    e = np.array([np.cos(leg.beta), np.sin(leg.beta)])
    n = np.array([-e[1], e[0]])
    u = scene.guide_direction(i)
    nodes = []
    for j in range(n_elements + 1):
        x = j * le
        pos = leg.slider_point + x * e
        vel = leg.rho_d * u + x * leg.beta_d * n
        slope_vel = leg.beta_d * n
        nodes.append(
            mbs.AddNode(
                NodePoint2DSlope1(
                    referenceCoordinates=[pos[0], pos[1], e[0], e[1]],
                    initialCoordinates=[0.0, 0.0, 0.0, 0.0],
                    initialVelocities=[vel[0], vel[1], slope_vel[0], slope_vel[1]],
                )
            )
        )
    elements = [
        mbs.AddObject(
            ObjectANCFCable2D(
                length=le,
                massPerLength=scene.mass_per_length,
                bendingStiffness=scene.bending_stiffness,
                axialStiffness=scene.axial_stiffness,
                axialDamping=axial_damping_time * scene.axial_stiffness,
                nodeNumbers=[nodes[j], nodes[j + 1]],
            )
        )
        for j in range(n_elements)
    ]
    return nodes, elements


def add_prescribed_slider(mbs, ground_coordinate, node, path=None, b_ref=None):
    """Coordinate constraints on the x and y coordinates of `node` (a link's first node).

    With a SliderPath, the node follows B_i(t) - B_i(0) (offset user functions; b_ref = B_i(0),
    the node's reference position); without, it is held at its reference position (locked
    slider). Position coupling only: a revolute joint at B_i. Returns the two constraints.
    """
    constraints = []
    for c in (0, 1):
        node_coordinate = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=c))
        if path is None:
            constraints.append(
                mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ground_coordinate, node_coordinate]))
            )
            continue

        def offset(mbs_, t, item, l_off, c=c, path=path, b_ref=b_ref):
            return path.position(t)[c] - b_ref[c]

        def offset_t(mbs_, t, item, l_off, c=c, path=path):
            return path.velocity(t)[c]

        constraints.append(
            mbs.AddObject(
                ObjectConnectorCoordinate(
                    markerNumbers=[ground_coordinate, node_coordinate],
                    offsetUserFunction=offset,
                    offsetUserFunction_t=offset_t,
                )
            )
        )
    return constraints


def add_platform_pin(mbs, scene, i, platform, last_element):
    """Revolute joint (position coupling) between the link's end (x = l_e of its last element)
    and the platform point c_i. The joint's reaction acts on marker 0, the platform."""
    le = mbs.GetObjectParameter(last_element, "length")
    c_loc = scene.platform_point(i)
    link_end = mbs.AddMarker(MarkerBodyPosition(bodyNumber=last_element, localPosition=[le, 0.0, 0.0]))
    platform_pt = mbs.AddMarker(
        MarkerBodyPosition(bodyNumber=platform, localPosition=[c_loc[0], c_loc[1], 0.0])
    )
    return mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[platform_pt, link_end]))


def check_elements(n_elements):
    """Elements per link must be even (a node at the mid-point) and at least 2."""
    if n_elements < 2 or n_elements % 2:
        raise ValueError(f"elements per link must be even and >= 2 (mid-point node), got {n_elements}")


def build_model(scene, n_elements, axial_damping_time=0.0):
    """Create the Exudyn system. Returns (SC, mbs, handles) with the items needed for output.

    axial_damping_time beta (s): see add_link.
    """
    check_elements(n_elements)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    _ground, ground_coordinate = add_ground(mbs)
    pose0, vel0, _acc0 = scene.platform_pose(0.0)
    platform_node, platform = add_platform(mbs, scene, pose0, vel0)
    handles = {"platform_node": platform_node, "links": [], "paths": []}
    for i in range(3):
        k = leg_kinematics(scene, i, 0.0)
        nodes, elements = add_link(mbs, scene, i, k, n_elements, axial_damping_time)
        # slider: node coordinates (displacements from the reference B_i(0)) follow B_i(t) - B_i(0)
        path = SliderPath(scene, i)
        slider_constraints = add_prescribed_slider(mbs, ground_coordinate, nodes[0], path, k.slider_point.copy())
        platform_joint = add_platform_pin(mbs, scene, i, platform, elements[-1])
        handles["paths"].append(path)
        handles["links"].append(
            {
                "nodes": nodes,
                "elements": elements,
                "slider_constraints": slider_constraints,
                "platform_joint": platform_joint,
            }
        )
    mbs.Assemble()
    return sc, mbs, handles


def add_sensors(mbs, handles, n_elements):
    """Sensors (stored in memory) for node positions, platform pose and joint reactions."""
    s = {"platform": mbs.AddSensor(
        SensorNode(nodeNumber=handles["platform_node"], storeInternal=True, writeToFile=False,
                   outputVariableType=exu.OutputVariableType.Coordinates))}
    s["platform_acc"] = mbs.AddSensor(
        SensorNode(nodeNumber=handles["platform_node"], storeInternal=True, writeToFile=False,
                   outputVariableType=exu.OutputVariableType.Coordinates_tt))
    mid_node = n_elements // 2  # material point x = l/2 (n_elements is even)
    for i, link in enumerate(handles["links"]):
        for key, node in (("B", link["nodes"][0]), ("M", link["nodes"][mid_node]), ("C", link["nodes"][-1])):
            s[f"{key}{i}"] = mbs.AddSensor(
                SensorNode(nodeNumber=node, storeInternal=True, writeToFile=False,
                           outputVariableType=exu.OutputVariableType.Position))
        for c, obj in enumerate(link["slider_constraints"]):
            s[f"FB{i}{c}"] = mbs.AddSensor(
                SensorObject(objectNumber=obj, storeInternal=True, writeToFile=False,
                             outputVariableType=exu.OutputVariableType.Force))
        s[f"FC{i}"] = mbs.AddSensor(
            SensorObject(objectNumber=link["platform_joint"], storeInternal=True, writeToFile=False,
                         outputVariableType=exu.OutputVariableType.Force))
        # axial force EA*eps from the ANCF strain at the two link ends (cross-check)
        for key, elem, xloc in (("NB", link["elements"][0], 0.0), ("NC", link["elements"][-1], 1.0)):
            le = mbs.GetObjectParameter(elem, "length")
            s[f"{key}{i}"] = mbs.AddSensor(
                SensorBody(bodyNumber=elem, localPosition=[xloc * le, 0.0, 0.0], storeInternal=True,
                           writeToFile=False, outputVariableType=exu.OutputVariableType.ForceLocal))
    return s


def solver_settings(end_time, step, spectral_radius=0.98, solver="alpha", verbose=False):
    """Exudyn simulation settings of the production runs: fixed step, Newton with the Jacobian
    updated every step, sparse solver, sensors sampled every SAMPLE_PERIOD, no files written.
    Returns (settings, solver type)."""
    settings = exu.SimulationSettings()
    ti = settings.timeIntegration
    ti.startTime = 0.0
    ti.endTime = end_time
    ti.numberOfSteps = int(round(end_time / step))
    ti.verboseMode = 1 if verbose else 0
    # Newton with the Jacobian updated every step. The residual has a round-off floor of
    # ~1e-8..1e-7 (forces in N, set by EA/l_e up to 7e8 N/m at 32 elements): the absolute
    # goal 1e-6 N sits just above it; a tighter goal stalls (and fails) at the floor
    ti.newton.useModifiedNewton = True
    ti.newton.modifiedNewtonJacUpdatePerStep = True
    ti.newton.relativeTolerance = 1e-8
    ti.newton.absoluteTolerance = 1e-6
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    ti.adaptiveStep = False
    ti.generalizedAlpha.computeInitialAccelerations = True
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = SAMPLE_PERIOD
    settings.show.statistics = False
    settings.show.computationTime = False
    if solver == "alpha":
        ti.generalizedAlpha.spectralRadius = spectral_radius
        solver_type = exu.DynamicSolverType.GeneralizedAlpha
    elif solver == "trapezoidal":
        solver_type = exu.DynamicSolverType.TrapezoidalIndex2
    else:
        raise ValueError(f"unknown solver {solver!r}")
    return settings, solver_type


def sample_rows(t):
    """Indices of the stored sensor rows on the SAMPLE_PERIOD grid (first row per grid point)."""
    grid = np.round(t / SAMPLE_PERIOD)
    keep = np.abs(t - grid * SAMPLE_PERIOD) < 1e-9
    _, first = np.unique(grid[keep], return_index=True)
    return np.nonzero(keep)[0][first]


def chord_frame(b, c):
    """Unit chord e (B -> C), its normal n = (-e_y, e_x) and the chord length, row-wise."""
    chord = c - b
    chord_len = np.linalg.norm(chord, axis=1)
    e = chord / chord_len[:, None]
    n = np.stack([-e[:, 1], e[:, 0]], axis=1)
    return e, n, chord_len


def simulate(scene, n_elements, step, spectral_radius=0.98, solver="alpha", verbose=False,
             axial_damping_time=0.0, end_time=END_TIME, allow_failure=False):
    """Run the coupled model from 0 to end_time. Returns (table (rows x COLUMNS), extras dict).

    allow_failure: when the solver stops early (Newton failure near a collapse), keep the data
    up to that time (extras["solver_ok"] is False) instead of raising.
    """
    sc, mbs, handles = build_model(scene, n_elements, axial_damping_time)
    sensors = add_sensors(mbs, handles, n_elements)
    settings, solver_type = solver_settings(end_time, step, spectral_radius, solver, verbose)
    n_steps = settings.timeIntegration.numberOfSteps
    t0 = time.time()
    ok = mbs.SolveDynamic(settings, solverType=solver_type, showHints=verbose)
    wall = time.time() - t0
    if not ok and not allow_failure:
        raise RuntimeError(f"Exudyn failed: f = {scene.frequency} Hz, {n_elements} elements, h = {step}")
    table, extras = collect(scene, mbs, sensors)
    extras["wall_s"] = wall
    extras["n_steps"] = n_steps
    extras["solver_ok"] = bool(ok)
    return table, extras


def collect(scene, mbs, sensors):
    """Turn the stored sensor data into the output columns (see README.md)."""
    def data(key):
        return mbs.GetSensorStoredData(sensors[key])

    plat = data("platform")
    idx = sample_rows(plat[:, 0])
    t = plat[idx, 0]
    n_rows = len(t)
    out = np.zeros((n_rows, len(COLUMNS)))
    out[:, 0] = t
    pose0, _v, _a = scene.platform_pose(0.0)
    nominal = np.array([scene.platform_pose(tn)[0] for tn in t])
    pose = pose0 + plat[idx, 1:4]
    out[:, 4:7] = pose - nominal
    extras = {"P_B_strain_N": np.zeros((n_rows, 3)), "P_C_strain_N": np.zeros((n_rows, 3))}
    for i in range(3):
        b = data(f"B{i}")[idx, 1:3]
        m = data(f"M{i}")[idx, 1:3]
        c = data(f"C{i}")[idx, 1:3]
        e, n, chord_len = chord_frame(b, c)
        out[:, 1 + i] = np.sum((m - b) * n, axis=1)
        # slider constraints: Lagrange multiplier lambda of g = q_node - offset; the force
        # of the slider on the link node is -lambda (sign confirmed by the independent axial
        # force EA*eps of the first element, meta.json rms_P_B_strain_minus_reaction_N)
        f_b = -np.stack([data(f"FB{i}0")[idx, 1], data(f"FB{i}1")[idx, 1]], axis=1)
        out[:, 7 + i] = -np.sum(f_b * e, axis=1)
        # revolute joint [platform marker, link marker]: the reported force acts on marker 0
        # (the platform), so the force of the platform on the link is its negative (sign
        # confirmed by the platform's momentum balance, see check_platform_balance)
        f_c = -data(f"FC{i}")[idx, 1:3]
        out[:, 10 + i] = np.sum(f_c * e, axis=1)
        u = scene.guide_direction(i)
        out[:, 13 + i] = (b - scene.guide_centre(i)) @ u
        extras["P_B_strain_N"][:, i] = data(f"NB{i}")[idx, 1]
        extras["P_C_strain_N"][:, i] = data(f"NC{i}")[idx, 1]
        extras.setdefault("chord_length_m", np.zeros((n_rows, 3)))[:, i] = chord_len
        extras.setdefault("F_C_N", np.zeros((n_rows, 3, 2)))[:, i, :] = f_c
    extras["platform_pose"] = pose
    extras["platform_acc"] = data("platform_acc")[idx, 1:4]
    return out, extras


def check_platform_balance(scene, table, extras):
    """Momentum balance of the platform: m_p p'' = -sum_i F_Ci, I_p phi'' = -sum_i (C_i - p) x F_Ci.

    F_Ci = force of the platform on link i (from the revolute-joint reaction), p'' and phi''
    from the solver's accelerations. Returns the relative RMS residual of the force balance;
    it fixes the sign convention of the joint reaction (a wrong sign gives ~2).
    """
    acc = extras["platform_acc"]
    force = -extras["F_C_N"].sum(axis=1)
    res = scene.platform_mass * acc[:, :2] - force
    return float(np.sqrt(np.mean(res**2)) / np.sqrt(np.mean(force**2)))


def write_csv(path, table):
    """Write the output table with a header row."""
    np.savetxt(path, table, delimiter=",", header=",".join(COLUMNS), comments="", fmt="%.6e")


def rel_l2(a, b):
    """||a - b|| / ||b||."""
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def convergence(freqs, log, axial_damping_time):
    """Mesh (8/16/32 elements), step (5e-5 ... 6.25e-6 s) and integrator study.

    Reference: 16 elements, h = 6.25e-6 s, generalized-alpha rho_inf = 0.98. Each entry gives
    the relative L2 difference ||a - ref|| / ||ref|| over all samples and links of the
    mid-point deflections, the platform position deviation and the axial forces.
    """
    cases = [
        (8, 2.5e-5, "alpha", 0.98),
        (16, 2.5e-5, "alpha", 0.98),
        (32, 2.5e-5, "alpha", 0.98),
        (16, 5e-5, "alpha", 0.98),
        (16, 1.25e-5, "alpha", 0.98),
        (16, 6.25e-6, "alpha", 0.98),
        (16, 1.25e-5, "alpha", 0.9),
        (16, 1.25e-5, "trapezoidal", 1.0),
    ]
    ref_case = (16, 6.25e-6, "alpha", 0.98)
    results = {}
    for f in freqs:
        scene = Scene(frequency=f)
        runs = {}
        for case in cases:
            ne, h, solver, rho_inf = case
            table, ex = simulate(scene, ne, h, rho_inf, solver, axial_damping_time=axial_damping_time)
            runs[case] = table
            log(f"f={f} {case}: wall {ex['wall_s']:.1f} s, max|w| {np.abs(table[:, 1:4]).max():.4e}")
        ref = runs[ref_case]
        res = {
            "reference_case": "16 elements, h = 6.25e-6 s, generalized-alpha rho_inf = 0.98",
            "axial_damping_time_s": axial_damping_time,
        }
        for case, table in runs.items():
            ne, h, solver, rho_inf = case
            res[f"ne{ne}_h{h:.3g}_{solver}{rho_inf:g}"] = {
                "w_mid": rel_l2(table[:, 1:4], ref[:, 1:4]),
                "platform_xy_deviation": rel_l2(table[:, 4:6], ref[:, 4:6]),
                "platform_dphi": rel_l2(table[:, 6], ref[:, 6]),
                "P_B": rel_l2(table[:, 7:10], ref[:, 7:10]),
                "P_C": rel_l2(table[:, 10:13], ref[:, 10:13]),
            }
        # pure mesh differences at a common step
        for ne in (8, 32):
            a, b = runs[(ne, 2.5e-5, "alpha", 0.98)], runs[(16, 2.5e-5, "alpha", 0.98)]
            res[f"mesh_{ne}_vs_16_at_h2.5e-5"] = {
                "w_mid": rel_l2(a[:, 1:4], b[:, 1:4]),
                "platform_xy_deviation": rel_l2(a[:, 4:6], b[:, 4:6]),
                "P_B": rel_l2(a[:, 7:10], b[:, 7:10]),
            }
        results[f"f{int(f)}"] = res
        log(json.dumps(res, indent=1))
    return results


def main(argv=None):
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--freq", type=float, nargs="*", default=[10.0, 20.0])
    parser.add_argument("--elements", type=int, default=16)
    parser.add_argument("--step", type=float, default=6.25e-6)
    parser.add_argument("--spectral-radius", type=float, default=0.98)
    parser.add_argument("--solver", choices=["alpha", "trapezoidal"], default="alpha")
    parser.add_argument("--out", default=None, help="CSV path (single frequency only)")
    parser.add_argument("--convergence", action="store_true")
    parser.add_argument(
        "--axial-damping",
        type=float,
        default=AXIAL_DAMPING_TIME,
        help="beta (s) of the axial damping d = beta EA (0: undamped)",
    )
    args = parser.parse_args(argv)
    data_dir = os.path.join(HERE, "data")
    os.makedirs(data_dir, exist_ok=True)

    if args.convergence:
        res = convergence(args.freq, print, args.axial_damping)
        name = "convergence.json" if args.axial_damping > 0.0 else "convergence_undamped.json"
        with open(os.path.join(data_dir, name), "w") as fh:
            json.dump(res, fh, indent=1)
        return

    meta = {
        "model": "Exudyn 2D ANCF cable links, prescribed sliders, free rigid platform, revolute joints",
        "exudyn_version": exu.__version__,
        "numpy_version": np.__version__,
        "elements_per_link": args.elements,
        "step_s": args.step,
        "solver": "generalized-alpha (index 3)" if args.solver == "alpha" else "trapezoidal (index 2)",
        "spectral_radius": args.spectral_radius if args.solver == "alpha" else 1.0,
        "axial_damping_time_s": args.axial_damping,
        "axial_damping": "d = beta EA on the axial strain rate only (bending undamped); zeta ~ beta omega / 2 ~ 0.05 at the 1.9 kHz axial (platform bounce) mode",
        "sample_period_s": SAMPLE_PERIOD,
        "end_time_s": END_TIME,
        "runs": {},
    }
    for f in args.freq:
        scene = Scene(frequency=f)
        table, ex = simulate(
            scene, args.elements, args.step, args.spectral_radius, args.solver,
            axial_damping_time=args.axial_damping,
        )
        path = args.out or os.path.join(data_dir, f"coupled_f{int(f)}.csv")
        write_csv(path, table)
        bal = check_platform_balance(scene, table, ex)
        acc_nom = np.array([scene.platform_pose(tn)[2][:2] for tn in table[:, 0]])
        acc_dev = ex["platform_acc"][:, :2] - acc_nom
        strain_diff_b = float(np.sqrt(np.mean((ex["P_B_strain_N"] - table[:, 7:10]) ** 2)))
        strain_diff_c = float(np.sqrt(np.mean((ex["P_C_strain_N"] - table[:, 10:13]) ** 2)))
        meta["runs"][f"f{int(f)}"] = {
            "frequency_Hz": f,
            "rows": int(table.shape[0]),
            "wall_s": ex["wall_s"],
            "platform_momentum_residual_rel_rms": bal,
            "rms_P_B_strain_minus_reaction_N": strain_diff_b,
            "rms_P_C_strain_minus_reaction_N": strain_diff_c,
            "max_abs_w_mid_m": float(np.abs(table[:, 1:4]).max()),
            "max_abs_dx_m": float(np.abs(table[:, 4]).max()),
            "max_abs_dy_m": float(np.abs(table[:, 5]).max()),
            "max_abs_dphi_rad": float(np.abs(table[:, 6]).max()),
            "P_B_range_N": [[float(table[:, 7 + i].min()), float(table[:, 7 + i].max())] for i in range(3)],
            "P_C_range_N": [[float(table[:, 10 + i].min()), float(table[:, 10 + i].max())] for i in range(3)],
            "max_abs_chord_shortening_m": float(np.abs(ex["chord_length_m"] - scene.link_length).max()),
            "rms_platform_acc_deviation_m_s2": float(np.sqrt(np.mean(np.sum(acc_dev**2, axis=1)))),
            "rms_platform_acc_nominal_m_s2": float(np.sqrt(np.mean(np.sum(acc_nom**2, axis=1)))),
        }
        print(json.dumps(meta["runs"][f"f{int(f)}"], indent=1))
    meta["parameters"] = {
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
        "guide_angles_deg": list(scene.guide_angles_deg),
        "phi_deg": scene.platform_angle_deg,
        "layout": "radial: R_p = s/sqrt(3), c_i = R_p u(a_i + pi), A_i = (R_p + l) u(a_i + pi)",
        "trajectory": "x = 0.05 cos(2 pi f t) - 0.05, y = 0.05 sin(2 pi f t), phi = 45 deg",
        "gravity": "none (normal to the plane)",
        "damping": "bending undamped; axial damping d = beta EA, see axial_damping_time_s",
    }
    if args.out is None:
        with open(os.path.join(data_dir, "meta.json"), "w") as fh:
            json.dump(meta, fh, indent=1)


if __name__ == "__main__":
    main()
