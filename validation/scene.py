"""The paper's 3-PRR scene: parameters, closed-form inverse kinematics and rigid-body
inverse dynamics (docs/model.md sections 1-5).

Shared by the coupled Exudyn model (`exudyn_3prr.py`) and the KED cross-check
(`ked_reference.py`). Pure numpy; SI units throughout.
"""

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Scene:
    """Parameters of the paper's scene (model.md section 2, radial layout of section 1)."""

    youngs_modulus: float = 7.3e10  # Pa (reproduces the paper's Table I frequencies)
    density: float = 2770.0  # kg/m^3
    link_length: float = 0.2  # m
    thickness: float = 0.002  # m, in-plane (bending) dimension
    height: float = 0.03  # m, out-of-plane dimension
    platform_side: float = 0.1  # m
    platform_mass: float = 0.2  # kg
    slider_mass: float = 0.5  # kg (only changes the driving force)
    guide_angles_deg: tuple = (150.0, 270.0, 30.0)
    platform_angle_deg: float = 45.0
    circle_radius: float = 0.05  # m
    frequency: float = 10.0  # Hz
    guide_angles: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "guide_angles", np.radians(np.asarray(self.guide_angles_deg)))

    # --- derived section properties -------------------------------------------------
    @property
    def area(self):
        """Cross-section area t*h (m^2)."""
        return self.thickness * self.height

    @property
    def mass_per_length(self):
        """rhoA (kg/m)."""
        return self.density * self.area

    @property
    def link_mass(self):
        """m = rhoA l (kg)."""
        return self.mass_per_length * self.link_length

    @property
    def bending_stiffness(self):
        """EI = E h t^3 / 12 (N m^2): bending in the plane of motion."""
        return self.youngs_modulus * self.height * self.thickness**3 / 12.0

    @property
    def axial_stiffness(self):
        """EA = E t h (N)."""
        return self.youngs_modulus * self.area

    @property
    def platform_inertia(self):
        """I_p = m_p s^2 / 12 (kg m^2), model.md section 2."""
        return self.platform_mass * self.platform_side**2 / 12.0

    @property
    def platform_radius(self):
        """R_p = s / sqrt(3) (m)."""
        return self.platform_side / np.sqrt(3.0)

    # --- layout ---------------------------------------------------------------------
    def guide_direction(self, i):
        """u_i = (cos a_i, sin a_i)."""
        a = self.guide_angles[i]
        return np.array([np.cos(a), np.sin(a)])

    def guide_normal(self, i):
        """v_i = (-sin a_i, cos a_i)."""
        a = self.guide_angles[i]
        return np.array([-np.sin(a), np.cos(a)])

    def guide_centre(self, i):
        """A_i = (R_p + l) u(a_i + pi)."""
        a = self.guide_angles[i] + np.pi
        return (self.platform_radius + self.link_length) * np.array([np.cos(a), np.sin(a)])

    def platform_point(self, i):
        """c_i = R_p u(a_i + pi), platform frame (phi = 0 at home)."""
        a = self.guide_angles[i] + np.pi
        return self.platform_radius * np.array([np.cos(a), np.sin(a)])

    # --- trajectory -----------------------------------------------------------------
    def platform_pose(self, t):
        """Nominal pose (x, y, phi) and its first and second time derivatives."""
        w = 2.0 * np.pi * self.frequency
        r = self.circle_radius
        c, s = np.cos(w * t), np.sin(w * t)
        phi = np.radians(self.platform_angle_deg)
        pose = np.array([r * c - r, r * s, phi])
        vel = np.array([-r * w * s, r * w * c, 0.0])
        acc = np.array([-r * w * w * c, -r * w * w * s, 0.0])
        return pose, vel, acc


def rotation(phi):
    """2D rotation matrix R(phi)."""
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


def cross2(a, b):
    """z-component of the 2D cross product a x b."""
    return a[0] * b[1] - a[1] * b[0]


@dataclass
class LegKinematics:
    """Rigid kinematics of leg i at one instant (model.md section 3)."""

    rho: float
    rho_d: float
    rho_dd: float
    beta: float
    beta_d: float
    beta_dd: float
    slider_point: np.ndarray  # B_i
    platform_joint: np.ndarray  # C_i
    platform_joint_velocity: np.ndarray
    platform_joint_acceleration: np.ndarray


def leg_kinematics(scene, i, t):
    """Closed-form inverse kinematics of leg i at time t on the scene's trajectory."""
    return pose_leg_kinematics(scene, i, *scene.platform_pose(t), t=t)


