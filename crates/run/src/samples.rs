//! The rigid-body data every output kind shares, computed once per output time: the
//! platform motion, the closed-form inverse kinematics and, when an output needs them, the
//! rigid joint reactions.

use flexprr_dynamics::{DynamicsError, JointReactions, Machine, inverse_dynamics};
use flexprr_kinematics::{MachineState, PlatformMotion};
use flexprr_scene::Scene;

/// Motion and kinematics at every output time reached.
pub(crate) struct Samples {
    /// Output times (s).
    pub t: Vec<f64>,
    /// Platform motion at each time.
    pub motions: Vec<PlatformMotion>,
    /// Inverse kinematics at each time.
    pub states: Vec<MachineState>,
    /// Rigid joint reactions at each time, when computed.
    pub reactions: Option<Vec<JointReactions>>,
}

impl Samples {
    /// The motion and inverse kinematics of `scene` at `t`.
    ///
    /// # Errors
    /// A pose the inverse kinematics cannot reach, with its time.
    pub fn new(scene: &Scene, t: &[f64]) -> Result<Self, DynamicsError> {
        let mut motions = Vec::with_capacity(t.len());
        let mut states = Vec::with_capacity(t.len());
        for &tk in t {
            let motion = scene.trajectory.motion(tk);
            let state = scene
                .machine
                .geometry
                .inverse_kinematics_unchecked(&motion)
                .map_err(|source| DynamicsError::Kinematics { t: tk, source })?;
            motions.push(motion);
            states.push(state);
        }
        Ok(Self {
            t: t.to_vec(),
            motions,
            states,
            reactions: None,
        })
    }

    /// Computes the rigid joint reactions at every time (once).
    ///
    /// # Errors
    /// A singular pose, with its time.
    pub fn with_reactions(
        &mut self,
        machine: &Machine,
    ) -> Result<&[JointReactions], DynamicsError> {
        if self.reactions.is_none() {
            let reactions = self
                .states
                .iter()
                .zip(&self.t)
                .map(|(state, &tk)| inverse_dynamics(machine, state, None, tk))
                .collect::<Result<Vec<_>, _>>()?;
            self.reactions = Some(reactions);
        }
        Ok(self.reactions.as_deref().unwrap_or(&[]))
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
}
