//! The inertia of a co-rotational element: lumped, or consistent with the element's own
//! centre line.
//!
//! **Consistent** ([`NodalMass::Consistent`]). The kinetic energy is that of the element's
//! centre line, the cubic Hermite curve through its end positions and unit tangents
//! `t = (cos psi, sin psi)` (the curve `NonlinearSystem` reports deflections from):
//!
//! ```text
//! r(xi) = H00(xi) r1 + H10(xi) L t1 + H01(xi) r2 + H11(xi) L t2,   T = rhoA L / 2 int_0^1 |r'(xi)|^2 dxi
//! ```
//!
//! With the four "slots" `P = (r1, L t1, r2, L t2)` the curve is `r = sum_s H_s P_s` and
//! `T = rhoA L / 2 sum_{s,s'} m_ss' P_s' . P_s'` with `m_ss' = int H_s H_s'` (the consistent
//! mass of the Hermite beam element, `[156 22 54 -13; 22 4 13 -3; 54 13 156 -22; -13 -3 -22
//! 4] / 420` in slot units; Archer, "Consistent mass matrix for distributed mass systems",
//! *J. Struct. Div. ASCE* 89 (1963) 161-178). Since `dP/dt = J dq/dt` with `J = diag(I, L n1, I, L n2)` (`n = (-sin psi,
//! cos psi)`), Lagrange's equations give the element's generalized inertia force
//!
//! ```text
//! Q = J^T m (J q'' + kappa),   kappa = (0, -L psi1'^2 t1, 0, -L psi2'^2 t2)
//! ```
//!
//! a mass `M_e = J^T m J` that turns with the nodal tangents (`n1 . n2 = cos(psi1 - psi2)`
//! in the rotation block) and the centripetal terms `kappa`. This is the exact kinetic
//! energy of the interpolated curve, so rigid translations and rigid rotations of any size
//! carry their exact kinetic energy (`m L^2 / 3` about an end) and, with the Hermite
//! stiffness of the element, the bending frequencies converge at fourth order in the element
//! length (the linear Hermite beam's consistent-mass result; whole-machine modes in
//! `crates/linear/tests/modes_validation.rs`). Unlike the usual co-rotational consistent mass (the local
//! mass rotated with the element, the rigid rotation's terms neglected: Crisfield, vol. 2,
//! 1997; Felippa's notes on co-rotational dynamics) nothing is neglected: the curve itself
//! defines the inertia. Like the ANCF cable element of the external model, the
//! section has no rotary inertia (Euler-Bernoulli).
//!
//! **Lumped** ([`NodalMass::Lumped`]): `rhoA L / 2` per node and the rotary inertia
//! `rhoA L^3 / 78` per element end (Hinton, Rock & Zienkiewicz, *Earthquake Eng. Struct.
//! Dyn.* 4 (1976) 245-249): a constant diagonal mass, second order in the bending frequencies.

// Index loops below mirror the formulas (rows and columns of small matrices).
#![allow(clippy::needless_range_loop)]

/// How an element's mass is distributed on its nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NodalMass {
    /// Half the element's mass and a rotary inertia on each node (HRZ lumping): a constant
    /// diagonal mass.
    Lumped,
    /// The kinetic energy of the element's Hermite centre line (module documentation): the
    /// default.
    #[default]
    Consistent,
}

/// `int_0^1 H_s H_s' dxi` for the slots `(r1, L t1, r2, L t2)`.
const HERMITE_MASS: [[f64; 4]; 4] = [
    [13.0 / 35.0, 11.0 / 210.0, 9.0 / 70.0, -13.0 / 420.0],
    [11.0 / 210.0, 1.0 / 105.0, 13.0 / 420.0, -1.0 / 140.0],
    [9.0 / 70.0, 13.0 / 420.0, 13.0 / 35.0, -11.0 / 210.0],
    [-13.0 / 420.0, -1.0 / 140.0, -11.0 / 210.0, 1.0 / 105.0],
];

/// One element's inertia at a configuration `q = (x1, y1, psi1, x2, y2, psi2)` and rates `v`:
/// the mass `M_e` (6x6, symmetric) and the velocity terms `h_e` (the inertia force at zero
/// acceleration), so that the generalized inertia force is `M_e q'' + h_e`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementInertia {
    /// `M_e`.
    pub mass: [[f64; 6]; 6],
    /// `h_e`.
    pub velocity_terms: [f64; 6],
}

