"""Whole-machine eigen-analysis of the paper's 3-PRR at rest: an external reference (Exudyn).

The machine of `exudyn_3prr.py` / `exudyn_servo.py` (ANCF cable links, axially elastic, EA = E t h;
free rigid platform pinned at C_i), at rest at a pose: zero velocities, straight unstrained links
along the rigid chords, no gravity (it is normal to the plane), no structural damping. Variants:

* ``locked``: the sliders fixed (node 0 of each link held at B_i by coordinate constraints);
* ``servo``: each slider a body of mass m_s on a prismatic joint along its guide, pinned to the
  link and held by a spring kp along the guide (undamped);
* ``servo_damped``: the same with the damper kd: complex eigenvalues lambda, reported as
  frequency |lambda| / 2 pi and damping ratio -Re(lambda) / |lambda| (MATLAB's ``damp``).

Eigenproblem: Exudyn's ``ComputeODE2Eigenvalues`` with its constraint handling
(``ignoreAlgebraicEquations=False``): M and K (and D) of the ODE2 coordinates are projected on the
null space of the constraint Jacobian (SVD), which is the constrained (index-reduced) linear
problem at rest (no constraint forces, so no geometric stiffness from the multipliers). The same
projection is repeated here from the exported matrices for the eigenvectors, and the two sets of
eigenvalues are compared. Each mode is classified by its kinetic energy (sliders, platform, each
link) and potential energy (servo springs; each link's axial and bending strain energy, from the
nodal displacements with the cable's Hermite shape functions; checked against x^T K x).

Output: data/modes.json. Self-checks (printed and stored in it): a pinned-pinned link and a
slider on its servo spring against closed forms; locked bending modes against the pinned-pinned
frequencies; platform modes against the chords' axial stiffness; servo modes against
kp I vs the rigid machine's mass matrix in slider coordinates (scene.slider_mass_matrix); mesh
convergence 16 / 32 / 64 elements.

Usage:
    python3 exudyn_modes.py                       # all poses, 16, 32 and 64 elements -> data/modes.json
    python3 exudyn_modes.py --pose -0.05 0 45 --elements 16 --out /some/file.json
"""

import argparse
import dataclasses
import json
import os
import time

import exudyn as exu
import numpy as np
from scipy.linalg import eig, eigh, svd

from exudyn_3prr import add_ground, add_link, add_platform, add_platform_pin, add_prescribed_slider, check_elements
from exudyn_collapse import type_ii_measure
from exudyn_servo import KD, KP, add_servo_slider
from scene import Scene, rest_legs, slider_mass_matrix

HERE = os.path.dirname(os.path.abspath(__file__))
POSES = [(0.0, 0.0, 45.0), (-0.05, 0.0, 45.0), (-0.1, 0.0, 45.0), (-0.05, 0.05, 30.0)]
ELEMENTS = (16, 32, 64)
N_MODES = 20
RIGID_FACTOR = 1e3  # E multiplier for the "rigid links" servo check
CHECK_ELEMENTS = 16  # mesh of the stiffened-link checks (better conditioned than finer meshes)
CONSTRAINT_TOLERANCE = 1e-12  # singular values of the constraint Jacobian treated as zero


@dataclasses.dataclass(frozen=True)
class AxiallyStiffScene(Scene):
    """The scene with EA multiplied by axial_factor (EI unchanged): links axially near-rigid."""

    axial_factor: float = 1.0

    @property
    def axial_stiffness(self):
        """EA = axial_factor E t h (N)."""
        return self.axial_factor * self.youngs_modulus * self.area


