//! The right-hand side of the nonlinear model: assembly of the element forces, the
//! accelerations, the collapse limit and the integrator's hooks ([`OdeSystem`]).

use super::*;

impl NonlinearSystem {
    /// Assembles the nodal forces (internal plus damping) of every link into `self.forces`.
    pub(in crate::nonlinear) fn assemble(&mut self, y: &[f64], frame: &Frame) {
        let ne = self.options.elements;
        let stride = 3 * (ne + 1);
        let (beta_a, beta_b) = (
            self.options.axial_damping_time,
            self.options.bending_damping_time,
        );
        let mut forces = std::mem::take(&mut self.forces);
        forces.fill(0.0);
        for i in 0..3 {
            let el = self.links[i].element;
            let f = &mut forces[i * stride..(i + 1) * stride];
            let (mut q1, mut v1) = self.node(y, frame, i, 0);
            for e in 0..ne {
                let (q2, v2) = self.node(y, frame, i, e + 1);
                let q = [q1[0], q1[1], q1[2], q2[0], q2[1], q2[2]];
                let mut st = el.state(&q);
                if beta_a > 0.0 || beta_b > 0.0 {
                    let [c, s] = st.direction;
                    let (dvx, dvy) = (v2[0] - v1[0], v2[1] - v1[1]);
                    let stretch_rate = c * dvx + s * dvy;
                    let beta_rate = (c * dvy - s * dvx) / st.chord_length;
                    let (w1, w2) = (v1[2] - beta_rate, v2[2] - beta_rate);
                    st.axial_force += beta_a * el.axial_stiffness * stretch_rate / el.length;
                    let k = beta_b * 2.0 * el.bending_stiffness / el.length;
                    st.moments[0] += k * (2.0 * w1 + w2);
                    st.moments[1] += k * (w1 + 2.0 * w2);
                }
                let fe = CorotationalElement::force_from_state(&st);
                for (j, v) in fe.iter().enumerate() {
                    f[3 * e + j] += v;
                }
                (q1, v1) = (q2, v2);
            }
        }
        self.forces = forces;
        self.apply_point_loads(frame);
        self.apply_patches(y, frame);
    }
    /// The collapse checks of [`NonlinearOptions`] at `(t, y)`: the margin (negative while
    /// no check fires: the largest of the most deflected link's deflection over its limit,
    /// minus one, and one minus the type-II measure over its threshold; NaN for a NaN
    /// measure) and the collapse it describes.
    pub(super) fn collapse_margin(&self, t: f64, y: &[f64], frame: &Frame) -> (f64, DynamicsError) {
        let measure = self.measure(frame);
        let w = self.midpoint_deflections(y, frame);
        let lengths: [f64; 3] = std::array::from_fn(|i| self.machine.links[i].length());
        let mut margin = f64::NEG_INFINITY;
        if let Some(f) = self.options.collapse_deflection {
            for i in 0..3 {
                margin = margin.max(w[i].abs() / (f * lengths[i]) - 1.0);
            }
        }
        if self.options.stop_at_type_ii {
            let threshold = self.machine.geometry.thresholds.type_ii;
            margin = if measure.is_nan() {
                f64::NAN
            } else {
                margin.max(1.0 - measure / threshold)
            };
        }
        let (link, deflection) =
            (0..3).map(|i| (i, w[i])).fold(
                (0, 0.0_f64),
                |a, b| if b.1.abs() > a.1.abs() { b } else { a },
            );
        let collapse = DynamicsError::Collapse {
            t,
            link: link + 1,
            deflection,
            length: lengths[link],
            type_ii_measure: measure,
        };
        (margin, collapse)
    }
    /// Accelerations `z''` into `acc` (the second block of `dy`): assembles and solves
    /// `M z'' = F` (`self.forces` and the actuators' forces must be assembled).
    pub(in crate::nonlinear) fn accelerations(
        &mut self,
        t: f64,
        y: &[f64],
        frame: &Frame,
        acc: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.assemble_equations(y, frame);
        self.solve_equations(t, acc)
    }
    /// The residual `M(z) acc - F(t, z, z')` of the equations of motion at `(t, y)` into
    /// `out` (the mechanical form's residual: no solve with the mass); NaN and a recorded
    /// failure where the right-hand side would fail.
    pub(in crate::nonlinear) fn motion_residual(
        &mut self,
        t: f64,
        y: &[f64],
        acc: &[f64],
        out: &mut [f64],
    ) {
        self.counters.rhs_evaluations += 1;
        let frame = match self.frame(t, y) {
            Ok(f) => f,
            Err(e) => return self.fail(e, y, out),
        };
        self.assemble(y, &frame);
        // The form exists only without a control law's states: no rates to write.
        if let Err(e) = self.actuate(t, y, &frame, &mut []) {
            return self.fail(e, y, out);
        }
        self.assemble_equations(y, &frame);
        self.equations_residual(acc, out);
    }
    /// Records `error` and writes NaN so the integrator rejects the trial. The record is
    /// the latest failure met since the last accepted step (the one closest to where the
    /// integration stopped) at a finite state: a stage built from an earlier stage's NaN
    /// fails only as a consequence, and does not replace the cause.
    pub(super) fn fail(&mut self, error: DynamicsError, y: &[f64], dy: &mut [f64]) {
        if self.failure.is_none() || y.iter().all(|v| v.is_finite()) {
            self.failure = Some(error);
        }
        dy.fill(f64::NAN);
    }
}