/// Derivatives of the inertia force `Q = M_e(q) a + h_e(q, v)` of one element at an
/// acceleration `a`: `dQ/dq` and `dQ/dv` (6x6; only the angle columns are non-zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InertiaDerivatives {
    /// `dQ / dq`.
    pub position: [[f64; 6]; 6],
    /// `dQ / dv`.
    pub velocity: [[f64; 6]; 6],
}

impl NodalMass {
    /// The inertia of an element of mass `m = rhoA L` and length `l` at `(q, v)`.
    #[inline]
    pub fn inertia(self, m: f64, l: f64, q: &[f64; 6], v: &[f64; 6]) -> ElementInertia {
        self.inertia_with_ends(m, l, v, [q[2].sin_cos(), q[5].sin_cos()])
    }

    /// [`NodalMass::inertia`] from `(sin psi, cos psi)` of both end angles `q[2]`, `q[5]`
    /// (the inertia depends on the configuration only through them): the elements of a
    /// chain share their nodes' angles, so one `sin_cos` per node serves two elements.
    #[inline]
    pub fn inertia_with_ends(
        self,
        m: f64,
        l: f64,
        v: &[f64; 6],
        ends: [(f64, f64); 2],
    ) -> ElementInertia {
        match self {
            NodalMass::Lumped => {
                let (half, rot) = (0.5 * m, m * l * l / 78.0);
                let d = [half, half, rot, half, half, rot];
                let mut mass = [[0.0; 6]; 6];
                for (k, row) in mass.iter_mut().enumerate() {
                    row[k] = d[k];
                }
                ElementInertia {
                    mass,
                    velocity_terms: [0.0; 6],
                }
            }
            NodalMass::Consistent => consistent(m, l, v, ends),
        }
    }

    /// `dQ/dq` and `dQ/dv` at acceleration `a` (zero for the lumped mass, which is constant).
    #[inline]
    pub fn derivatives(
        self,
        m: f64,
        l: f64,
        q: &[f64; 6],
        v: &[f64; 6],
        a: &[f64; 6],
    ) -> InertiaDerivatives {
        match self {
            NodalMass::Lumped => InertiaDerivatives {
                position: [[0.0; 6]; 6],
                velocity: [[0.0; 6]; 6],
            },
            NodalMass::Consistent => consistent_derivatives(m, l, q, v, a),
        }
    }
}

/// Tangents `t = (cos psi, sin psi)` and normals `n = (-sin psi, cos psi)` of both ends.
#[inline]
fn frames(q: &[f64; 6]) -> [[[f64; 2]; 2]; 2] {
    frames_of([q[2].sin_cos(), q[5].sin_cos()])
}

/// [`frames`] from `(sin psi, cos psi)` of both ends.
#[inline]
fn frames_of([(s1, c1), (s2, c2)]: [(f64, f64); 2]) -> [[[f64; 2]; 2]; 2] {
    [[[c1, s1], [-s1, c1]], [[c2, s2], [-s2, c2]]]
}

/// The element's coordinates belonging to slot `s`: translations `(0, 1)` / `(3, 4)` for
/// slots 0 and 2, the angle 2 / 5 for slots 1 and 3.
const SLOT_ANGLE: [usize; 2] = [2, 5];

