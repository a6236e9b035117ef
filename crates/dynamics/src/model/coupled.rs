//! The coupled model ([`CoupledSystem`]) as a scene model: sliders on their commanded path,
//! the platform moved by the links' foreshortening, the chord tensions as the actual axial
//! forces (docs/coupled.md). Its own tables: the platform deviation with the quasi-static
//! axial stretch, and the chord forces with the largest chord shortening.

use flexprr_integrators::Solution;

use crate::model::{force_table, platform_deviation_table};
use crate::{
    Column, CoupledSystem, DynamicsError, Machine, MachineSnapshot, ModelCounters, Quantity as Q,
    SceneModel, SliderMotion, Table,
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
    fn modes(&self) -> usize {
        CoupledSystem::modes(self)
    }
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        CoupledSystem::link_range(self, link)
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        CoupledSystem::take_failure(self)
    }
    fn counters(&self) -> ModelCounters {
        ModelCounters {
            rhs_evaluations: CoupledSystem::counters(self).rhs_evaluations,
            inverse_dynamics_solves: 0,
        }
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
        })
    }
    fn platform_follows_links(&self) -> bool {
        true
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
