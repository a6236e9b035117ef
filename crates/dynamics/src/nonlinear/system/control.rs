//! The control wiring of the nonlinear model: the sliders' actuators under their law, the
//! piezoelectric patches under their vibration law (sensors from the centre line, moments as
//! consistent nodal loads), and the external loads of linear models.

use super::*;

impl NonlinearSystem {
    /// The same model with the sliders as degrees of freedom, driven along their guides by
    /// `actuation`'s actuators under its controller (docs/control.md), started at `t0` on
    /// the commanded path: each slider carries its mass, the actuator's reflected mass and
    /// half the mass of its link's first node, `(m_s + m_r + m_0) rho'' = F - f_0 . u` with
    /// `f_0` the internal force at the node.
    ///
    /// # Errors
    /// The commanded motion's inverse kinematics fails at `t0`.
    pub fn with_actuation(mut self, actuation: Actuation, t0: f64) -> Result<Self, DynamicsError> {
        let coordinates = 3 + 3 * self.per_link + 3;
        self.actuated = Some(Actuated::new(actuation, &self.machine, t0, coordinates));
        self.mass = BorderedBanded::new(3, self.per_link, MASS_BANDWIDTH, 6);
        self.generalized = vec![0.0; self.coordinates()];
        self.tangent_work = vec![0.0; self.dim()];
        self.start_at(t0)?;
        Ok(self)
    }
    /// Sets external loads (the inputs of linear models): a transverse point force on a
    /// link goes to the nodes of its element as the element's consistent load (the cubic
    /// Hermite shape functions: forces `P h00(a)`, `P h01(a)` along the chord normal, moments
    /// `P L_e h10(a)`, `P L_e h11(a)`); a slider load adds to the actuator's force.
    ///
    /// # Errors
    /// A point force off the links.
    pub fn set_loads(&mut self, loads: &crate::ExternalLoads) -> Result<(), DynamicsError> {
        let ne = self.options.elements;
        let mut points = Vec::with_capacity(loads.point.len());
        for p in &loads.point {
            crate::model::check_point_force(p)?;
            let s = p.xi * ne as f64;
            let e = (s.floor() as usize).min(ne - 1);
            points.push((p.link, e, s - e as f64, p.force));
        }
        self.point_loads = points;
        self.slider_loads = loads.slider;
        if let Some(actuated) = self.actuated.as_mut() {
            actuated.set_overrides(loads);
        }
        if let Some((law, _)) = self.patches.as_mut() {
            law.set_overrides(loads);
        }
        Ok(())
    }
    /// Number of piezoelectric patches.
    pub fn patch_count(&self) -> usize {
        self.patches
            .as_ref()
            .map_or(0, |(law, _)| law.patches().len())
    }
    /// The sampled laws at `t` (see [`crate::ControlLaws::sampled_laws`]).
    pub fn sampled_laws(&self, t: f64) -> crate::SampledLaws {
        crate::actuation::sampled_laws(
            self.actuated.as_ref(),
            self.patches.as_ref().map_or(0.0, |(law, _)| law.period()),
            t,
        )
    }
    /// What the sampled laws command at a sample at `(t, y)` (see
    /// [`crate::ControlLaws::law_sample`]).
    ///
    /// # Errors
    /// A wrong state length, a kinematic failure, or a singular rigid inverse dynamics (the
    /// feedforward).
    pub fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<crate::LawSample, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        let mut sample = crate::LawSample::default();
        if let Some(actuated) = self.actuated.as_ref().filter(|a| a.period() > 0.0) {
            (sample.slider_command, sample.slider_rates) =
                actuated.law_sample_at(&self.machine, &frame.rigid, t, y, slider_states)?;
        }
        if self
            .patches
            .as_ref()
            .is_some_and(|(law, _)| law.period() > 0.0)
        {
            self.sense_patches(y, &frame);
            if let Some((law, _)) = &self.patches {
                sample.patch_command = law.law_voltages(t);
            }
        }
        Ok(sample)
    }
    /// The same model with piezoelectric patches on the links under a vibration control law
    /// (docs/piezo.md), started at `t0`. A patch's sensor reads the rotation of the centre
    /// line between its ends (the slope difference, exact for any deflection); its actuator
    /// puts moments `-k_a V` and `+k_a V` at its ends, each as the consistent nodal load of
    /// its element (forces `C h'(a) / L_e` across the element, moments `C L_e h'(a)` of the
    /// Hermite functions' derivatives).
    ///
    /// # Errors
    /// A bad patch.
    pub fn with_patch_control(
        mut self,
        control: crate::PatchControl,
        t0: f64,
    ) -> Result<Self, DynamicsError> {
        let law = crate::patches::PatchLaw::new(control, t0)?;
        let ne = self.options.elements;
        let place = |xi: f64| {
            let s = xi * ne as f64;
            let e = (s.floor() as usize).min(ne - 1);
            (e, s - e as f64)
        };
        let places = law
            .patches()
            .iter()
            .map(|p| [place(p.xi_start), place(p.xi_end)])
            .collect();
        self.patches = Some((law, places));
        Ok(self)
    }
    /// The patches' sensors from the state (their laws' sensor buffers).
    pub(super) fn sense_patches(&mut self, y: &[f64], frame: &Frame) {
        let Some((mut law, places)) = self.patches.take() else {
            return;
        };
        for (p, place) in places.iter().enumerate() {
            let patch = law.patches()[p];
            let (theta1, rate1) = self.tangent_angle(y, frame, patch.link, place[0]);
            let (theta2, rate2) = self.tangent_angle(y, frame, patch.link, place[1]);
            law.sensors[p] = patch.sensor_constant * wrap_angle(theta2 - theta1);
            law.rates[p] = patch.sensor_constant * (rate2 - rate1);
        }
        self.patches = Some((law, places));
    }
    /// Subtracts the patches' nodal loads at `(t, y)` from the nodal force buffer (after the
    /// law's voltages at the frame's time).
    pub(super) fn apply_patches(&mut self, y: &[f64], frame: &Frame) {
        if self.patches.is_none() {
            return;
        }
        self.sense_patches(y, frame);
        let Some((mut law, places)) = self.patches.take() else {
            return;
        };
        law.drive(frame.t);
        let stride = 3 * (self.options.elements + 1);
        for (p, place) in places.iter().enumerate() {
            let patch = law.patches()[p];
            let moment = patch.actuator_constant * law.voltage(p);
            let i = patch.link;
            for (&(e, a), c) in place.iter().zip([-moment, moment]) {
                let (q1, _) = self.node(y, frame, i, e);
                let (q2, _) = self.node(y, frame, i, e + 1);
                let chord = Vector2::new(q2[0] - q1[0], q2[1] - q1[1]);
                let length = chord.norm();
                let normal = perp(&(chord / length));
                let (d00, d10) = (6.0 * a * a - 6.0 * a, 3.0 * a * a - 4.0 * a + 1.0);
                let (d01, d11) = (-6.0 * a * a + 6.0 * a, 3.0 * a * a - 2.0 * a);
                let f = &mut self.forces[i * stride..(i + 1) * stride];
                for (node, force, torque) in [(e, d00, d10), (e + 1, d01, d11)] {
                    f[3 * node] -= c * force / length * normal.x;
                    f[3 * node + 1] -= c * force / length * normal.y;
                    f[3 * node + 2] -= c * torque;
                }
            }
        }
        self.patches = Some((law, places));
    }
    /// The patches' states at `(t, y)` (none without patches).
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn patch_states(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Vec<crate::PatchState>, DynamicsError> {
        if self.patches.is_none() {
            return Ok(Vec::new());
        }
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        self.sense_patches(y, &frame);
        Ok(self.patches.as_mut().map_or_else(Vec::new, |(law, _)| {
            law.drive(t);
            law.states()
        }))
    }
    /// Subtracts the external point loads from the nodal force buffer (it holds the internal
    /// forces, which the accelerations oppose).
    pub(super) fn apply_point_loads(&mut self, frame: &Frame) {
        let stride = 3 * (self.options.elements + 1);
        for &(i, e, a, force) in &self.point_loads {
            let chord = frame.c[i][0] - frame.b[i][0];
            let n = perp(&chord.normalize());
            let le = self.links[i].element.length;
            let (h00, h10) = (
                2.0 * a * a * a - 3.0 * a * a + 1.0,
                a * a * a - 2.0 * a * a + a,
            );
            let (h01, h11) = (-2.0 * a * a * a + 3.0 * a * a, a * a * a - a * a);
            let f = &mut self.forces[i * stride..(i + 1) * stride];
            for (node, shape, moment) in [(e, h00, h10), (e + 1, h01, h11)] {
                f[3 * node] -= force * shape * n.x;
                f[3 * node + 1] -= force * shape * n.y;
                f[3 * node + 2] -= force * le * moment;
            }
        }
    }
    /// The actuators' commands and outputs at `(t, y)` for the frame's commanded state
    /// (the control law's state rates into `rates`); their forces into `slider_forces`.
    pub(in crate::nonlinear) fn actuate(
        &mut self,
        t: f64,
        y: &[f64],
        frame: &Frame,
        rates: &mut [f64],
    ) -> Result<Option<crate::actuation::Commands>, DynamicsError> {
        let Some(actuated) = self.actuated.as_ref() else {
            return Ok(None);
        };
        let (command, outputs) = actuated.forces(&self.machine, &frame.rigid, t, y, rates)?;
        self.slider_forces = outputs.map(|o| o.force);
        Ok(Some((command, outputs)))
    }
}