fn consistent(m: f64, l: f64, v: &[f64; 6], ends: [(f64, f64); 2]) -> ElementInertia {
    let [[t1, n1], [t2, n2]] = frames_of(ends);
    let n = [n1, n2];
    let t = [t1, t2];
    // dP/dq for each slot as 2-vectors per element coordinate: J[s] = list of (coordinate,
    // vector).
    let mut mass = [[0.0; 6]; 6];
    // Translation-translation blocks: m_ss' I.
    for (sa, ia) in [(0usize, 0usize), (2, 3)] {
        for (sb, ib) in [(0usize, 0usize), (2, 3)] {
            let w = m * HERMITE_MASS[sa][sb];
            mass[ia][ib] = w;
            mass[ia + 1][ib + 1] = w;
        }
    }
    // Translation-rotation blocks: m_s,s' L n.
    for (sa, ia) in [(0usize, 0usize), (2, 3)] {
        for (k, sb) in [1usize, 3].into_iter().enumerate() {
            let w = m * HERMITE_MASS[sa][sb] * l;
            let j = SLOT_ANGLE[k];
            mass[ia][j] = w * n[k][0];
            mass[ia + 1][j] = w * n[k][1];
            mass[j][ia] = mass[ia][j];
            mass[j][ia + 1] = mass[ia + 1][j];
        }
    }
    // Rotation-rotation block: m L^2 n_a . n_b.
    for (ka, sa) in [1usize, 3].into_iter().enumerate() {
        for (kb, sb) in [1usize, 3].into_iter().enumerate() {
            let dot = n[ka][0] * n[kb][0] + n[ka][1] * n[kb][1];
            mass[SLOT_ANGLE[ka]][SLOT_ANGLE[kb]] = m * HERMITE_MASS[sa][sb] * l * l * dot;
        }
    }
    // Velocity terms: J^T m kappa, kappa in the slots 1, 3: -L psi'^2 t.
    let kappa = [
        [-l * v[2] * v[2] * t[0][0], -l * v[2] * v[2] * t[0][1]],
        [-l * v[5] * v[5] * t[1][0], -l * v[5] * v[5] * t[1][1]],
    ];
    let mut slot_force = [[0.0; 2]; 4];
    for (s, f) in slot_force.iter_mut().enumerate() {
        for (k, sb) in [1usize, 3].into_iter().enumerate() {
            let w = m * HERMITE_MASS[s][sb];
            f[0] += w * kappa[k][0];
            f[1] += w * kappa[k][1];
        }
    }
    let velocity_terms = [
        slot_force[0][0],
        slot_force[0][1],
        l * (n[0][0] * slot_force[1][0] + n[0][1] * slot_force[1][1]),
        slot_force[2][0],
        slot_force[2][1],
        l * (n[1][0] * slot_force[3][0] + n[1][1] * slot_force[3][1]),
    ];
    ElementInertia {
        mass,
        velocity_terms,
    }
}

/// The slot accelerations `P'' = J q'' + kappa` of an element.
fn slot_accelerations(l: f64, q: &[f64; 6], v: &[f64; 6], a: &[f64; 6]) -> [[f64; 2]; 4] {
    let [[t1, n1], [t2, n2]] = frames(q);
    let end = |t: [f64; 2], n: [f64; 2], w: f64, wd: f64| {
        [
            l * (wd * n[0] - w * w * t[0]),
            l * (wd * n[1] - w * w * t[1]),
        ]
    };
    [
        [a[0], a[1]],
        end(t1, n1, v[2], a[2]),
        [a[3], a[4]],
        end(t2, n2, v[5], a[5]),
    ]
}