def pose_leg_kinematics(scene, i, pose, vel, acc, t=None):
    """Closed-form inverse kinematics of leg i for a platform pose (x, y, phi) with its first and
    second time derivatives (slider behind C_i).

    rho = d.u - sqrt(l^2 - (d x u)^2), d = C - A; rho', rho'' from differentiating
    |C - B|^2 = l^2 once and twice; b' = (C' - rho' u).n / l, b'' = (C'' - rho'' u).n / l.
    Raises ValueError for an unreachable pose (negative discriminant).
    """
    pose, vel, acc = (np.asarray(v, dtype=float) for v in (pose, vel, acc))
    phi, phi_d, phi_dd = pose[2], vel[2], acc[2]
    rc = rotation(phi) @ scene.platform_point(i)
    perp = np.array([-rc[1], rc[0]])
    c_pt = pose[:2] + rc
    c_vel = vel[:2] + phi_d * perp
    c_acc = acc[:2] + phi_dd * perp - phi_d**2 * rc
    u = scene.guide_direction(i)
    a_pt = scene.guide_centre(i)
    l = scene.link_length
    d = c_pt - a_pt
    disc = l * l - cross2(d, u) ** 2
    if disc < 0.0:
        where = f"at t = {t} s" if t is not None else f"(x, y, phi) = ({pose[0]:g} m, {pose[1]:g} m, {pose[2]:g} rad)"
        raise ValueError(f"leg {i + 1}: pose {where} is unreachable (discriminant {disc})")
    rho = d @ u - np.sqrt(disc)
    b_pt = a_pt + rho * u
    chord = c_pt - b_pt
    e = chord / l
    n = np.array([-e[1], e[0]])
    eu = e @ u
    rho_d = (e @ c_vel) / eu
    rel_vel = c_vel - rho_d * u
    rho_dd = (rel_vel @ rel_vel + l * (e @ c_acc)) / (l * eu)
    beta = np.arctan2(e[1], e[0])
    beta_d = (rel_vel @ n) / l
    beta_dd = ((c_acc - rho_dd * u) @ n) / l
    return LegKinematics(rho, rho_d, rho_dd, beta, beta_d, beta_dd, b_pt, c_pt, c_vel, c_acc)


def rigid_inverse_dynamics(scene, t):
    """Rigid-body inverse dynamics (model.md section 4).

    Unknowns: F_Bi (slider on link i) and F_Ci (platform on link i), 12 in all; equations:
    force and moment balance of each link about its centroid, force and moment balance of
    the platform. Returns (legs, F_B (3x2), F_C (3x2), F_a (3,)).
    """
    legs = [leg_kinematics(scene, i, t) for i in range(3)]
    pose, _vel, acc = scene.platform_pose(t)
    m = scene.link_mass
    l = scene.link_length
    j_link = m * l * l / 12.0
    mat = np.zeros((12, 12))
    rhs = np.zeros(12)
    for i, k in enumerate(legs):
        e = np.array([np.cos(k.beta), np.sin(k.beta)])
        n = np.array([-e[1], e[0]])
        u = scene.guide_direction(i)
        a_g = k.rho_dd * u + 0.5 * l * (k.beta_dd * n - k.beta_d**2 * e)
        cb, cc = 4 * i, 4 * i + 2  # columns of F_Bi and F_Ci
        r0 = 3 * i
        # link force balance: F_B + F_C = m a_G
        mat[r0, cb] = mat[r0, cc] = 1.0
        mat[r0 + 1, cb + 1] = mat[r0 + 1, cc + 1] = 1.0
        rhs[r0 : r0 + 2] = m * a_g
        # link moment about centroid: (-l/2 e) x F_B + (l/2 e) x F_C = J b''
        mat[r0 + 2, cb] = 0.5 * l * e[1]
        mat[r0 + 2, cb + 1] = -0.5 * l * e[0]
        mat[r0 + 2, cc] = -0.5 * l * e[1]
        mat[r0 + 2, cc + 1] = 0.5 * l * e[0]
        rhs[r0 + 2] = j_link * k.beta_dd
        # platform: receives -F_Ci at C_i
        arm = k.platform_joint - pose[:2]
        mat[9, cc] = -1.0
        mat[10, cc + 1] = -1.0
        mat[11, cc] = arm[1]
        mat[11, cc + 1] = -arm[0]
    rhs[9] = scene.platform_mass * acc[0]
    rhs[10] = scene.platform_mass * acc[1]
    rhs[11] = scene.platform_inertia * acc[2]
    sol = np.linalg.solve(mat, rhs)
    f_b = np.array([sol[4 * i : 4 * i + 2] for i in range(3)])
    f_c = np.array([sol[4 * i + 2 : 4 * i + 4] for i in range(3)])
    f_a = np.array(
        [scene.slider_mass * legs[i].rho_dd + f_b[i] @ scene.guide_direction(i) for i in range(3)]
    )
    return legs, f_b, f_c, f_a


