//! What the coupled model reports at one `(t, y)`.

use flexprr_kinematics::PlatformMotion;
use nalgebra::Vector3;

use super::{CoupledOutput, CoupledSystem, dot};
use crate::DynamicsError;
use crate::model::ActuatorState;

impl CoupledSystem {
    /// Modal accelerations `eta''` at `(t, y)` (allocating; for outputs and tests).
    ///
    /// # Errors
    /// Kinematic failure (forward or inverse), a type-II singular pose, a singular mass matrix.
    pub fn modal_accelerations(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, DynamicsError> {
        self.check_state(y)?;
        let kin = self.kinetics(t, y)?;
        let mut rates = vec![0.0; y.len() - 2 * self.coordinates()];
        let actuators = self.actuator_forces(t, y, &kin.rigid, &mut rates)?;
        let forces = actuators.map(|(_, outputs)| outputs.map(|o| o.force));
        self.solve_accelerations(t, y, &kin, forces.as_ref())?;
        Ok(self.scratch.acceleration.clone())
    }

    /// Platform motion, chord kinematics, axial forces, mid-point deflections and driving
    /// forces at `(t, y)`.
    ///
    /// # Errors
    /// As [`CoupledSystem::modal_accelerations`].
    pub fn output(&mut self, t: f64, y: &[f64]) -> Result<CoupledOutput, DynamicsError> {
        self.check_state(y)?;
        let kin = self.kinetics(t, y)?;
        let mut rates = vec![0.0; y.len() - 2 * self.coordinates()];
        let actuators = self.actuator_forces(t, y, &kin.rigid, &mut rates)?;
        let forces = actuators.map(|(_, outputs)| outputs.map(|o| o.force));
        let z = self.solve_accelerations(t, y, &kin, forces.as_ref())?;
        let (s, m, r) = (z.s, z.m, z.r);
        let (eta, eta_dot) = self.elastic_state(y);
        let acceleration = kin.acceleration0 + kin.q_of_s * s + kin.q_of_r * r;
        let beta_ddot = kin.beta0 + kin.beta_s * s + kin.beta_r * r;
        let tension = kin.tension0 + kin.tension_s * s + kin.tension_m * m + kin.tension_r * r;
        let slider: [[f64; 3]; 3] =
            std::array::from_fn(|i| [kin.rho[i][0], kin.rho[i][1], kin.rho[i][2] + r[i]]);
        let slider_mass = self
            .actuated
            .as_ref()
            .map_or(self.machine.slider_mass, |a| a.slider_mass);
        let mut out = CoupledOutput {
            t,
            nominal: kin.nominal,
            platform: PlatformMotion {
                pose: kin.pose,
                velocity: kin.velocity,
                acceleration,
            },
            slider,
            chord_length: kin.lengths,
            chord_angle: [[0.0; 3]; 3],
            axial_force_b: [0.0; 3],
            axial_force_c: [0.0; 3],
            midpoint_deflection: [0.0; 3],
            driving_force: [0.0; 3],
            axial_stretch: [0.0; 3],
            stretch_pose_correction: [0.0; 3],
            actuators: actuators.map(|(command, outputs)| {
                std::array::from_fn(|i| ActuatorState {
                    command: command[i],
                    output: outputs[i],
                })
            }),
        };
        for (i, link) in self.links.iter().enumerate() {
            let range = self.offsets[i]..self.offsets[i] + link.r;
            let (e, ed, acc) = (
                &eta[range.clone()],
                &eta_dot[range.clone()],
                &self.scratch.acceleration[range],
            );
            let (l, mass) = (link.length, link.mass);
            let (rho_ddot, b_dot, b_ddot) = (slider[i][2], kin.beta_dot[i], beta_ddot[i]);
            out.chord_angle[i] = [kin.e[i].y.atan2(kin.e[i].x), b_dot, b_ddot];
            out.axial_force_c[i] = tension[i];
            out.axial_force_b[i] =
                tension[i] - mass * (rho_ddot * kin.cos_ab[i] - 0.5 * b_dot * b_dot * l);
            out.midpoint_deflection[i] = dot(&link.psi_mid, e);
            if let Some(stiffness) = self.options.axial_stiffness {
                // int_0^l N dx for N(x) = P_B + rhoA rho'' cos x - rhoA b'^2 x^2 / 2.
                let rho_a = mass / l;
                let integral = out.axial_force_b[i] * l
                    + 0.5 * rho_a * rho_ddot * kin.cos_ab[i] * l * l
                    - rho_a * b_dot * b_dot * l * l * l / 6.0;
                out.axial_stretch[i] = integral / stiffness[i];
            }
            // Slider force on the link from the link's force balance: the rigid chord inertia
            // plus the elastic transverse and Coriolis/tangential parts, minus the force at C.
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            let (ei, ni) = (kin.e[i], kin.n[i]);
            let m_psi_eta = dot(&link.mass_psi, e);
            let transverse = dot(&link.mass_psi, acc) - b_dot * b_dot * m_psi_eta;
            let tangential = -2.0 * b_dot * dot(&link.mass_psi, ed) - b_ddot * m_psi_eta;
            let inertia = mass * (rho_ddot * u + 0.5 * l * (b_ddot * ni - b_dot * b_dot * ei))
                + transverse * ni
                + tangential * ei;
            let mom = link.inertia_b * b_ddot
                + 0.5 * mass * l * rho_ddot * kin.sin_ab[i]
                + if self.options.elastic_reactions {
                    l * m[i] - rho_ddot * kin.cos_ab[i] * m_psi_eta
                } else {
                    0.0
                };
            let f_c = tension[i] * ei + (mom / kin.lengths[i]) * ni;
            let f_b = inertia - f_c - self.loads.transverse[i] * ni;
            // Actuated: the slider's equation of motion makes this the actuator's force.
            out.driving_force[i] = slider_mass[i] * rho_ddot + f_b.dot(&u);
        }
        if self.options.axial_stiffness.is_some() {
            // F dq = L stretch with F the closure's pose Jacobian, Q = F^-1 diag(L).
            let dq = kin.q_of_s * Vector3::from(out.axial_stretch);
            out.stretch_pose_correction = [dq.x, dq.y, dq.z];
        }
        Ok(out)
    }
}