def build_rest_model(scene, pose_deg, n_elements, variant, kp=KP, kd=KD):
    """The machine at rest at pose (x_m, y_m, phi_deg). variant: "locked", "servo" (spring kp
    only) or "servo_damped" (kp and kd). Returns (mbs, SC, groups) (keep SC alive while mbs is
    used): groups maps "slider_i", "link_i", "platform" to ODE2 coordinate indices, "link_nodes"
    to per-node index lists and "legs" to the rigid leg kinematics."""
    check_elements(n_elements)
    pose = np.array([pose_deg[0], pose_deg[1], np.radians(pose_deg[2])])
    legs = rest_legs(scene, pose)  # raises ValueError for an unreachable pose
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground, ground_coordinate = add_ground(mbs)
    platform_node, platform = add_platform(mbs, scene, pose, np.zeros(3))
    links, sliders = [], []
    for i, leg in enumerate(legs):
        nodes, elements = add_link(mbs, scene, i, leg, n_elements)
        if variant == "locked":
            add_prescribed_slider(mbs, ground_coordinate, nodes[0])
        elif variant in ("servo", "servo_damped"):
            damping = kd if variant == "servo_damped" else 0.0
            sliders.append(add_servo_slider(mbs, scene, i, leg, ground, elements[0], kp, damping)["node"])
        else:
            raise ValueError(f"unknown variant {variant!r} (locked, servo, servo_damped)")
        add_platform_pin(mbs, scene, i, platform, elements[-1])
        links.append(nodes)
    mbs.Assemble()
    groups = {"platform": coordinate_indices(mbs, [platform_node])}
    for i, node in enumerate(sliders):
        groups[f"slider_{i + 1}"] = coordinate_indices(mbs, [node])
    for i, nodes in enumerate(links):
        groups[f"link_{i + 1}"] = coordinate_indices(mbs, nodes)
    groups["link_nodes"] = [[coordinate_indices(mbs, [nd]) for nd in nodes] for nodes in links]
    groups["legs"] = legs
    return mbs, sc, groups


def coordinate_indices(mbs, nodes):
    """Global ODE2 indices of the coordinates of the given nodes."""
    out = []
    for nd in nodes:
        start = mbs.GetNodeODE2Index(nd)
        out.extend(range(start, start + len(mbs.GetNodeOutput(nd, exu.OutputVariableType.Coordinates))))
    return np.array(out)


def system_matrices(mbs):
    """M, K, D (ODE2) and the transposed constraint Jacobian C (ODE2 x AE) at the initial state,
    exported the way ComputeODE2Eigenvalues does (static solver: no integrator factors)."""
    settings = exu.SimulationSettings()
    settings.staticSolver.verboseMode = 0
    settings.solution.file.write = False  # the static solver would write solution/ otherwise
    settings.solution.sensors.active = False
    solver = exu.MainSolverStatic()
    solver.InitializeSolver(mbs, settings)
    n2 = solver.GetODE2size()
    solver.ComputeMassMatrix(mbs)
    mass = np.array(solver.GetSystemMassMatrix())
    solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=-1, scalarFactor_ODE2_t=0, scalarFactor_ODE1=0)
    solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=1.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0,
                             velocityLevel=False)
    jac = np.array(solver.GetSystemJacobian())
    stiffness, constraint = jac[:n2, :n2].copy(), jac[:n2, n2:].copy()
    solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0, scalarFactor_ODE2_t=-1, scalarFactor_ODE1=0)
    damping = np.array(solver.GetSystemJacobian())[:n2, :n2].copy()
    solver.FinalizeSolver(mbs, settings)
    return mass, stiffness, damping, constraint


def null_space(constraint):
    """Orthonormal basis N of the admissible motions (C^T N = 0) by SVD, and the rank facts."""
    u_mat, sing, _vt = svd(constraint)
    rank = int((np.abs(sing) > CONSTRAINT_TOLERANCE).sum())
    info = {
        "constraint_equations": int(constraint.shape[1]),
        "constraint_rank": rank,
        "smallest_nonzero_singular_value": float(sing[rank - 1]) if rank else None,
        "largest_zero_singular_value": float(sing[rank]) if rank < len(sing) else 0.0,
        "degrees_of_freedom": int(constraint.shape[0] - rank),
    }
    return u_mat[:, rank:], info


