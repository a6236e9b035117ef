//! The state layout of the nonlinear model: its rigid initial state and the check of a
//! state's length.

use super::*;

impl NonlinearSystem {
    /// The rigid initial state at `t0`: straight, unstrained links on the rigid chords with
    /// the rigid velocity field, the platform on its nominal pose and velocity.
    ///
    /// # Errors
    /// The rigid inverse kinematics fails at `t0`.
    pub fn initial_state(&self, t0: f64) -> Result<Vec<f64>, DynamicsError> {
        let nominal = self.trajectory.motion(t0);
        let rigid = self
            .machine
            .geometry
            .inverse_kinematics_unchecked(&nominal)
            .map_err(|source| DynamicsError::Kinematics { t: t0, source })?;
        let n = self.coordinates();
        let mut y = vec![0.0; self.dim()];
        if let Some(actuated) = &self.actuated {
            actuated.start(&rigid, &mut y);
        }
        let (z, zd) = y[..2 * n].split_at_mut(n);
        let p = nominal.pose;
        z[..3].copy_from_slice(&[p.x, p.y, p.phi]);
        zd[..3].copy_from_slice(nominal.velocity.as_slice());
        let ne = self.options.elements;
        for (i, leg) in rigid.legs.iter().enumerate() {
            let off = 3 + i * self.per_link;
            let le = self.links[i].element.length;
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            let b_dot = leg.rho_dot * u;
            z[off] = leg.beta;
            zd[off] = leg.beta_dot;
            for k in 1..ne {
                let x = k as f64 * le;
                let pos = leg.b.coords + x * leg.e;
                let vel = b_dot + x * leg.beta_dot * leg.n;
                let j = off + 3 * k - 2;
                z[j..j + 3].copy_from_slice(&[pos.x, pos.y, leg.beta]);
                zd[j..j + 3].copy_from_slice(&[vel.x, vel.y, leg.beta_dot]);
            }
            z[off + 3 * ne - 2] = leg.beta;
            zd[off + 3 * ne - 2] = leg.beta_dot;
        }
        Ok(y)
    }
    /// Sets the initial state of the integration to the rigid state at `t0`
    /// ([`NonlinearSystem::initial_state`]); [`crate::SceneModel::initial_state`] returns it.
    ///
    /// # Errors
    /// The rigid inverse kinematics fails at `t0`.
    pub fn start_at(&mut self, t0: f64) -> Result<(), DynamicsError> {
        self.initial = self.initial_state(t0)?;
        Ok(())
    }
    pub(super) fn check_state(&self, y: &[f64]) -> Result<(), DynamicsError> {
        if y.len() != self.dim() {
            return Err(DynamicsError::Dimension {
                what: "state",
                unit: "entries",
                model: "nonlinear system",
                found: y.len(),
                expected: self.dim(),
            });
        }
        Ok(())
    }
}
