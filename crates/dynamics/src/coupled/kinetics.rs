//! The rigid kinematics of one evaluation and its linear-in-`eta''` pieces: platform pose by
//! the closure with the shortened chords, chord angles, and the chord tensions from the
//! platform's Newton-Euler equations (docs/coupled.md, "Derivation").

use flexprr_kinematics::{MachineKinematics, PlatformMotion, Pose};
use nalgebra::{Matrix3, Vector2, Vector3};

use super::{CoupledSystem, FORWARD_ITERATIONS, cross, dot};
use crate::DynamicsError;

/// Linear-in-acceleration pieces of one evaluation: `b'' = beta0 + Bs s + Br r`,
/// `T = tension0 + Ts s + Tm m + Tr r` and the link moments over the chord lengths
/// `S = moment0 + Ss s + Sr r (+ (l / L) m)`, with `s_j = dL_j . eta_j''`,
/// `m_j = m_xipsi_j . eta_j''` and, for actuated sliders, `r_j = rho_j''` (the `r` pieces are
/// zero when the sliders are prescribed: their accelerations are then known and inside the
/// `0` parts).
#[derive(Debug, Clone, Copy)]
pub(super) struct Kinetics {
    pub(super) nominal: PlatformMotion,
    /// The commanded machine (inverse kinematics of the trajectory).
    pub(super) rigid: MachineKinematics,
    pub(super) pose: Pose,
    pub(super) velocity: Vector3<f64>,
    pub(super) acceleration0: Vector3<f64>,
    /// `Q = F^-1 diag(L)`: `q'' = acceleration0 + Q s (+ Qr r)`.
    pub(super) q_of_s: Matrix3<f64>,
    /// `Qr = F^-1 diag(g.u)`, `g.u = L cos(a - b)` (actuated sliders).
    pub(super) q_of_r: Matrix3<f64>,
    pub(super) lengths: [f64; 3],
    /// `rho`, `rho'` and the known part of `rho''` (all of it when prescribed, 0 when
    /// actuated).
    pub(super) rho: [[f64; 3]; 3],
    pub(super) e: [Vector2<f64>; 3],
    pub(super) n: [Vector2<f64>; 3],
    pub(super) beta_dot: [f64; 3],
    pub(super) beta0: Vector3<f64>,
    pub(super) beta_s: Matrix3<f64>,
    pub(super) beta_r: Matrix3<f64>,
    pub(super) tension0: Vector3<f64>,
    pub(super) tension_s: Matrix3<f64>,
    pub(super) tension_m: Matrix3<f64>,
    pub(super) tension_r: Matrix3<f64>,
    pub(super) moment0: Vector3<f64>,
    pub(super) moment_s: Matrix3<f64>,
    pub(super) moment_r: Matrix3<f64>,
    pub(super) sin_ab: [f64; 3],
    pub(super) cos_ab: [f64; 3],
    /// Type-II measure of the actual chords.
    pub(super) type_ii_measure: f64,
}

/// Chord lengths `L = l - delta`, their rates, and the part of `L''` independent of `eta''`.
#[derive(Debug, Clone, Copy)]
struct Chords {
    lengths: [f64; 3],
    rate: [f64; 3],
    acceleration0: [f64; 3],
}

/// The platform's balance columns `E_i = (e_i, r_i x e_i)`, `N_i = (n_i, r_i x n_i)` and the
/// normalised columns of the type-II measure.
#[derive(Debug, Clone, Copy, Default)]
struct Balance {
    e_cols: Matrix3<f64>,
    n_cols: Matrix3<f64>,
    measure_cols: Matrix3<f64>,
}