impl OdeSystem for NonlinearSystem {
    fn dim(&self) -> usize {
        self.actuated
            .as_ref()
            .map_or(2 * self.coordinates(), Actuated::dim)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.counters.rhs_evaluations += 1;
        if let Some(e) = self.actuated.as_ref().and_then(|a| a.failure_at(t)) {
            return self.fail(e, y, dy);
        }
        let frame = match self.frame(t, y) {
            Ok(f) => f,
            Err(e) => return self.fail(e, y, dy),
        };
        self.assemble(y, &frame);
        let n = self.coordinates();
        let (dz, rest) = dy.split_at_mut(n);
        let (dzd, rates) = rest.split_at_mut(n);
        dz.copy_from_slice(&y[n..2 * n]);
        if let Err(e) = self.actuate(t, y, &frame, rates) {
            return self.fail(e, y, dy);
        }
        if let Err(e) = self.accelerations(t, y, &frame, dzd) {
            self.fail(e, y, dy);
        }
    }

    /// The natural scales of the absolute coordinates (positions: the link length; angles:
    /// one radian), so that a node or a link angle passing the frame's origin or zero does
    /// not tighten the error test (`OdeSystem::tolerance_scales`). Velocities and the
    /// controller's states keep their own values.
    fn tolerance_scales(&self, scales: &mut [f64]) -> bool {
        scales.fill(0.0);
        let lengths: [f64; 3] =
            std::array::from_fn(|i| self.links[i].element.length * self.options.elements as f64);
        let mean = lengths.iter().sum::<f64>() / 3.0;
        scales[0] = mean;
        scales[1] = mean;
        scales[2] = 1.0;
        for (link, length) in lengths.iter().enumerate() {
            for (k, scale) in scales[self.link_range(link)].iter_mut().enumerate() {
                // psi_0, (x_k, y_k, psi_k) for k = 1..N-1, psi_N
                *scale = if k == 0 || k % 3 == 0 || k + 1 == self.per_link {
                    1.0
                } else {
                    *length
                };
            }
        }
        if self.actuated.is_some() {
            for i in 0..3 {
                scales[self.slider_index(i)] = mean;
            }
        }
        true
    }

    /// A sampled controller's next sample ([`NonlinearSystem::next_sample`]).
    fn next_stop(&self, t: f64) -> Option<f64> {
        self.next_sample(t)
    }

    /// A failure met in a rejected trial is forgotten once a step is accepted.
    fn step_accepted(&mut self, _t: f64, _y: &[f64]) {
        self.failure = None;
    }

    /// The collapse checks ([`NonlinearOptions::collapse_deflection`],
    /// [`NonlinearOptions::stop_at_type_ii`]) as a terminal event, decided on accepted
    /// states only; where it is reached the collapse is recorded for
    /// [`NonlinearSystem::take_failure`]. None without checks; where the commanded motion
    /// itself fails (the right-hand side reports that), not reached.
    fn terminal_event(&mut self, t: f64, y: &[f64]) -> Option<f64> {
        if !(self.options.stop_at_type_ii || self.options.collapse_deflection.is_some())
            || y.len() != self.dim()
        {
            return None;
        }
        let Ok(frame) = self.frame(t, y) else {
            return Some(-1.0);
        };
        let (margin, collapse) = self.collapse_margin(t, y, &frame);
        if margin >= 0.0 || margin.is_nan() {
            self.failure = Some(collapse);
        }
        Some(margin)
    }

    /// The mechanical form for implicit integrators (super::tangent); none when a
    /// continuous control law adds first-order states.
    fn second_order_form(&mut self) -> Option<&mut dyn flexprr_integrators::SecondOrderForm> {
        if self.actuated.as_ref().is_some_and(|a| a.ode_states() > 0) {
            return None;
        }
        Some(self)
    }

    /// A sampled controller takes its sample when a segment starts at one of its sample
    /// times (they are stop times: [`NonlinearSystem::next_sample`]).
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        if y.len() != self.dim() {
            return;
        }
        if self.patches.is_some() {
            if let Ok(frame) = self.frame(t, y) {
                self.sense_patches(y, &frame);
                if let Some((law, _)) = self.patches.as_mut() {
                    law.sample(t);
                }
            }
        }
        if let Some(actuated) = self.actuated.as_mut() {
            actuated.sample_at(&self.machine, self.trajectory.as_ref(), t, y);
        }
    }
}