def solve_modes(mass, stiffness, damping, basis, damped):
    """Eigenvalues and position eigenvectors (full coordinates) of the projected problem, sorted by
    |lambda|; undamped: lambda = i omega. Complex pairs are kept once (Im > 0)."""
    m_r = basis.T @ mass @ basis
    k_r = basis.T @ stiffness @ basis
    k_r = 0.5 * (k_r + k_r.T)
    m_r = 0.5 * (m_r + m_r.T)
    if not damped:
        w2, vec = eigh(k_r, m_r)
        lam = 1j * np.sqrt(np.abs(w2)) * np.sign(w2)
        return lam, basis @ vec
    # first-order form in the undamped modal coordinates, scaled to y = (Omega q_m, q_m'):
    # A = [[0, Omega], [-Omega, -Phi^T D Phi]], a similarity transform of the usual
    # [[0, I], [-M^-1 K, -M^-1 D]] whose entries are all of the size of the frequencies, so the
    # near-degenerate pairs of the symmetric poses keep their digits
    w2, phi = eigh(k_r, m_r)
    omega = np.sqrt(w2)
    d_m = phi.T @ (basis.T @ damping @ basis) @ phi
    n = len(omega)
    state = np.block([[np.zeros((n, n)), np.diag(omega)], [-np.diag(omega), -d_m]])
    lam, vec = eig(state)
    keep = lam.imag >= -1e-9 * np.abs(lam)
    lam, vec = lam[keep], vec[n:, keep] / lam[keep]  # q_m = q_m' / lambda
    order = np.argsort(np.abs(lam))
    return lam[order], basis @ phi @ vec[:, order]


def hermite(xi, le):
    """Cable element shape functions and their first and second x-derivatives at xi in [0, 1]
    (positions r0, slope r0', r1, slope r1')."""
    s = np.array([1 - 3 * xi**2 + 2 * xi**3, le * (xi - 2 * xi**2 + xi**3),
                  3 * xi**2 - 2 * xi**3, le * (-(xi**2) + xi**3)])
    ds = np.array([-6 * xi + 6 * xi**2, le * (1 - 4 * xi + 3 * xi**2),
                   6 * xi - 6 * xi**2, le * (-2 * xi + 3 * xi**2)]) / le
    dds = np.array([-6 + 12 * xi, le * (-4 + 6 * xi), 6 - 12 * xi, le * (-2 + 6 * xi)]) / le**2
    return s, ds, dds


def link_strain_energies(scene, leg, node_idx, x):
    """Axial and bending strain energy (x^H K x / 2 parts) of one link for the displacement vector
    x, linearised about the straight unstrained link: eps = e . dr', kappa = n . dr''."""
    e = np.array([np.cos(leg.beta), np.sin(leg.beta)])
    n = np.array([-e[1], e[0]])
    n_el = len(node_idx) - 1
    le = scene.link_length / n_el
    gauss, weights = np.polynomial.legendre.leggauss(5)
    gauss, weights = 0.5 * (gauss + 1), 0.5 * weights * le
    axial = bending = 0.0
    for j in range(n_el):
        q0, q1 = x[node_idx[j]], x[node_idx[j + 1]]
        dofs = [q0[:2], q0[2:4], q1[:2], q1[2:4]]
        for g, w in zip(gauss, weights):
            _s, ds, dds = hermite(g, le)
            dr1 = sum(c * d for c, d in zip(ds, dofs))
            dr2 = sum(c * d for c, d in zip(dds, dofs))
            axial += 0.5 * w * scene.axial_stiffness * abs(e @ dr1) ** 2
            bending += 0.5 * w * scene.bending_stiffness * abs(n @ dr2) ** 2
    return axial, bending


def half_waves(leg, node_idx, x):
    """Sign changes + 1 of the transverse deflection relative to the line through the link's
    displaced ends (interior nodes; the vector's phase aligned to its largest entry first)."""
    e = np.array([np.cos(leg.beta), np.sin(leg.beta)])
    n = np.array([-e[1], e[0]])
    xr = x * np.exp(-1j * np.angle(x[np.argmax(np.abs(x))]))
    pos = np.array([xr[idx[:2]].real for idx in node_idx])
    s = np.linspace(0.0, 1.0, len(node_idx))
    w = (pos - np.outer(1 - s, pos[0]) - np.outer(s, pos[-1])) @ n
    w = w[1:-1]
    w = w[np.abs(w) > 1e-3 * np.abs(w).max()] if np.abs(w).max() > 0 else w
    return int(np.sum(np.diff(np.sign(w)) != 0) + 1)