def axial_force_coefficients(scene, leg, i, f_b, form):
    """P(x) = P0 + P1 x + P2 x^2 in link i (tension positive), model.md section 5.

    form = "joint": P0 = -F_B.e (joint-reaction form);
    form = "paper": P0 = -(F_B.u) cos(b - a) (paper eq. 12, drops F_B.v).
    P1 = rhoA rho'' cos(b - a), P2 = -rhoA b'^2 / 2 in both.
    """
    e = np.array([np.cos(leg.beta), np.sin(leg.beta)])
    cba = np.cos(leg.beta - scene.guide_angles[i])
    if form == "joint":
        p0 = -(f_b @ e)
    elif form == "paper":
        p0 = -(f_b @ scene.guide_direction(i)) * cba
    else:
        raise ValueError(f"unknown axial force form {form!r}")
    rho_a = scene.mass_per_length
    return p0, rho_a * leg.rho_dd * cba, -0.5 * rho_a * leg.beta_d**2


def rest_legs(scene, pose):
    """Rigid inverse kinematics of the three legs at a pose (x, y, phi) at rest."""
    zero = np.zeros(3)
    return [pose_leg_kinematics(scene, i, pose, zero, zero) for i in range(3)]


def slider_velocity_jacobian(scene, pose):
    """Rigid-machine velocities per unit slider rate at a pose, by the closure of model.md
    section 3 and docs/coupled.md: F q' = diag(g_i . u_i) rho', F rows (g_i^T, r_i x g_i),
    g_i = C_i - B_i, r_i = C_i - p. Then per link B' = rho' u, C' = p' + phi' k x r,
    b' = (C' - B') . n / l and the centroid velocity v_G = B' + (l/2) b' n.

    Returns J (15 x 3): rows (slider speeds 1-3; link i: v_Gx, v_Gy, b' for i = 1-3; platform
    x', y', phi'), columns the three slider rates. Raises ValueError at a type-II pose.
    """
    legs = rest_legs(scene, pose)
    p = np.asarray(pose[:2], dtype=float)
    l = scene.link_length
    f_mat = np.zeros((3, 3))
    g_u = np.zeros(3)
    for i, k in enumerate(legs):
        g = k.platform_joint - k.slider_point
        r = k.platform_joint - p
        f_mat[i] = [g[0], g[1], cross2(r, g)]
        g_u[i] = g @ scene.guide_direction(i)
    if abs(np.linalg.det(f_mat)) < 1e-12 * np.linalg.norm(f_mat) ** 3:
        raise ValueError(
            f"pose (x, y, phi) = ({pose[0]:g} m, {pose[1]:g} m, {pose[2]:g} rad) is type-II singular: "
            "the platform is not determined by the sliders"
        )
    jac = np.zeros((15, 3))
    for col in range(3):
        rho_d = np.zeros(3)
        rho_d[col] = 1.0
        q_d = np.linalg.solve(f_mat, g_u * rho_d)
        jac[:3, col] = rho_d
        jac[12:15, col] = q_d
        for i, k in enumerate(legs):
            u = scene.guide_direction(i)
            e = np.array([np.cos(k.beta), np.sin(k.beta)])
            n = np.array([-e[1], e[0]])
            r = k.platform_joint - p
            b_vel = rho_d[i] * u
            c_vel = q_d[:2] + q_d[2] * np.array([-r[1], r[0]])
            beta_d = (c_vel - b_vel) @ n / l
            jac[3 + 3 * i : 5 + 3 * i, col] = b_vel + 0.5 * l * beta_d * n
            jac[5 + 3 * i, col] = beta_d
    return jac


def slider_mass_matrix(scene, pose):
    """Mass matrix of the rigid machine in slider coordinates, M_rho = J^T M J (3 x 3), with J of
    slider_velocity_jacobian and M = diag(m_s (3 sliders); m, m, m l^2/12 (each link, about its
    centroid); m_p, m_p, I_p): the kinetic energy T = rho'^T M_rho rho' / 2 at rest."""
    m = scene.link_mass
    j_link = m * scene.link_length**2 / 12.0
    diag = [scene.slider_mass] * 3 + [m, m, j_link] * 3
    diag += [scene.platform_mass, scene.platform_mass, scene.platform_inertia]
    jac = slider_velocity_jacobian(scene, pose)
    return jac.T @ np.diag(diag) @ jac
