//! The geometrically nonlinear model ([`NonlinearSystem`]) as a scene model: its coordinates
//! are node positions and angles, not modal amplitudes, so its deflection (from the deformed
//! chord, which needs the time), energies and tables come from the model's own output.

use flexprr_integrators::{OdeSystem, Solution};

use crate::model::{
    ControlLaws, LinearHints, LoadInput, PatchReadout, force_table, platform_deviation_table,
};
use crate::{
    Column, DynamicsError, Machine, MachineSnapshot, ModelCounters, ModelEnergies, NonlinearSystem,
    Quantity as Q, SceneModel, SliderMotion, Table,
};

impl SceneModel for NonlinearSystem {
    fn kind(&self) -> &'static str {
        "nonlinear"
    }
    fn machine(&self) -> &Machine {
        NonlinearSystem::machine(self)
    }
    /// The generalized coordinates (platform pose and every link's nodal coordinates).
    fn modes(&self) -> usize {
        self.coordinates()
    }
    /// Link `link`'s nodal coordinates (the platform's three come first).
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        NonlinearSystem::link_range(self, link)
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        NonlinearSystem::take_failure(self)
    }
    fn counters(&self) -> ModelCounters {
        ModelCounters {
            rhs_evaluations: NonlinearSystem::counters(self).rhs_evaluations,
            inverse_dynamics_solves: 0,
        }
    }
    fn snapshot(&mut self, t: f64, y: &[f64]) -> Result<MachineSnapshot, DynamicsError> {
        let out = self.output(t, y)?;
        Ok(MachineSnapshot {
            t,
            nominal: out.nominal,
            platform: out.platform,
            sliders: out.slider.map(|r| SliderMotion {
                position: r[0],
                velocity: r[1],
                acceleration: r[2],
            }),
            axial_force_b: out.axial_force_b,
            axial_force_c: out.axial_force_c,
            driving_force: out.driving_force,
            actuators: out.actuators,
        })
    }
    /// The rigid state set by [`NonlinearSystem::start_at`] (at `t = 0` when it was not
    /// called; NaN, which every integrator refuses, when the kinematics fails there).
    fn initial_state(&self) -> Vec<f64> {
        let start = self.start_state();
        if start.len() == self.dim() {
            return start.to_vec();
        }
        NonlinearSystem::initial_state(self, 0.0).unwrap_or_else(|_| vec![f64::NAN; self.dim()])
    }
    /// From the chord of the deflected link ([`NonlinearSystem::deflection_at`]).
    fn deflection(&self, t: f64, link: usize, xi: f64, y: &[f64]) -> Result<f64, DynamicsError> {
        self.deflection_at(t, link, xi, y)
    }
    /// The slope of the deflection from the chord, by the derivative of the element's
    /// cubic Hermite centre line ([`NonlinearSystem::slope_at`]).
    fn slope(&self, t: f64, link: usize, xi: f64, y: &[f64]) -> Result<f64, DynamicsError> {
        self.slope_at(t, link, xi, y)
    }
    fn patches(&mut self) -> Option<&mut dyn PatchReadout> {
        Some(self)
    }
    fn loads(&mut self) -> Option<&mut dyn LoadInput> {
        Some(self)
    }
    fn linear_hints(&self) -> Option<&dyn LinearHints> {
        Some(self)
    }
    fn linear_hints_mut(&mut self) -> Option<&mut dyn LinearHints> {
        Some(self)
    }
    fn control(&self) -> Option<&dyn ControlLaws> {
        Some(self)
    }
    fn control_mut(&mut self) -> Option<&mut dyn ControlLaws> {
        Some(self)
    }
    /// The kinetic energy of the nodes and the platform, the strain energy of each link.
    fn energies(&mut self, t: f64, y: &[f64]) -> Result<ModelEnergies, DynamicsError> {
        let out = self.output(t, y)?;
        Ok(ModelEnergies {
            kinetic: Some(out.kinetic_energy),
            strain: out.link_strain_energy,
            elastic_kinetic: None,
        })
    }
    /// `platform_deviation` (`dx`, `dy`, `dphi`) and `nonlinear_forces` (`P_B`, `P_C`, `F_a`
    /// per link, the chords' type-II measure).
    fn tables(&mut self, solution: &Solution) -> Result<Vec<Table>, DynamicsError> {
        let n_out = solution.len();
        let mut snapshots = Vec::with_capacity(n_out);
        let mut measure = Vec::with_capacity(n_out);
        for k in 0..n_out {
            let (t, y) = (solution.t[k], solution.y(k));
            measure.push(self.output(t, y)?.type_ii_measure);
            snapshots.push(self.snapshot(t, y)?);
        }
        let pose = platform_deviation_table(&solution.t, &snapshots);
        let mut forces = force_table("nonlinear_forces", &solution.t, &snapshots);
        forces.push(Column::of(Q::TypeIIMeasure), measure);
        Ok(vec![pose, forces])
    }
}

