//! The coupled model ([`CoupledSystem`]) as a scene model: sliders on their commanded path,
//! the platform moved by the links' foreshortening, the chord tensions as the actual axial
//! forces (docs/coupled.md). Its own tables: the platform deviation with the quasi-static
//! axial stretch, and the chord forces with the largest chord shortening.

use flexprr_integrators::Solution;

use crate::model::{
    ControlLaws, LinearHints, LoadInput, PatchReadout, force_table, modal_energies,
    platform_deviation_table,
};
use crate::{
    Column, CoupledSystem, DynamicsError, Machine, MachineSnapshot, ModelCounters, ModelEnergies,
    Quantity as Q, SceneModel, SliderMotion, Table,
};

/// Largest deflection of a coupled run, as a fraction of the link length, beyond which the
/// run warns and recommends the nonlinear model. Measured on the paper scene at 30 Hz
/// (docs/coupled.md, "Which model when"): the coupled mid-point deflections leave 5 %
/// (relative L2 over 10 ms windows) of the nonlinear model's when the largest deflection has
/// reached 11 % of the link length, and are within 1 % of it up to 5 %. The warning comes at
/// 5 %: the coupled results are still good there, and a collapsing run is told early (at
/// 30 Hz the largest deflection passes 5 % at about 11 ms, the 10 % collapse limit at 29.8 ms).
pub const NONLINEAR_ADVICE_FRACTION: f64 = 0.05;