def classify(scene, groups, mass, stiffness, kp, lam, x):
    """Energy fractions and a label for one mode (position eigenvector x, full coordinates)."""
    total_t = float(np.real(np.conj(x) @ mass @ x))
    kinetic = {}
    for key in ["platform"] + [f"slider_{i}" for i in (1, 2, 3)] + [f"link_{i}" for i in (1, 2, 3)]:
        if key in groups:
            idx = groups[key]
            kinetic[key] = float(np.real(np.conj(x[idx]) @ mass[np.ix_(idx, idx)] @ x[idx])) / total_t
    if "slider_1" in kinetic:
        kinetic["sliders"] = sum(kinetic.pop(f"slider_{i}") for i in (1, 2, 3))
    potential = {"servo": 0.0}
    for i in range(3):
        if f"slider_{i + 1}" in groups:
            u = scene.guide_direction(i)
            potential["servo"] += 0.5 * kp * abs(x[groups[f"slider_{i + 1}"][:2]] @ u) ** 2
    axial, bending = [], []
    for i in range(3):
        node_idx = groups["link_nodes"][i]
        a, b = link_strain_energies(scene, groups["legs"][i], node_idx, x)
        axial.append(a)
        bending.append(b)
    total_u = potential["servo"] + sum(axial) + sum(bending)
    rayleigh = 0.5 * float(np.real(np.conj(x) @ stiffness @ x))
    potential = {"servo": potential["servo"] / total_u}
    for i in range(3):
        potential[f"axial_{i + 1}"] = axial[i] / total_u
        potential[f"bending_{i + 1}"] = bending[i] / total_u
    servo, ax, be = potential["servo"], sum(axial) / total_u, sum(bending) / total_u
    if servo >= max(ax, be):
        label, link = "servo", None
    elif ax >= be:
        label, link = "platform (axial)", None
    else:
        link = int(np.argmax(bending)) + 1
        label = "bending"
    mode = {
        "frequency_hz": float(abs(lam) / (2 * np.pi)),
        "damping_ratio": float(-lam.real / abs(lam)) if abs(lam) > 0 else 0.0,
        "kind": label,
        "kinetic_fraction": {k: round(v, 4) for k, v in kinetic.items()},
        "potential_fraction": {k: round(v, 4) for k, v in potential.items()},
    }
    if link is not None:
        mode["link"] = link
        mode["half_waves"] = half_waves(groups["legs"][link - 1], groups["link_nodes"][link - 1], x)
    if lam.real != 0.0:
        mode["eigenvalue"] = [float(lam.real), float(lam.imag)]
    return mode, abs(2 * total_u - 2 * rayleigh) / (2 * rayleigh)


