//! The planar co-rotational Euler-Bernoulli beam element.
//!
//! Source: M. A. Crisfield, *Non-linear Finite Element Analysis of Solids and Structures*,
//! vol. 1 (Wiley, 1991), section 7.3 (the "simplest" co-rotational beam: a linear
//! Euler-Bernoulli element in a frame that follows the chord of the element), and C. A.
//! Felippa, *Nonlinear Finite Element Methods* (lecture notes, University of Colorado), the
//! chapters on the co-rotational description. The rigid motion of each element is removed
//! exactly (any rotation, however large), the deformation inside the element is small when
//! the mesh is fine: the model converges to the geometrically exact (Kirchhoff) rod.
//!
//! Nodal coordinates of an element: `q = (x1, y1, psi1, x2, y2, psi2)` with `psi` the
//! absolute angle of the beam's tangent at the node (the reference, straight element has
//! `psi1 = psi2 = beta0`, its chord angle). With the current chord `l`, `beta`,
//! `(c, s) = (cos beta, sin beta)`:
//!
//! ```text
//! local strains   u = l - L0 = (l^2 - L0^2) / (l + L0),   th1 = psi1 - beta,   th2 = psi2 - beta
//! local forces    N = EA u / L0,   M1 = (2 EI / L0)(2 th1 + th2),   M2 = (2 EI / L0)(th1 + 2 th2)
//! global forces   f = N r - (M1 + M2) z / l + M1 e3 + M2 e6
//!                 r = (-c, -s, 0, c, s, 0) = dl/dq,   z = (s, -c, 0, -s, c, 0) = l dbeta/dq
//! tangent         K = B^T D B + N z z^T / l + (M1 + M2)(r z^T + z r^T) / l^2   (Crisfield 7.3)
//! ```
//!
//! with `B = d(u, th1, th2)/dq` and `D = diag(EA/L0, [4 2; 2 4] EI/L0)`. The angle
//! differences `psi - beta` are wrapped into `(-pi, pi]`, so nodal angles may wind freely.

use std::f64::consts::PI;

/// One planar co-rotational Euler-Bernoulli element: reference length and section
/// stiffnesses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorotationalElement {
    /// Reference (unstretched) length `L0` (m).
    pub length: f64,
    /// Axial stiffness `EA` (N).
    pub axial_stiffness: f64,
    /// Bending stiffness `EI` (N m^2).
    pub bending_stiffness: f64,
}

/// The element's deformation and local forces at one configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementState {
    /// Current chord length `l` (m).
    pub chord_length: f64,
    /// `cos beta`, `sin beta` of the current chord angle.
    pub direction: [f64; 2],
    /// Axial stretch `u = l - L0` (m).
    pub stretch: f64,
    /// Local end rotations `th1, th2` relative to the chord (rad).
    pub rotations: [f64; 2],
    /// Axial force `N` (tension positive, N).
    pub axial_force: f64,
    /// Local end moments `M1, M2` (N m).
    pub moments: [f64; 2],
}

/// `a - 2 pi round(a / (2 pi))`: the angle in `(-pi, pi]` (up to rounding at the ends).
#[inline]
pub(crate) fn wrap_angle(a: f64) -> f64 {
    a - 2.0 * PI * (a / (2.0 * PI)).round()
}

impl CorotationalElement {
    /// Deformation and local forces at nodal coordinates `q = (x1, y1, psi1, x2, y2, psi2)`.
    #[inline]
    pub fn state(&self, q: &[f64; 6]) -> ElementState {
        let (dx, dy) = (q[3] - q[0], q[4] - q[1]);
        let l = dx.hypot(dy);
        let (c, s) = (dx / l, dy / l);
        let l0 = self.length;
        let stretch = (l * l - l0 * l0) / (l + l0);
        // Wrapping keeps psi - beta in (-pi, pi] however far psi has wound.
        let beta = s.atan2(c);
        let th1 = wrap_angle(q[2] - beta);
        let th2 = wrap_angle(q[5] - beta);
        let k = 2.0 * self.bending_stiffness / l0;
        ElementState {
            chord_length: l,
            direction: [c, s],
            stretch,
            rotations: [th1, th2],
            axial_force: self.axial_stiffness * stretch / l0,
            moments: [k * (2.0 * th1 + th2), k * (th1 + 2.0 * th2)],
        }
    }

    /// Global internal force vector `f = B^T (N, M1, M2)` (the gradient of the strain
    /// energy) at `q`, and the state it came from.
    #[inline]
    pub fn internal_force(&self, q: &[f64; 6]) -> ([f64; 6], ElementState) {
        let st = self.state(q);
        (Self::force_from_state(&st), st)
    }

    /// `f = N r - (M1 + M2) z / l + M1 e3 + M2 e6` from a state (the local forces may have
    /// been augmented, e.g. by damping, before the call).
    #[inline]
    pub fn force_from_state(st: &ElementState) -> [f64; 6] {
        let [c, s] = st.direction;
        let n = st.axial_force;
        let [m1, m2] = st.moments;
        let v = (m1 + m2) / st.chord_length;
        [
            -n * c - v * s,
            -n * s + v * c,
            m1,
            n * c + v * s,
            n * s - v * c,
            m2,
        ]
    }

    /// Consistent tangent stiffness `K = df/dq` (6x6, symmetric) at `q` (Crisfield 1991,
    /// eq. 7.23 in the notation of this module).
    pub fn tangent(&self, q: &[f64; 6]) -> [[f64; 6]; 6] {
        let st = self.state(q);
        let [c, s] = st.direction;
        let l = st.chord_length;
        let l0 = self.length;
        let r = [-c, -s, 0.0, c, s, 0.0];
        let z = [s, -c, 0.0, -s, c, 0.0];
        // B rows: du/dq = r (exactly, since d l / d q = r), dth_k/dq = e_k - z / l.
        let mut b = [[0.0; 6]; 3];
        b[0] = r;
        for j in 0..6 {
            b[1][j] = -z[j] / l;
            b[2][j] = -z[j] / l;
        }
        b[1][2] += 1.0;
        b[2][5] += 1.0;
        let ea = self.axial_stiffness / l0;
        let ei = self.bending_stiffness / l0;
        let d = [
            [ea, 0.0, 0.0],
            [0.0, 4.0 * ei, 2.0 * ei],
            [0.0, 2.0 * ei, 4.0 * ei],
        ];
        let n = st.axial_force;
        let msum = st.moments[0] + st.moments[1];
        let mut k = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                let mut v = 0.0;
                for a in 0..3 {
                    for bb in 0..3 {
                        v += b[a][i] * d[a][bb] * b[bb][j];
                    }
                }
                v += n * z[i] * z[j] / l + msum * (r[i] * z[j] + z[i] * r[j]) / (l * l);
                k[i][j] = v;
            }
        }
        k
    }
}