impl CoupledSystem {
    /// Platform pose, velocity and the part `a_0` of its acceleration independent of `eta''`
    /// for chord lengths `L` (and rates), by Newton's method on the closure
    /// `f_i = (|C_i - B_i|^2 - L_i^2) / 2 = 0` from the nominal pose (the deviation is a
    /// fraction of a millimetre: two or three iterations), then implicit differentiation:
    /// `F q' = (g.u) rho' + L L'`, `F q'' = (g.u) rho'' + L L'' + L'^2 - |g'|^2 + phi'^2 g.r`
    /// (as [`flexprr_kinematics::Geometry::forward_motion`], which this inlines to share `F^-1`).
    /// Returns the motion and `F^-1`.
    pub(super) fn platform_motion(
        &self,
        t: f64,
        nominal: &Pose,
        rho: &[[f64; 3]; 3],
        lengths: [f64; 3],
        length_dot: [f64; 3],
        length_ddot0: [f64; 3],
    ) -> Result<(PlatformMotion, Matrix3<f64>), DynamicsError> {
        let geometry = &self.machine.geometry;
        let mut q = nominal.to_vector();
        let tolerance = 64.0 * f64::EPSILON * self.size;
        let mut g = [Vector2::zeros(); 3];
        let mut r = [Vector2::zeros(); 3];
        let mut f = Matrix3::zeros();
        let mut residual = Vector3::zeros();
        let mut iterations = 0;
        loop {
            let (sin, cos) = q.z.sin_cos();
            let mut worst: f64 = 0.0;
            for (i, leg) in geometry.legs.iter().enumerate() {
                let c = leg.attachment;
                r[i] = Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
                g[i] = Vector2::new(q.x, q.y) + r[i]
                    - leg.guide.anchor.coords
                    - rho[i][0] * leg.guide.direction.into_inner();
                residual[i] = 0.5 * (g[i].norm_squared() - lengths[i] * lengths[i]);
                f.set_row(
                    i,
                    &nalgebra::RowVector3::new(g[i].x, g[i].y, cross(&r[i], &g[i])),
                );
                worst = worst.max((residual[i] / lengths[i]).abs());
            }
            if worst <= tolerance {
                break;
            }
            if iterations == FORWARD_ITERATIONS || !worst.is_finite() {
                return Err(DynamicsError::Kinematics {
                    t,
                    source: flexprr_kinematics::KinematicsError::NoConvergence {
                        iterations,
                        residual: worst,
                    },
                });
            }
            let step = f
                .try_inverse()
                .ok_or(DynamicsError::SingularInverseDynamics {
                    t,
                    measure: 0.0,
                    threshold: geometry.thresholds.type_ii,
                })?
                * residual;
            q -= step;
            iterations += 1;
        }
        let f_inv = f
            .try_inverse()
            .ok_or(DynamicsError::SingularInverseDynamics {
                t,
                measure: 0.0,
                threshold: geometry.thresholds.type_ii,
            })?;
        let mut rhs = Vector3::zeros();
        for i in 0..3 {
            let u = geometry.legs[i].guide.direction.into_inner();
            rhs[i] = g[i].dot(&u) * rho[i][1] + lengths[i] * length_dot[i];
        }
        let velocity = f_inv * rhs;
        let omega = velocity.z;
        for i in 0..3 {
            let u = geometry.legs[i].guide.direction.into_inner();
            let g_dot = Vector2::new(velocity.x - omega * r[i].y, velocity.y + omega * r[i].x)
                - rho[i][1] * u;
            rhs[i] = g[i].dot(&u) * rho[i][2]
                + lengths[i] * length_ddot0[i]
                + length_dot[i] * length_dot[i]
                - g_dot.norm_squared()
                + omega * omega * g[i].dot(&r[i]);
        }
        let acceleration = f_inv * rhs;
        Ok((
            PlatformMotion {
                pose: Pose::from_vector(&q),
                velocity,
                acceleration,
            },
            f_inv,
        ))
    }

    /// Rigid kinematics and the linear-in-acceleration pieces at `(t, y)`; fills
    /// `scratch.g0_eta`, `scratch.inv_g0_eta` and `scratch.length_gradient`.
    pub(super) fn kinetics(&mut self, t: f64, y: &[f64]) -> Result<Kinetics, DynamicsError> {
        let (eta, eta_dot) = self.elastic_state(y);
        let nominal = self.trajectory.motion(t);
        // The commanded machine, in place and without the link angles.
        let mut rigid = MachineKinematics::default();
        self.machine
            .geometry
            .inverse_kinematics_unchecked_into(&nominal, &mut rigid)
            .map_err(|source| DynamicsError::Kinematics { t, source })?;
        let rho = self.slider_motion(y, &rigid);
        let chords = self.chords(y);
        let (motion, f_inv) = self.platform(t, &nominal, &rigid, &rho, &chords, eta)?;
        let q_of_s = f_inv * Matrix3::from_diagonal(&Vector3::from(chords.lengths));
        let mut out = Kinetics {
            nominal,
            rigid,
            pose: motion.pose,
            velocity: motion.velocity,
            acceleration0: motion.acceleration,
            q_of_s,
            q_of_r: Matrix3::zeros(),
            lengths: chords.lengths,
            rho,
            e: [Vector2::zeros(); 3],
            n: [Vector2::zeros(); 3],
            beta_dot: [0.0; 3],
            beta0: Vector3::zeros(),
            beta_s: Matrix3::zeros(),
            beta_r: Matrix3::zeros(),
            tension0: Vector3::zeros(),
            tension_s: Matrix3::zeros(),
            tension_m: Matrix3::zeros(),
            tension_r: Matrix3::zeros(),
            moment0: Vector3::zeros(),
            moment_s: Matrix3::zeros(),
            moment_r: Matrix3::zeros(),
            sin_ab: [0.0; 3],
            cos_ab: [0.0; 3],
            type_ii_measure: f64::NAN,
        };
        let balance = self.chord_motion(&mut out, eta, &chords);
        if self.actuated.is_some() {
            self.slider_sensitivities(&mut out, f_inv, eta);
        }
        let _ = eta_dot;
        self.tensions(&mut out, &balance, t, eta)?;
        Ok(out)
    }