def analyse(scene, pose_deg, n_elements, variant, kp=KP, kd=KD, n_modes=N_MODES):
    """Modes of one pose / variant / mesh. Returns a dict with the modes and the checks."""
    t0 = time.time()
    mbs, _sc, groups = build_rest_model(scene, pose_deg, n_elements, variant, kp, kd)
    mass, stiffness, damping, constraint = system_matrices(mbs)
    basis, rank = null_space(constraint)
    damped = variant == "servo_damped"
    lam, vecs = solve_modes(mass, stiffness, damping, basis, damped)
    # Exudyn's own constrained eigen-solver on the same system
    if damped:
        ev, _ = mbs.ComputeODE2Eigenvalues(computeComplexEigenvalues=True, useAbsoluteValues=False,
                                           singularValuesTolerance=CONSTRAINT_TOLERANCE)
        ev = ev[ev.imag >= -1e-9 * np.abs(ev)]
        exu_freq = np.sort(np.abs(ev))[:n_modes] / (2 * np.pi)
    else:
        ev, _ = mbs.ComputeODE2Eigenvalues(singularValuesTolerance=CONSTRAINT_TOLERANCE)
        exu_freq = np.sqrt(np.sort(np.abs(ev))[:n_modes]) / (2 * np.pi)
    # residual of the quadratic eigenproblem (lambda^2 M + lambda D + K) x = 0, projected
    m_r, k_r, d_r = (basis.T @ a @ basis for a in (mass, stiffness, damping if damped else 0 * damping))
    residual = 0.0
    for k in range(n_modes):
        y = basis.T @ vecs[:, k]
        parts = (lam[k] ** 2 * (m_r @ y), lam[k] * (d_r @ y), k_r @ y)
        residual = max(residual, np.linalg.norm(sum(parts)) / sum(np.linalg.norm(p) for p in parts))
    modes, rayleigh = [], 0.0
    for k in range(n_modes):
        mode, err = classify(scene, groups, mass, stiffness, kp, lam[k], vecs[:, k])
        modes.append(mode)
        rayleigh = max(rayleigh, err)
    ours = np.array([m["frequency_hz"] for m in modes])
    # the kinetic-energy split needs M block-diagonal over the groups (bodies share no nodes)
    body = np.full(len(mass), -1)
    bodies = [k for k in groups if k == "platform" or k.startswith("slider_") or k[:5] == "link_" and k[5:].isdigit()]
    for b, key in enumerate(bodies):
        body[groups[key]] = b
    coupled = body[:, None] != body[None, :]
    return {
        "modes": modes,
        "checks": {
            # damped: Exudyn's complex path (-inv(A) B of the unscaled first-order form) loses
            # digits as the mesh grows; the residual below is the accuracy of ours
            "exudyn_ComputeODE2Eigenvalues_max_rel_diff": float(np.max(np.abs(exu_freq - ours) / ours)),
            "eigen_residual_max_rel": float(residual),
            "strain_energy_vs_xKx_max_rel_diff": float(rayleigh),
            "stiffness_asymmetry_rel": float(np.abs(stiffness - stiffness.T).max() / np.abs(stiffness).max()),
            "mass_coupling_between_bodies": float(np.abs(mass[coupled]).max()),
            "ode2_coordinates": int(mass.shape[0]),
            **rank,
        },
        "wall_s": time.time() - t0,
    }


def known_cases(scene):
    """Closed forms through the same projection: a pinned-pinned link; a slider on its spring."""
    out = {}
    # (a) link 1 at the centre pose, both ends held by coordinate constraints
    legs = rest_legs(scene, np.array([0.0, 0.0, np.radians(45.0)]))
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    _g, gc = add_ground(mbs)
    nodes, _el = add_link(mbs, scene, 0, legs[0], 16)
    add_prescribed_slider(mbs, gc, nodes[0])
    add_prescribed_slider(mbs, gc, nodes[-1])
    mbs.Assemble()
    mass, stiffness, damping, constraint = system_matrices(mbs)
    basis, _rank = null_space(constraint)
    lam, _v = solve_modes(mass, stiffness, damping, basis, False)
    f = np.abs(lam[:3]) / (2 * np.pi)
    ev, _ = mbs.ComputeODE2Eigenvalues(constrainedCoordinates=[0, 1, len(mass) - 4, len(mass) - 3],
                                       ignoreAlgebraicEquations=True)
    f_del = np.sqrt(np.abs(ev[:3])) / (2 * np.pi)
    exact = np.array([pinned_pinned(scene, j) for j in (1, 2, 3)])
    out["pinned_pinned_link_16_elements"] = {
        "frequencies_hz": f.tolist(),
        "exact_hz": exact.tolist(),
        "max_rel_error": float(np.max(np.abs(f - exact) / exact)),
        "null_space_vs_deleted_coordinates_max_rel_diff": float(np.max(np.abs(f - f_del) / f_del)),
    }
    # (b) one slider body on its prismatic joint and servo spring-damper (no link)
    for kd in (0.0, KD):
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        ground, _gc = add_ground(mbs)
        add_servo_slider(mbs, scene, 0, legs[0], ground, None, KP, kd)
        mbs.Assemble()
        mass, stiffness, damping, constraint = system_matrices(mbs)
        basis, _rank = null_space(constraint)
        lam, _v = solve_modes(mass, stiffness, damping, basis, kd > 0)
        omega = np.sqrt(KP / scene.slider_mass)
        zeta = kd / (2 * np.sqrt(KP * scene.slider_mass))
        out[f"slider_on_spring_kd{kd:g}"] = {
            "frequency_hz": float(abs(lam[0]) / (2 * np.pi)),
            "damping_ratio": float(-lam[0].real / abs(lam[0])),
            "exact_frequency_hz": float(omega / (2 * np.pi)),
            "exact_damping_ratio": float(zeta),
            "rel_error": float(abs(abs(lam[0]) - omega) / omega),
        }
    return out