fn consistent_derivatives(
    m: f64,
    l: f64,
    q: &[f64; 6],
    v: &[f64; 6],
    a: &[f64; 6],
) -> InertiaDerivatives {
    let [[t1, n1], [t2, n2]] = frames(q);
    let (t, n) = ([t1, t2], [n1, n2]);
    let slots = slot_accelerations(l, q, v, a);
    // Slot inertia forces I_s = m sum_s' m_ss' P''_s'.
    let mut forces = [[0.0; 2]; 4];
    for (s, f) in forces.iter_mut().enumerate() {
        for (sb, p) in slots.iter().enumerate() {
            let w = m * HERMITE_MASS[s][sb];
            f[0] += w * p[0];
            f[1] += w * p[1];
        }
    }
    let mut position = [[0.0; 6]; 6];
    let mut velocity = [[0.0; 6]; 6];
    for k in 0..2 {
        let slot = 2 * k + 1;
        let col = SLOT_ANGLE[k];
        let (w, wd) = (v[col], a[col]);
        // dP''_slot / dpsi_k = L (-psi'' t - psi'^2 n), d / dpsi'_k = -2 L psi' t.
        let dp = [
            l * (-wd * t[k][0] - w * w * n[k][0]),
            l * (-wd * t[k][1] - w * w * n[k][1]),
        ];
        let dv = [-2.0 * l * w * t[k][0], -2.0 * l * w * t[k][1]];
        for (matrix, d) in [(&mut position, dp), (&mut velocity, dv)] {
            // dI_s = m m_s,slot d: projected on each generalized force.
            let di: [[f64; 2]; 4] = std::array::from_fn(|s| {
                let c = m * HERMITE_MASS[s][slot];
                [c * d[0], c * d[1]]
            });
            matrix[0][col] += di[0][0];
            matrix[1][col] += di[0][1];
            matrix[3][col] += di[2][0];
            matrix[4][col] += di[2][1];
            matrix[2][col] += l * (n[0][0] * di[1][0] + n[0][1] * di[1][1]);
            matrix[5][col] += l * (n[1][0] * di[3][0] + n[1][1] * di[3][1]);
        }
        // The projection L n_k . I_slot turns with psi_k: d n / d psi = -t.
        position[col][col] -= l * (t[k][0] * forces[slot][0] + t[k][1] * forces[slot][1]);
    }
    InertiaDerivatives { position, velocity }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Q = M q'' + h` against the slot form `J^T m (J q'' + kappa)` and its derivatives
    /// against central differences; the rigid rotation's kinetic energy is exact.
    #[test]
    fn consistent_inertia_is_the_curves_and_its_derivatives_are_exact() {
        let (m, l) = (0.7, 0.05);
        let q = [
            0.1,
            -0.2,
            0.9,
            0.1 + 0.05 * 1.1_f64.cos(),
            -0.2 + 0.05 * 1.1_f64.sin(),
            1.3,
        ];
        let v = [0.3, -1.1, 7.0, -0.4, 0.8, -5.0];
        let a = [10.0, -3.0, 200.0, 4.0, 7.0, -150.0];
        let q_force = |q: &[f64; 6], v: &[f64; 6]| {
            let inertia = NodalMass::Consistent.inertia(m, l, q, v);
            let mut f = inertia.velocity_terms;
            for i in 0..6 {
                for j in 0..6 {
                    f[i] += inertia.mass[i][j] * a[j];
                }
            }
            f
        };
        let d = NodalMass::Consistent.derivatives(m, l, &q, &v, &a);
        let h = 1e-6;
        for j in 0..6 {
            let (mut qp, mut qm, mut vp, mut vm) = (q, q, v, v);
            qp[j] += h;
            qm[j] -= h;
            vp[j] += h;
            vm[j] -= h;
            let (fp, fm) = (q_force(&qp, &v), q_force(&qm, &v));
            let (gp, gm) = (q_force(&q, &vp), q_force(&q, &vm));
            for i in 0..6 {
                let dq = (fp[i] - fm[i]) / (2.0 * h);
                let dv = (gp[i] - gm[i]) / (2.0 * h);
                assert!(
                    (dq - d.position[i][j]).abs() < 1e-6 * (1.0 + dq.abs()),
                    "q {i} {j}: {dq} {}",
                    d.position[i][j]
                );
                assert!(
                    (dv - d.velocity[i][j]).abs() < 1e-6 * (1.0 + dv.abs()),
                    "v {i} {j}: {dv} {}",
                    d.velocity[i][j]
                );
            }
        }
        // A rigid rotation at rate w about node 1 (straight element): T = m L^2 w^2 / 6.
        let (w, b) = (3.0, 0.4_f64);
        let q = [0.0, 0.0, b, l * b.cos(), l * b.sin(), b];
        let v = [0.0, 0.0, w, -l * w * b.sin(), l * w * b.cos(), w];
        let inertia = NodalMass::Consistent.inertia(m, l, &q, &v);
        let mut t = 0.0;
        for i in 0..6 {
            for j in 0..6 {
                t += 0.5 * v[i] * inertia.mass[i][j] * v[j];
            }
        }
        assert!((t - m * l * l * w * w / 6.0).abs() < 1e-14, "{t}");
        // Its centripetal acceleration: node 2 at -w^2 L e, the generalized inertia force of
        // the steady rotation is M a + h with a the rigid accelerations.
        let a = [
            0.0,
            0.0,
            0.0,
            -w * w * l * b.cos(),
            -w * w * l * b.sin(),
            0.0,
        ];
        let mut f = inertia.velocity_terms;
        for i in 0..6 {
            for j in 0..6 {
                f[i] += inertia.mass[i][j] * a[j];
            }
        }
        // The resultant is the mass times the centre's acceleration -w^2 (L/2) e.
        let (fx, fy) = (f[0] + f[3], f[1] + f[4]);
        assert!((fx + m * w * w * 0.5 * l * b.cos()).abs() < 1e-12, "{fx}");
        assert!((fy + m * w * w * 0.5 * l * b.sin()).abs() < 1e-12, "{fy}");
    }
}