    /// `rho`, `rho'` and the known part of `rho''` of each slider: the commanded motion
    /// when the sliders are prescribed; the state's position and velocity (and 0) when they
    /// are degrees of freedom.
    fn slider_motion(&self, y: &[f64], rigid: &MachineKinematics) -> [[f64; 3]; 3] {
        if self.actuated.is_some() {
            let (n, coordinates) = (self.modes, self.coordinates());
            return std::array::from_fn(|i| [y[n + i], y[coordinates + n + i], 0.0]);
        }
        std::array::from_fn(|i| {
            let leg = &rigid.legs[i];
            [leg.rho, leg.rho_dot, leg.rho_ddot]
        })
    }

    /// Chord lengths and rates from the links' foreshortening (the rigid length `l` with
    /// the switch off); fills the scratch `G0 eta / l`, `M^-1 G0 eta / l` and `dL / d eta`.
    fn chords(&mut self, y: &[f64]) -> Chords {
        let (eta, eta_dot) = self.elastic_state(y);
        let mut chords = Chords {
            lengths: [0.0; 3],
            rate: [0.0; 3],
            acceleration0: [0.0; 3],
        };
        for (i, link) in self.links.iter().enumerate() {
            let range = self.offsets[i]..self.offsets[i] + link.r;
            let r = link.r;
            let (e, ed) = (&eta[range.clone()], &eta_dot[range.clone()]);
            let mut quad = 0.0;
            let mut quad_dot = 0.0;
            for j in 0..r {
                let row = &link.g0[j * r..(j + 1) * r];
                let g0e = dot(row, e) / link.length;
                self.scratch.g0_eta[range.start + j] = g0e;
                quad += e[j] * g0e;
                quad_dot += ed[j] * dot(row, ed) / link.length;
            }
            let inv_g0 = &link.inv_geometric[0];
            for j in 0..r {
                self.scratch.inv_g0_eta[range.start + j] =
                    dot(&inv_g0[j * r..(j + 1) * r], e) / link.length;
            }
            if self.options.foreshortening {
                chords.lengths[i] = link.length - 0.5 * quad;
                chords.rate[i] = -dot(&self.scratch.g0_eta[range.clone()], ed);
                chords.acceleration0[i] = -quad_dot;
                for j in range {
                    self.scratch.length_gradient[j] = -self.scratch.g0_eta[j];
                }
            } else {
                chords.lengths[i] = link.length;
                self.scratch.length_gradient[range].fill(0.0);
            }
        }
        chords
    }

    /// The platform motion and `F^-1`: from the closure with the sliders and the chords
    /// (foreshortening on, or sliders that are degrees of freedom), else the commanded motion
    /// (chords of length `l` on the commanded sliders close on the commanded pose).
    fn platform(
        &mut self,
        t: f64,
        nominal: &PlatformMotion,
        rigid: &MachineKinematics,
        rho: &[[f64; 3]; 3],
        chords: &Chords,
        eta: &[f64],
    ) -> Result<(PlatformMotion, Matrix3<f64>), DynamicsError> {
        if self.options.foreshortening || self.actuated.is_some() {
            self.counters.forward_kinematics_solves += 1;
            let Chords {
                lengths,
                rate,
                acceleration0,
            } = *chords;
            return self
                .platform_motion(t, &nominal.pose, rho, lengths, rate, acceleration0)
                .map_err(|e| self.collapse_or(e, t, eta, rigid, 0.0));
        }
        let closure =
            self.machine
                .geometry
                .closure(&nominal.pose, rho.map(|r| r[0]), chords.lengths);
        let f_inv =
            closure
                .pose_jacobian
                .try_inverse()
                .ok_or(DynamicsError::SingularInverseDynamics {
                    t,
                    measure: 0.0,
                    threshold: self.machine.geometry.thresholds.type_ii,
                })?;
        Ok((*nominal, f_inv))
    }