def pinned_pinned(scene, j):
    """Pinned-pinned Euler-Bernoulli frequency j (Hz): (j pi)^2 / (2 pi l^2) sqrt(EI / rhoA)."""
    return (j * np.pi) ** 2 / (2 * np.pi * scene.link_length**2) * np.sqrt(scene.bending_stiffness / scene.mass_per_length)


def platform_estimate(scene, pose_deg):
    """Platform modes on the chords' axial springs EA/l: eig(K, M) with K = sum (EA/l) E_i E_i^T,
    E_i = (e_i, r_i x e_i), M = diag(m_p, m_p, I_p) + sum (m/3) E_i E_i^T (each link's axial
    mass, linear axial displacement profile). Hz, ascending."""
    pose = np.array([pose_deg[0], pose_deg[1], np.radians(pose_deg[2])])
    legs = rest_legs(scene, pose)
    k = np.zeros((3, 3))
    m = np.diag([scene.platform_mass, scene.platform_mass, scene.platform_inertia])
    for leg in legs:
        e = np.array([np.cos(leg.beta), np.sin(leg.beta)])
        r = leg.platform_joint - pose[:2]
        big_e = np.array([e[0], e[1], r[0] * e[1] - r[1] * e[0]])
        k += scene.axial_stiffness / scene.link_length * np.outer(big_e, big_e)
        m += scene.link_mass / 3.0 * np.outer(big_e, big_e)
    return np.sqrt(eigh(k, m, eigvals_only=True)) / (2 * np.pi)


def rigid_servo_frequencies(scene, pose_deg, kp=KP):
    """Servo modes of the rigid machine: eig(kp I, M_rho), M_rho = J^T M J (scene.py). Hz."""
    pose = np.array([pose_deg[0], pose_deg[1], np.radians(pose_deg[2])])
    m_rho = slider_mass_matrix(scene, pose)
    return np.sqrt(eigh(kp * np.eye(3), m_rho, eigvals_only=True)) / (2 * np.pi), m_rho


