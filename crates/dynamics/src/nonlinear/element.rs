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
//! `(c, s) = (cos beta, sin beta)`, the local deformations are the chord stretch and the end
//! rotations relative to the chord,
//!
//! ```text
//! u = l - L0 = (l^2 - L0^2) / (l + L0),   th1 = psi1 - beta,   th2 = psi2 - beta
//! ```
//!
//! and the element is defined by its strain energy `U(u, th1, th2)` ([`LocalStrain`]):
//!
//! ```text
//! Chord:        U = EA u^2 / (2 L0) + (2 EI / L0)(th1^2 + th1 th2 + th2^2)
//! ShallowArch:  U = EA L0 eps^2 / 2  + (2 EI / L0)(th1^2 + th1 th2 + th2^2),
//!               eps = u / L0 + (2 th1^2 - th1 th2 + 2 th2^2) / 30
//! ```
//!
//! `Chord` is Crisfield's "simplest" element (1991, vol. 1, section 7.3: a linear
//! Euler-Bernoulli beam in the chord frame). `ShallowArch` takes the mean axial strain of the
//! element from the shallow-arch (von Karman) strain `u' + w'^2 / 2` of the cubic transverse
//! displacement `w = L0 (H10 th1 + H11 th2)` in the chord frame (Crisfield 1991, vol. 1,
//! section 7.1 for the shallow arch, chapter 7 for its use as the local strain of a
//! co-rotational element): the axial force then enters the local bending stiffness as the
//! consistent geometric stiffness `N L0 / 30 [4 -1; -1 4]`, which the `Chord` element lacks
//! (it has only the chord's string stiffness `N / l`). With it the Euler load of a pinned
//! strut of `n` elements converges at fourth order (`Chord`: second order); the measured
//! orders are in `tests/nonlinear_statics.rs`.
//!
//! With `N = dU/du`, `M1 = dU/dth1`, `M2 = dU/dth2`, the forces and the tangent are, for both,
//!
//! ```text
//! global forces   f = N r - (M1 + M2) z / l + M1 e3 + M2 e6
//!                 r = (-c, -s, 0, c, s, 0) = dl/dq,   z = (s, -c, 0, -s, c, 0) = l dbeta/dq
//! tangent         K = B^T D B + N z z^T / l + (M1 + M2)(r z^T + z r^T) / l^2   (Crisfield 7.3)
//! ```
//!
//! with `B = d(u, th1, th2)/dq` and `D` the Hessian of `U` in `(u, th1, th2)`. The angle
//! differences `psi - beta` are wrapped into `(-pi, pi]`, so nodal angles may wind freely.

use std::f64::consts::PI;

/// The local strain energy of a [`CorotationalElement`] (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LocalStrain {
    /// Axial strain from the chord stretch alone (Crisfield's simplest element): Euler loads
    /// and large deflections converge at second order in the element length.
    Chord,
    /// The chord stretch plus the mean shallow-arch strain of the element's bending: the
    /// consistent geometric stiffness, fourth-order Euler loads (the default).
    #[default]
    ShallowArch,
}