    /// Chord directions, angular rates and the `eta''`-free and `s` parts of the chord
    /// angular accelerations and link moments; returns the platform's balance columns.
    ///
    /// `b_i'' = [N_i . q'' - phi'^2 r_i.n_i - rho_i'' sin(a_i - b_i) - 2 L_i' b_i'] / L_i`,
    /// `Mom_i = I_B b_i'' + (m l / 2) rho_i'' sin(a_i - b_i) + l m_xipsi.eta_i''
    /// - rho_i'' cos(a_i - b_i) m_psi.eta_i` (docs/coupled.md, "Derivation").
    fn chord_motion(&self, out: &mut Kinetics, eta: &[f64], chords: &Chords) -> Balance {
        let geometry = &self.machine.geometry;
        let (sin, cos) = out.pose.phi.sin_cos();
        let rotate = |c: &Vector2<f64>| Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
        let p = Vector2::new(out.pose.x, out.pose.y);
        let v = Vector2::new(out.velocity.x, out.velocity.y);
        let omega = out.velocity.z;
        let a0 = out.acceleration0;
        let lengths = chords.lengths;
        let mut balance = Balance::default();
        let centroid = rotate(&geometry.platform_centroid());
        let radius = geometry.platform_radius().max(f64::MIN_POSITIVE);
        for (i, leg) in geometry.legs.iter().enumerate() {
            let link = &self.links[i];
            let range = self.offsets[i]..self.offsets[i] + link.r;
            let rho = out.rho[i];
            let u = leg.guide.direction.into_inner();
            let r_i = rotate(&leg.attachment);
            let chord = p + r_i - leg.guide.anchor.coords - rho[0] * u;
            let e = chord / lengths[i];
            let nrm = Vector2::new(-e.y, e.x);
            let c_dot = v + omega * Vector2::new(-r_i.y, r_i.x);
            let beta_dot = (c_dot - rho[1] * u).dot(&nrm) / lengths[i];
            let big_n = Vector3::new(nrm.x, nrm.y, cross(&r_i, &nrm));
            let sin_ab = u.dot(&nrm);
            let cos_ab = u.dot(&e);
            out.beta0[i] = (big_n.dot(&a0)
                - omega * omega * r_i.dot(&nrm)
                - rho[2] * sin_ab
                - 2.0 * chords.rate[i] * beta_dot)
                / lengths[i];
            let row = big_n.transpose() * out.q_of_s / lengths[i];
            out.beta_s.set_row(i, &row);
            balance
                .e_cols
                .set_column(i, &Vector3::new(e.x, e.y, cross(&r_i, &e)));
            balance.n_cols.set_column(i, &big_n);
            let column = Vector3::new(e.x, e.y, cross(&(r_i - centroid), &e) / radius);
            balance.measure_cols.set_column(i, &column.normalize());
            // Moment about B_i of the link's inertia forces (the part independent of eta'').
            let mut m0 =
                link.inertia_b * out.beta0[i] + 0.5 * link.mass * link.length * rho[2] * sin_ab;
            if self.options.elastic_reactions {
                m0 -= rho[2] * cos_ab * dot(&link.mass_psi, &eta[range]);
            }
            // External point forces: their moment about B_i (docs/linear.md).
            out.moment0[i] = (m0 - self.loads.moment[i]) / lengths[i];
            out.moment_s
                .set_row(i, &(row * (link.inertia_b / lengths[i])));
            out.e[i] = e;
            out.n[i] = nrm;
            out.beta_dot[i] = beta_dot;
            out.sin_ab[i] = sin_ab;
            out.cos_ab[i] = cos_ab;
        }
        balance
    }

    /// The slider accelerations' part of the platform acceleration, the chord angular
    /// accelerations and the link moments, for sliders that are degrees of freedom:
    /// `Qr = F^-1 diag(L cos(a - b))` (the closure's `(g.u) rho''`),
    /// `Br_ij = (N_i . Qr_j - delta_ij sin(a_i - b_i)) / L_i`, and
    /// `Sr_ij = (I_B Br_ij + delta_ij ((m l / 2) sin(a_i - b_i) - cos(a_i - b_i) m_psi.eta_i)) / L_i`.
    fn slider_sensitivities(&self, out: &mut Kinetics, f_inv: Matrix3<f64>, eta: &[f64]) {
        let along = Vector3::from(std::array::from_fn::<f64, 3, _>(|i| {
            out.lengths[i] * out.cos_ab[i]
        }));
        out.q_of_r = f_inv * Matrix3::from_diagonal(&along);
        let (sin, cos) = out.pose.phi.sin_cos();
        for (i, leg) in self.machine.geometry.legs.iter().enumerate() {
            let link = &self.links[i];
            let c = leg.attachment;
            let r_i = Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
            let nrm = out.n[i];
            let big_n = Vector3::new(nrm.x, nrm.y, cross(&r_i, &nrm));
            let mut row = big_n.transpose() * out.q_of_r / out.lengths[i];
            row[i] -= out.sin_ab[i] / out.lengths[i];
            out.beta_r.set_row(i, &row);
            let mut moment = row * link.inertia_b;
            moment[i] += 0.5 * link.mass * link.length * out.sin_ab[i];
            if self.options.elastic_reactions {
                let range = self.offsets[i]..self.offsets[i] + link.r;
                moment[i] -= out.cos_ab[i] * dot(&link.mass_psi, &eta[range]);
            }
            out.moment_r.set_row(i, &(moment / out.lengths[i]));
        }
    }

