//! What the nonlinear model reports at one `(t, y)` ([`NonlinearOutput`]).

use super::*;

/// Everything the nonlinear model reports at one `(t, y)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearOutput {
    /// Time (s).
    pub t: f64,
    /// The nominal platform motion (the trajectory's).
    pub nominal: PlatformMotion,
    /// The actual platform motion (pose and velocity from the state, acceleration from the
    /// equations of motion).
    pub platform: PlatformMotion,
    /// Slider positions, velocities and accelerations `(rho_i, rho_i', rho_i'')` (m, m/s,
    /// m/s^2): the commanded ones.
    pub slider: [[f64; 3]; 3],
    /// Chord lengths `|C_i - B_i|` (m).
    pub chord_length: [f64; 3],
    /// Chord angles `b_i` (rad).
    pub chord_angle: [f64; 3],
    /// Transverse deflection of each link's mid-point (the middle node) from its chord, along
    /// the chord normal `n = (-sin b, cos b)` (m).
    pub midpoint_deflection: [f64; 3],
    /// Axial force at `B_i`, `-F_B . e` with `F_B` the slider's force on the link (tension
    /// positive, N).
    pub axial_force_b: [f64; 3],
    /// Axial force at `C_i`, `F_C . e` with `F_C` the platform's force on the link (N).
    pub axial_force_c: [f64; 3],
    /// Driving force of each slider along its guide, `m_s rho'' + F_B . u` (N).
    pub driving_force: [f64; 3],
    /// Type-II measure of the chords ([`crate::equilibrium_measure`]'s definition).
    pub type_ii_measure: f64,
    /// Kinetic energy of the links' nodes and the platform, and of the sliders (with the
    /// actuators' reflected inertia) when they are actuated (J).
    pub kinetic_energy: f64,
    /// Strain energy of the links (J).
    pub strain_energy: f64,
    /// Strain energy of each link (J).
    pub link_strain_energy: [f64; 3],
    /// Power the sliders deliver to the links, `sum_i F_B_i . B_i'` (W): the rate of change
    /// of the total energy when there is no damping.
    pub slider_power: f64,
    /// The actuators' commands and outputs, when the sliders are actuated.
    pub actuators: Option<[ActuatorState; 3]>,
}

impl NonlinearOutput {
    /// Platform pose minus the nominal pose `(dx, dy, dphi)` (m, m, rad).
    pub fn pose_deviation(&self) -> [f64; 3] {
        [
            self.platform.pose.x - self.nominal.pose.x,
            self.platform.pose.y - self.nominal.pose.y,
            self.platform.pose.phi - self.nominal.pose.phi,
        ]
    }
}

impl NonlinearSystem {
    /// Platform motion, chords, mid-point deflections, axial and driving forces at `(t, y)`.
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure (not the collapse checks: the output of a
    /// collapsed state is still reported).
    pub fn output(&mut self, t: f64, y: &[f64]) -> Result<NonlinearOutput, DynamicsError> {
        self.check_state(y)?;
        let mut frame = self.frame(t, y)?;
        self.assemble(y, &frame);
        let n = self.coordinates();
        let mut rates = vec![0.0; y.len() - 2 * n];
        let actuators = self.actuate(t, y, &frame, &mut rates)?;
        let mut acc = vec![0.0; n];
        self.accelerations(t, y, &frame, &mut acc)?;
        if self.actuated.is_some() {
            for i in 0..3 {
                let rho_ddot = acc[self.slider_index(i)];
                let u = self.machine.geometry.legs[i].guide.direction.into_inner();
                frame.rho[i][2] = rho_ddot;
                frame.b[i][2] = rho_ddot * u;
            }
        }
        let slider_mass = self.slider_masses();
        let ne = self.options.elements;
        let stride = 3 * (ne + 1);
        let omega = y[n + 2];
        let qdd = Vector3::new(acc[0], acc[1], acc[2]);
        let mut out = NonlinearOutput {
            t,
            nominal: frame.nominal,
            platform: PlatformMotion {
                pose: Pose::new(y[0], y[1], y[2]),
                velocity: Vector3::new(y[n], y[n + 1], y[n + 2]),
                acceleration: qdd,
            },
            slider: frame.rho,
            actuators: actuators.map(|(command, outputs)| {
                std::array::from_fn(|i| ActuatorState {
                    command: command[i],
                    output: outputs[i],
                })
            }),
            chord_length: [0.0; 3],
            chord_angle: [0.0; 3],
            midpoint_deflection: self.midpoint_deflections(y, &frame),
            axial_force_b: [0.0; 3],
            axial_force_c: [0.0; 3],
            driving_force: [0.0; 3],
            type_ii_measure: self.measure(&frame),
            kinetic_energy: 0.5
                * (self.machine.platform_mass * (y[n] * y[n] + y[n + 1] * y[n + 1])
                    + self.machine.platform_inertia * omega * omega),
            strain_energy: 0.0,
            link_strain_energy: [0.0; 3],
            slider_power: 0.0,
        };
        for (i, link) in self.links.iter().enumerate() {
            let f = &self.forces[i * stride..(i + 1) * stride];
            let chord = frame.c[i][0] - frame.b[i][0];
            let e = chord.normalize();
            out.chord_length[i] = chord.norm();
            out.chord_angle[i] = wrap_angle(e.y.atan2(e.x));
            // Node 0: F_B = (its inertia) + f_0; node N: F_C = (its inertia) + f_N.
            let first = self.element_inertia_force(&frame, y, &acc, i, 0);
            let last = self.element_inertia_force(&frame, y, &acc, i, ne - 1);
            let f_b = Vector2::new(first[0] + f[0], first[1] + f[1]);
            let f_c = Vector2::new(last[3] + f[3 * ne], last[4] + f[3 * ne + 1]);
            out.axial_force_b[i] = -f_b.dot(&e);
            out.axial_force_c[i] = f_c.dot(&e);
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            // Actuated: the slider's equation of motion makes this the actuator's force.
            out.driving_force[i] = slider_mass[i] * frame.rho[i][2] + f_b.dot(&u);
            if self.actuated.is_some() {
                out.kinetic_energy += 0.5 * slider_mass[i] * frame.rho[i][1] * frame.rho[i][1];
            }
            out.slider_power += f_b.dot(&frame.b[i][1]);
            out.kinetic_energy += self.link_kinetic_energy(y, &frame, i);
            let el = link.element;
            for k in 0..ne {
                let (q, v) = self.element_state(y, &frame, i, k);
                let _ = v;
                out.link_strain_energy[i] += el.strain_energy(&el.state(&q));
            }
        }
        out.strain_energy = out.link_strain_energy.iter().sum();
        Ok(out)
    }
}