def pose_checks(scene, pose_deg, results):
    """Self-checks of one pose from the finest mesh's modes."""
    finest = str(max(int(k) for k in results["locked"]))
    locked = results["locked"][finest]["modes"]
    exact = [pinned_pinned(scene, j) for j in (1, 2, 3)]
    bend = {}
    for j, fx in enumerate(exact, start=1):
        f = [m["frequency_hz"] for m in locked if m["kind"] == "bending" and m.get("half_waves") == j]
        bend[f"mode_{j}"] = {
            "pinned_pinned_hz": fx,
            "locked_machine_hz": f,
            "rel_deviation": [(x - fx) / fx for x in f],
        }
    plat_est = platform_estimate(scene, pose_deg)
    plat = [m["frequency_hz"] for m in locked if m["kind"] == "platform (axial)"][:3]
    rigid, m_rho = rigid_servo_frequencies(scene, pose_deg)
    servo_flex = [m["frequency_hz"] for m in results["servo"][finest]["modes"] if m["kind"] == "servo"][:3]
    check = str(CHECK_ELEMENTS)
    servo_rigid = [m["frequency_hz"] for m in results["servo_rigid_links"][check]["modes"] if m["kind"] == "servo"][:3]
    stiff = results["locked_axially_stiff"][check]["modes"]
    for j, fx in enumerate(exact, start=1):
        f = [m["frequency_hz"] for m in stiff if m["kind"] == "bending" and m.get("half_waves") == j]
        bend[f"mode_{j}"]["locked_EA_x1000_hz"] = f
        bend[f"mode_{j}"]["locked_EA_x1000_rel_deviation"] = [(x - fx) / fx for x in f]
    return {
        "elements_per_link": int(finest),
        "locked_bending_vs_pinned_pinned": bend,
        "platform_modes_hz": plat,
        "platform_estimate_axial_springs_hz": plat_est.tolist(),
        "platform_rel_deviation": [(a - b) / b for a, b in zip(plat, plat_est)],
        "slider_mass_matrix_kg": m_rho.tolist(),
        "servo_rigid_prediction_hz": rigid.tolist(),
        "servo_links_E_x1000_hz": servo_rigid,
        "servo_links_E_x1000_rel_deviation": [(a - b) / b for a, b in zip(servo_rigid, rigid)],
        "servo_flexible_hz": servo_flex,
        "servo_flexible_rel_deviation": [(a - b) / b for a, b in zip(servo_flex, rigid)],
    }


def mesh_convergence(results, n_low=12):
    """Max relative frequency difference between successive meshes, lowest n_low and all modes."""
    out = {}
    for variant, by_mesh in results.items():
        meshes = sorted(int(k) for k in by_mesh)
        for a, b in zip(meshes, meshes[1:]):
            fa = np.array([m["frequency_hz"] for m in by_mesh[str(a)]["modes"]])
            fb = np.array([m["frequency_hz"] for m in by_mesh[str(b)]["modes"]])
            rel = np.abs(fa - fb) / fb
            out[f"{variant}_{a}_vs_{b}"] = {f"lowest_{n_low}": float(rel[:n_low].max()), f"all_{len(rel)}": float(rel.max())}
    return out


def run_pose(scene, pose_deg, meshes, log):
    """All variants and meshes at one pose, plus the checks."""
    legs = rest_legs(scene, np.array([pose_deg[0], pose_deg[1], np.radians(pose_deg[2])]))
    chords = np.array([[[np.cos(k.beta), np.sin(k.beta)] for k in legs]])
    measure = type_ii_measure(scene, np.array([[pose_deg[0], pose_deg[1], np.radians(pose_deg[2])]]), chords)[0]
    rigid_scene = dataclasses.replace(scene, youngs_modulus=scene.youngs_modulus * RIGID_FACTOR)
    stiff_axial = AxiallyStiffScene(axial_factor=RIGID_FACTOR)
    results = {}
    for variant in ("locked", "servo", "servo_damped"):
        results[variant] = {}
        for ne in meshes:
            results[variant][str(ne)] = analyse(scene, pose_deg, ne, variant)
    # checks: servo with near-rigid links (E x 1000); locked with near-rigid chords (EA x 1000)
    results["servo_rigid_links"] = {str(CHECK_ELEMENTS): analyse(rigid_scene, pose_deg, CHECK_ELEMENTS, "servo")}
    results["locked_axially_stiff"] = {str(CHECK_ELEMENTS): analyse(stiff_axial, pose_deg, CHECK_ELEMENTS, "locked")}
    for variant, by_mesh in results.items():
        for ne, res in by_mesh.items():
            log(f"pose {pose_deg} {variant} {ne} el: {res['wall_s']:.1f} s, "
                f"f = {[round(m['frequency_hz'], 2) for m in res['modes'][:12]]}")
    return {
        "pose": {"x_m": pose_deg[0], "y_m": pose_deg[1], "phi_deg": pose_deg[2]},
        "rho_m": [float(k.rho) for k in legs],
        "type_II_measure": float(measure),
        "variants": results,
        "lowest_12_finest_mesh": {
            variant: [[round(m["frequency_hz"], 3), round(m["damping_ratio"], 4), m["kind"]]
                      for m in results[variant][str(max(meshes))]["modes"][:12]]
            for variant in ("locked", "servo", "servo_damped")
        },
        "mesh_convergence": mesh_convergence({k: results[k] for k in ("locked", "servo", "servo_damped")}),
        "checks": pose_checks(scene, pose_deg, results),
    }