    /// The chord tensions from the platform's Newton-Euler equations,
    /// `sum_i T_i E_i = -M_p q'' - sum_i S_i N_i`; refuses a type-II pose of the actual
    /// chords (a collapse when the commanded pose is regular).
    fn tensions(
        &self,
        out: &mut Kinetics,
        balance: &Balance,
        t: f64,
        eta: &[f64],
    ) -> Result<(), DynamicsError> {
        let geometry = &self.machine.geometry;
        let singular = |measure: f64| {
            let rigid_singular = DynamicsError::SingularInverseDynamics {
                t,
                measure,
                threshold: geometry.thresholds.type_ii,
            };
            self.collapse_or(rigid_singular, t, eta, &out.rigid, measure)
        };
        let measure = balance.measure_cols.determinant().abs();
        if measure.is_nan() || measure < geometry.thresholds.type_ii {
            return Err(singular(measure));
        }
        out.type_ii_measure = measure;
        let e_inv = balance
            .e_cols
            .try_inverse()
            .ok_or_else(|| singular(measure))?;
        let mp = Vector3::new(
            self.machine.platform_mass,
            self.machine.platform_mass,
            self.machine.platform_inertia,
        );
        let n_cols = balance.n_cols;
        out.tension0 = e_inv * (-out.acceleration0.component_mul(&mp) - n_cols * out.moment0);
        out.tension_s =
            e_inv * (-(Matrix3::from_diagonal(&mp) * out.q_of_s) - n_cols * out.moment_s);
        if self.actuated.is_some() {
            out.tension_r =
                e_inv * (-(Matrix3::from_diagonal(&mp) * out.q_of_r) - n_cols * out.moment_r);
        }
        if self.options.elastic_reactions {
            let scale = Vector3::from(std::array::from_fn::<f64, 3, _>(|i| {
                self.links[i].length / out.lengths[i]
            }));
            out.tension_m = -(e_inv * n_cols * Matrix3::from_diagonal(&scale));
        }
        Ok(())
    }

    /// [`DynamicsError::Collapse`] when the largest mid-point deflection passes `limit` times
    /// its link's length.
    pub(super) fn deflection_collapse(
        &self,
        t: f64,
        eta: &[f64],
        measure: f64,
        limit: f64,
    ) -> Option<DynamicsError> {
        (0..3).find_map(|i| {
            let w = dot(&self.links[i].psi_mid, &eta[self.link_range(i)]);
            let length = self.links[i].length;
            (w.abs() > limit * length).then_some(DynamicsError::Collapse {
                t,
                link: i + 1,
                deflection: w,
                length,
                type_ii_measure: measure,
            })
        })
    }

    /// A singular platform pose is a collapse when the nominal (rigid) pose is regular: the
    /// deflection, not the trajectory, made the chords concurrent. Then
    /// [`DynamicsError::Collapse`] with the most deflected link; otherwise `error` unchanged.
    fn collapse_or(
        &self,
        error: DynamicsError,
        t: f64,
        eta: &[f64],
        rigid: &flexprr_kinematics::MachineKinematics,
        measure: f64,
    ) -> DynamicsError {
        let nominal = crate::equilibrium_measure(rigid);
        if nominal.is_nan() || nominal < self.machine.geometry.thresholds.type_ii {
            return error;
        }
        let (link, deflection) = (0..3)
            .map(|i| (i, dot(&self.links[i].psi_mid, &eta[self.link_range(i)])))
            .fold(
                (0, 0.0_f64),
                |a, b| if b.1.abs() > a.1.abs() { b } else { a },
            );
        if deflection.abs() <= 0.0 {
            return error;
        }
        DynamicsError::Collapse {
            t,
            link: link + 1,
            deflection,
            length: self.links[link].length,
            type_ii_measure: measure,
        }
    }
}