impl PatchReadout for NonlinearSystem {
    fn patch_count(&self) -> usize {
        NonlinearSystem::patch_count(self)
    }
    fn patch_states(&mut self, t: f64, y: &[f64]) -> Result<Vec<crate::PatchState>, DynamicsError> {
        NonlinearSystem::patch_states(self, t, y)
    }
}

impl LoadInput for NonlinearSystem {
    fn set_loads(&mut self, loads: &crate::ExternalLoads) -> Result<(), DynamicsError> {
        NonlinearSystem::set_loads(self, loads)
    }
}

/// Nodal coordinates: the deflection needs the time, the platform follows the links, the
/// tangents are exact at rest.
impl LinearHints for NonlinearSystem {
    /// At rest without actuation or patches: the tangents leave out only terms that vanish
    /// there (the platform's centripetal acceleration, the damping forces' change with the
    /// element rotations, the inertia forces' derivatives at zero acceleration), while the
    /// actuators' derivatives are differences of the control law and the patches' feedback
    /// is not in them (crates/dynamics/src/nonlinear/tangent.rs).
    fn exact_mechanical_form(&mut self, t: f64, y: &[f64]) -> bool {
        let n = self.coordinates();
        if NonlinearSystem::actuation(self).is_some() || y.len() != 2 * n {
            return false;
        }
        if y[n..].iter().any(|v| *v != 0.0) {
            return false;
        }
        let motion = self.trajectory().motion(t);
        if motion
            .velocity
            .iter()
            .chain(motion.acceleration.iter())
            .any(|v| *v != 0.0)
        {
            return false;
        }
        NonlinearSystem::patch_states(self, t, y).is_ok_and(|p| p.is_empty())
    }
    fn linear_deflection(&self) -> bool {
        false
    }
    fn platform_follows_links(&self) -> bool {
        true
    }
    /// The platform's `x`, `y`, `phi`; each link's nodal coordinates (the first node's
    /// angle, the inner nodes' `x`, `y`, angle, the last node's angle); the sliders.
    fn coordinate_label(&self, k: usize) -> Option<(String, String)> {
        if k < 3 {
            let axis = ["x", "y", "phi"][k];
            return Some((format!("platform {axis}"), format!("platform_{axis}")));
        }
        for link in 0..3 {
            let range = NonlinearSystem::link_range(self, link);
            if range.contains(&k) {
                let j = k - range.start;
                let last = range.len() - 1;
                let (node, what) = match j {
                    0 => (0, "angle"),
                    j if j == last => (j.div_ceil(3), "angle"),
                    j => ((j - 1) / 3 + 1, ["x", "y", "angle"][(j - 1) % 3]),
                };
                let short = if what == "angle" { "theta" } else { what };
                return Some((
                    format!("link {}, node {node} {what}", link + 1),
                    format!("{short}_{}_{node}", link + 1),
                ));
            }
        }
        let i = k.saturating_sub(self.coordinates() - 3);
        Some((
            format!("position of slider {}", i + 1),
            format!("rho_{}", i + 1),
        ))
    }
}

impl ControlLaws for NonlinearSystem {
    fn actuation(&self) -> Option<&crate::Actuation> {
        NonlinearSystem::actuation(self)
    }
    fn sampled_laws(&self, t: f64) -> crate::SampledLaws {
        NonlinearSystem::sampled_laws(self, t)
    }
    fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<crate::LawSample, DynamicsError> {
        NonlinearSystem::law_sample(self, t, y, slider_states)
    }
}