/// One planar co-rotational Euler-Bernoulli element: reference length, section stiffnesses
/// and local strain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorotationalElement {
    /// Reference (unstretched) length `L0` (m).
    pub length: f64,
    /// Axial stiffness `EA` (N).
    pub axial_stiffness: f64,
    /// Bending stiffness `EI` (N m^2).
    pub bending_stiffness: f64,
    /// The local strain energy.
    pub strain: LocalStrain,
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
    // The usual case first (a local rotation within a half turn: no rounding call); the
    // same result as `a - 2 pi round(a / 2 pi)` wherever `|a| <= pi`.
    if a.abs() <= PI {
        return a;
    }
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
        let mut moments = [k * (2.0 * th1 + th2), k * (th1 + 2.0 * th2)];
        let axial_force = match self.strain {
            LocalStrain::Chord => self.axial_stiffness * stretch / l0,
            LocalStrain::ShallowArch => {
                // N = EA eps; dU/dth adds N L0 deps/dth = N L0 / 30 (4 th1 - th2, 4 th2 - th1).
                let n = self.axial_stiffness * self.strain_of(stretch, th1, th2);
                moments[0] += n * l0 / 30.0 * (4.0 * th1 - th2);
                moments[1] += n * l0 / 30.0 * (4.0 * th2 - th1);
                n
            }
        };
        ElementState {
            chord_length: l,
            direction: [c, s],
            stretch,
            rotations: [th1, th2],
            axial_force,
            moments,
        }
    }

    /// The mean axial strain `eps` of the element for a stretch and end rotations (the chord
    /// strain `u / L0` for [`LocalStrain::Chord`]).
    #[inline]
    pub fn strain_of(&self, stretch: f64, th1: f64, th2: f64) -> f64 {
        let chord = stretch / self.length;
        match self.strain {
            LocalStrain::Chord => chord,
            LocalStrain::ShallowArch => {
                chord + (2.0 * th1 * th1 - th1 * th2 + 2.0 * th2 * th2) / 30.0
            }
        }
    }

    /// Strain energy `U` (J) of a state (module documentation).
    #[inline]
    pub fn strain_energy(&self, st: &ElementState) -> f64 {
        let [t1, t2] = st.rotations;
        let eps = self.strain_of(st.stretch, t1, t2);
        0.5 * self.axial_stiffness * self.length * eps * eps
            + 2.0 * self.bending_stiffness / self.length * (t1 * t1 + t1 * t2 + t2 * t2)
    }

    /// The Hessian `D` of the strain energy in `(u, th1, th2)` at a state.
    fn local_stiffness(&self, st: &ElementState) -> [[f64; 3]; 3] {
        let l0 = self.length;
        let ea = self.axial_stiffness / l0;
        let ei = self.bending_stiffness / l0;
        let mut d = [
            [ea, 0.0, 0.0],
            [0.0, 4.0 * ei, 2.0 * ei],
            [0.0, 2.0 * ei, 4.0 * ei],
        ];
        if self.strain == LocalStrain::ShallowArch {
            // U = EA L0 eps^2 / 2 + bending: D = EA L0 g g^T + N L0 d2eps, with
            // g = d eps / d(u, th1, th2) = (1 / L0, (4 th1 - th2) / 30, (4 th2 - th1) / 30).
            let [t1, t2] = st.rotations;
            let g = [1.0 / l0, (4.0 * t1 - t2) / 30.0, (4.0 * t2 - t1) / 30.0];
            let ea_l = self.axial_stiffness * l0;
            let n_l = st.axial_force * l0 / 30.0;
            let h = [[0.0, 0.0, 0.0], [0.0, 4.0, -1.0], [0.0, -1.0, 4.0]];
            for a in 0..3 {
                for b in 0..3 {
                    let axial = if a == 0 && b == 0 {
                        0.0
                    } else {
                        ea_l * g[a] * g[b]
                    };
                    d[a][b] += axial + n_l * h[a][b];
                }
            }
        }
        d
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

    /// The Kelvin-Voigt damping matrix `C = B^T D_d B` (6x6, symmetric) of the nodal forces
    /// of [`crate::NonlinearSystem`]'s strain-rate damping at `q`: the axial force
    /// `beta_a EA u' / L0` and the end moments `beta_b (2 EI / L0) (2 th1' + th2', th1' + 2 th2')`
    /// are linear in the rates `(u', th1', th2') = B q'`, so `C = df/dq'` exactly (with
    /// `B = d(u, th1, th2)/dq` of [`CorotationalElement::tangent`]).
    pub fn damping_matrix(&self, q: &[f64; 6], beta_a: f64, beta_b: f64) -> [[f64; 6]; 6] {
        let st = self.state(q);
        let b = Self::strain_matrix(&st);
        let ea = beta_a * self.axial_stiffness / self.length;
        let ei = beta_b * 2.0 * self.bending_stiffness / self.length;
        let d = [[ea, 0.0, 0.0], [0.0, 2.0 * ei, ei], [0.0, ei, 2.0 * ei]];
        let mut c = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                let mut v = 0.0;
                for a in 0..3 {
                    for bb in 0..3 {
                        v += b[a][i] * d[a][bb] * b[bb][j];
                    }
                }
                c[i][j] = v;
            }
        }
        c
    }

    /// `B = d(u, th1, th2)/dq` at a state: `du/dq = r`, `dth_k/dq = e_k - z / l`.
    fn strain_matrix(st: &ElementState) -> [[f64; 6]; 3] {
        let [c, s] = st.direction;
        let l = st.chord_length;
        let z = [s, -c, 0.0, -s, c, 0.0];
        let mut b = [[0.0; 6]; 3];
        b[0] = [-c, -s, 0.0, c, s, 0.0];
        for j in 0..6 {
            b[1][j] = -z[j] / l;
            b[2][j] = -z[j] / l;
        }
        b[1][2] += 1.0;
        b[2][5] += 1.0;
        b
    }

    /// Consistent tangent stiffness `K = df/dq` (6x6, symmetric) at `q` (Crisfield 1991,
    /// eq. 7.23 in the notation of this module).
    pub fn tangent(&self, q: &[f64; 6]) -> [[f64; 6]; 6] {
        let st = self.state(q);
        let [c, s] = st.direction;
        let l = st.chord_length;
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
        let d = self.local_stiffness(&st);
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
