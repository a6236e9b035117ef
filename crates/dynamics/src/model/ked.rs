//! The KED modal system ([`ModalSystem`]) as a scene model: the platform and the sliders
//! follow the commanded motion; the axial forces are those of the scene's axial force model
//! (model.md section 5); the driving forces are the rigid inverse dynamics with the links'
//! elastic inertia (model.md section 4).

use crate::{
    DynamicsError, Machine, MachineSnapshot, ModalSystem, ModelCounters, PatchReadout, SceneModel,
    SliderMotion, end_forces, inverse_dynamics,
};

impl SceneModel for ModalSystem {
    fn kind(&self) -> &'static str {
        "ked"
    }
    fn machine(&self) -> &Machine {
        ModalSystem::machine(self)
    }
    fn modes(&self) -> usize {
        ModalSystem::modes(self)
    }
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        ModalSystem::link_range(self, link)
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        ModalSystem::take_failure(self)
    }
    fn counters(&self) -> ModelCounters {
        let c = ModalSystem::counters(self);
        ModelCounters {
            rhs_evaluations: c.rhs_evaluations,
            inverse_dynamics_solves: c.inverse_dynamics_solves,
        }
    }
    /// The commanded motion, the axial model's end forces, and the driving forces of the
    /// rigid inverse dynamics with the elastic inertia of the modal accelerations at `y`.
    fn snapshot(&mut self, t: f64, y: &[f64]) -> Result<MachineSnapshot, DynamicsError> {
        let instant = self.instant(t)?;
        let acceleration = self.modal_accelerations(t, y)?;
        let elastic = self.elastic_inertia(&acceleration);
        self.count_inverse_dynamics();
        let machine = ModalSystem::machine(self);
        let reactions = inverse_dynamics(machine, &instant.state, Some(&elastic), t)?;
        let ends: [(f64, f64); 3] =
            std::array::from_fn(|i| end_forces(&instant.loads[i], machine.links[i].length()));
        let legs = &instant.state.legs;
        Ok(MachineSnapshot {
            t,
            nominal: instant.state.motion,
            platform: instant.state.motion,
            sliders: std::array::from_fn(|i| SliderMotion {
                position: legs[i].rho,
                velocity: legs[i].rho_dot,
                acceleration: legs[i].rho_ddot,
            }),
            axial_force_b: ends.map(|e| e.0),
            axial_force_c: ends.map(|e| e.1),
            driving_force: reactions.driving_force,
            actuators: None,
        })
    }
    fn patches(&mut self) -> Option<&mut dyn PatchReadout> {
        Some(self)
    }
}

impl PatchReadout for ModalSystem {
    fn patch_count(&self) -> usize {
        ModalSystem::patch_count(self)
    }
    fn patch_states(&mut self, t: f64, y: &[f64]) -> Result<Vec<crate::PatchState>, DynamicsError> {
        Ok(ModalSystem::patch_states(self, t, y))
    }
}