def compact(out):
    """Keep the energy fractions only for the finest mesh of each variant (and the checks), and
    drop fractions below 1e-4: the coarser meshes repeat the same classification."""
    for pose in out["poses"]:
        for by_mesh in pose["variants"].values():
            finest = str(max(int(k) for k in by_mesh))
            for ne, res in by_mesh.items():
                for mode in res["modes"]:
                    if ne != finest:
                        mode.pop("kinetic_fraction", None)
                        mode.pop("potential_fraction", None)
                        continue
                    for key in ("kinetic_fraction", "potential_fraction"):
                        mode[key] = {k: v for k, v in mode[key].items() if v >= 1e-4}
    return no_negative_zero(out)


def no_negative_zero(obj):
    """The same structure with -0.0 (the undamped modes' damping ratio) written as 0.0."""
    if isinstance(obj, dict):
        return {k: no_negative_zero(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [no_negative_zero(v) for v in obj]
    return obj + 0.0 if isinstance(obj, float) else obj


def dumps(out):
    """JSON text with one line per mode (the rest indented)."""
    lines = []
    for pose in out["poses"]:
        for by_mesh in pose["variants"].values():
            for res in by_mesh.values():
                for k, mode in enumerate(res["modes"]):
                    lines.append(json.dumps(mode))
                    res["modes"][k] = f"@@{len(lines) - 1}@@"
    text = json.dumps(out, indent=1)
    for k, line in enumerate(lines):
        text = text.replace(f'"@@{k}@@"', line, 1)
    return text + "\n"


def main(argv=None):
    """Command line entry point."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pose", type=float, nargs=3, action="append", metavar=("X_M", "Y_M", "PHI_DEG"))
    parser.add_argument("--elements", type=int, nargs="*", default=list(ELEMENTS))
    parser.add_argument("--out", default=os.path.join(HERE, "data", "modes.json"))
    args = parser.parse_args(argv)
    scene = Scene()
    t0 = time.time()
    out = {
        "description": "Whole-machine modes at rest (Exudyn ANCF cable links, axially elastic; rigid platform; "
                       "sliders locked or on servo springs); frequencies in Hz, damping ratio -Re(lambda)/|lambda|",
        "exudyn_version": exu.__version__,
        "parameters": {
            "E_Pa": scene.youngs_modulus, "density_kg_m3": scene.density, "link_length_m": scene.link_length,
            "thickness_m": scene.thickness, "height_m": scene.height, "EA_N": scene.axial_stiffness,
            "EI_Nm2": scene.bending_stiffness, "mass_per_length_kg_m": scene.mass_per_length,
            "platform_side_m": scene.platform_side, "platform_mass_kg": scene.platform_mass,
            "platform_inertia_kgm2": scene.platform_inertia, "slider_mass_kg": scene.slider_mass,
            "kp_N_m": KP, "kd_N_s_m": KD, "guide_angles_deg": list(scene.guide_angles_deg),
            "layout": "radial: R_p = s/sqrt(3), c_i = R_p u(a_i + pi), A_i = (R_p + l) u(a_i + pi)",
            "structural_damping": "none", "gravity": "none",
            "rigid_links_check": f"E x {RIGID_FACTOR:g} (EI and EA)",
        },
        "known_cases": known_cases(scene),
        "poses": [],
    }
    print(json.dumps(out["known_cases"], indent=1))
    for pose in args.pose or POSES:
        out["poses"].append(run_pose(scene, tuple(pose), args.elements, print))
        print(json.dumps(out["poses"][-1]["checks"], indent=1))
        print(json.dumps(out["poses"][-1]["mesh_convergence"], indent=1))
    out["wall_s"] = time.time() - t0
    with open(args.out, "w") as fh:
        fh.write(dumps(compact(out)))


if __name__ == "__main__":
    main()