impl SceneModel for CoupledSystem {
    fn kind(&self) -> &'static str {
        "coupled"
    }
    fn machine(&self) -> &Machine {
        CoupledSystem::machine(self)
    }
    /// The modal coordinates, and the sliders when they are actuated.
    fn modes(&self) -> usize {
        self.coordinates()
    }
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        CoupledSystem::link_range(self, link)
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        CoupledSystem::take_failure(self)
    }
    fn counters(&self) -> ModelCounters {
        let c = CoupledSystem::counters(self);
        ModelCounters {
            rhs_evaluations: c.rhs_evaluations,
            inverse_dynamics_solves: c.inverse_dynamics_solves,
        }
    }
    fn initial_state(&self) -> Vec<f64> {
        CoupledSystem::initial_state(self)
    }
    fn snapshot(&mut self, t: f64, y: &[f64]) -> Result<MachineSnapshot, DynamicsError> {
        let out = self.output(t, y)?;
        let rho = out.slider;
        Ok(MachineSnapshot {
            t,
            nominal: out.nominal,
            platform: out.platform,
            sliders: rho.map(|r| SliderMotion {
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
    /// The modal energies and the kinetic energy of the whole machine: sliders (with the
    /// actuators' reflected inertia), platform, and each link's
    /// `int rhoA |r'|^2 / 2 dx` for `r' = rho' u + x b' n + w' n - w b' e` (the velocity of the
    /// model's link points, foreshortening left out as in its equations):
    /// `m rho'^2 / 2 + I_B b'^2 / 2 + (m l / 2) rho' b' sin(a - b) + eta'^T M eta' / 2
    /// + b'^2 eta^T M eta / 2 + rho' sin(a - b) m_psi.eta' - rho' b' cos(a - b) m_psi.eta
    /// + l b' m_xipsi.eta'`.
    fn energies(&mut self, t: f64, y: &[f64]) -> Result<ModelEnergies, DynamicsError> {
        let out = self.output(t, y)?;
        let mut energies = modal_energies(self, y);
        let slider_mass = self.slider_masses();
        let (n, coordinates) = (CoupledSystem::modes(self), self.coordinates());
        let machine = self.machine();
        let v = out.platform.velocity;
        let mut kinetic = 0.5
            * (machine.platform_mass * (v.x * v.x + v.y * v.y)
                + machine.platform_inertia * v.z * v.z);
        for i in 0..3 {
            let link = &machine.links[i];
            let ints = &link.integrals;
            let range = self.link_range(i);
            let (eta, rate) = (
                &y[range.clone()],
                &y[coordinates + range.start..coordinates + range.end],
            );
            let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
            let (mass, l) = (link.mass(), link.length());
            let inertia_b = link.centroid_inertia + 0.25 * mass * l * l;
            let rho_dot = out.slider[i][1];
            let b_dot = out.chord_angle[i][1];
            let u = machine.geometry.legs[i].guide.direction.into_inner();
            let angle = out.chord_angle[i][0];
            let (e, nrm) = (
                nalgebra::Vector2::new(angle.cos(), angle.sin()),
                nalgebra::Vector2::new(-angle.sin(), angle.cos()),
            );
            let (sin_ab, cos_ab) = (u.dot(&nrm), u.dot(&e));
            let m_eta: f64 = (0..eta.len())
                .map(|j| {
                    eta[j]
                        * (0..eta.len())
                            .map(|k| ints.mass[(j, k)] * eta[k])
                            .sum::<f64>()
                })
                .sum();
            kinetic += 0.5 * slider_mass[i] * rho_dot * rho_dot
                + 0.5 * mass * rho_dot * rho_dot
                + 0.5 * inertia_b * b_dot * b_dot
                + 0.5 * mass * l * rho_dot * b_dot * sin_ab
                + energies.elastic_kinetic.map_or(0.0, |k| k[i])
                + 0.5 * b_dot * b_dot * m_eta
                + rho_dot * sin_ab * dot(&ints.mass_psi, rate)
                - rho_dot * b_dot * cos_ab * dot(&ints.mass_psi, eta)
                + l * b_dot * dot(&ints.mass_xi_psi, rate);
        }
        let _ = n;
        energies.kinetic = Some(kinetic);
        Ok(energies)
    }
    /// `platform_deviation` (`dx`, `dy`, `dphi`, and the same with the quasi-static axial
    /// stretch) and `coupled_forces` (`P_B`, `P_C`, `F_a` per link, the largest chord
    /// shortening).
    fn tables(&mut self, solution: &Solution) -> Result<Vec<Table>, DynamicsError> {
        let n_out = solution.len();
        let mut snapshots = Vec::with_capacity(n_out);
        let mut stretched: [Vec<f64>; 3] = Default::default();
        let mut shortening = Vec::with_capacity(n_out);
        for k in 0..n_out {
            let (t, y) = (solution.t[k], solution.y(k));
            let out = self.output(t, y)?;
            for (column, value) in stretched.iter_mut().zip(out.pose_deviation_with_stretch()) {
                column.push(value);
            }
            let delta = self.chord_shortening(&y[..CoupledSystem::modes(self)]);
            shortening.push(delta.iter().fold(0.0, |m: f64, d| m.max(*d)));
            snapshots.push(self.snapshot(t, y)?);
        }
        let mut pose = platform_deviation_table(&solution.t, &snapshots);
        let [dx, dy, dphi] = stretched;
        pose.push(Column::of(Q::DeviationXWithStretch), dx);
        pose.push(Column::of(Q::DeviationYWithStretch), dy);
        pose.push(Column::of(Q::DeviationPhiWithStretch), dphi);
        let mut forces = force_table("coupled_forces", &solution.t, &snapshots);
        forces.push(Column::of(Q::MaxChordShortening), shortening);
        Ok(vec![pose, forces])
    }
    fn deflection_advice(&self, max_deflection: f64) -> Option<String> {
        let length = self.machine().links[0].length();
        let fraction = max_deflection / length;
        (fraction > NONLINEAR_ADVICE_FRACTION).then(|| {
            format!(
                "the largest link deflection reached {:.1} mm ({:.1} % of the link length, above {:.0} %): \
                 the coupled model assumes small deflections and drifts from a geometrically exact one \
                 beyond this; rerun with model.coupling = \"nonlinear\" (docs/coupled.md)",
                max_deflection * 1e3,
                100.0 * fraction,
                100.0 * NONLINEAR_ADVICE_FRACTION
            )
        })
    }
}

impl PatchReadout for CoupledSystem {
    fn patch_count(&self) -> usize {
        CoupledSystem::patch_count(self)
    }
    fn patch_states(&mut self, t: f64, y: &[f64]) -> Result<Vec<crate::PatchState>, DynamicsError> {
        Ok(CoupledSystem::patch_states(self, t, y))
    }
}

impl LoadInput for CoupledSystem {
    fn set_loads(&mut self, loads: &crate::ExternalLoads) -> Result<(), DynamicsError> {
        CoupledSystem::set_loads(self, loads)
    }
}

/// The chords relax into axial springs at rest; the platform follows the links.
impl LinearHints for CoupledSystem {
    fn chord_compliance(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<crate::ChordCompliance>, DynamicsError> {
        CoupledSystem::chord_compliance(self, t, y)
    }
    fn platform_follows_links(&self) -> bool {
        true
    }
}

impl ControlLaws for CoupledSystem {
    fn actuation(&self) -> Option<&crate::Actuation> {
        CoupledSystem::actuation(self)
    }
    fn sampled_laws(&self, t: f64) -> crate::SampledLaws {
        CoupledSystem::sampled_laws(self, t)
    }
    fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<crate::LawSample, DynamicsError> {
        CoupledSystem::law_sample(self, t, y, slider_states)
    }
}
