//! Axial force models: the tension `P(x) = P0 + P1 x + P2 x^2` along each link
//! (model.md section 5; tension positive, `x` from `B_i`).
//!
//! Both non-trivial models share the distributed inertia part of eq. (11),
//! `rhoA (rho'' cos(b - a) x - b'^2 x^2 / 2)`, and differ in the end force at `B`:
//! * [`PaperAxialForce`] (eq. 12): `(m_s rho'' - F_a) cos(b - a) = -(F_B.u) cos(b - a)`, only the
//!   along-guide part of the slider's force on the link;
//! * [`JointReactionAxialForce`]: `-F_B.e`, the whole reaction projected on the link.

use flexprr_beam::AxialLoad;
use flexprr_kinematics::LegKinematics;
use nalgebra::Vector2;

use crate::{JointReactions, LinkModel};

/// Everything an axial force model may read for one link at one instant.
#[derive(Debug, Clone, Copy)]
pub struct AxialInput<'a> {
    /// Kinematic state of the leg (a `&LegState` coerces to it).
    pub leg: &'a LegKinematics,
    /// Guide direction `u_i`.
    pub guide_direction: Vector2<f64>,
    /// The link.
    pub link: &'a LinkModel,
    /// Rigid joint reactions (present when the model asked for inverse dynamics).
    pub reactions: Option<&'a JointReactions>,
    /// Leg index (0-based).
    pub index: usize,
}

/// A model of the axial force in a link.
///
/// # Implementing
/// A constant pretension `P0` in every link (a bolted-in preload, say). For the first sine
/// mode of a pinned-pinned link the frequency under a uniform tension is the closed form
/// `f = f0 sqrt(1 + P0 / P_cr)` with `P_cr = pi^2 EI / l^2` (Timoshenko & Young, *Vibration
/// Problems in Engineering*, section 5.12), which the beam layer reproduces from the load:
///
/// ```
/// use std::sync::Arc;
/// use flexprr_beam::{AxialLoad, Coupling, SineBasis, UniformSection, frequencies};
/// use flexprr_dynamics::{AxialForceModel, AxialInput, LinkModel};
/// use flexprr_kinematics::LegKinematics;
/// use nalgebra::Vector2;
///
/// #[derive(Debug)]
/// struct Pretension(f64);
///
/// impl AxialForceModel for Pretension {
///     fn name(&self) -> &'static str {
///         "pretension"
///     }
///     fn needs_inverse_dynamics(&self) -> bool {
///         false
///     }
///     fn load(&self, _input: &AxialInput<'_>) -> AxialLoad {
///         AxialLoad::uniform(self.0)
///     }
/// }
///
/// let (e, t, h, l) = (7.3e10, 0.002, 0.03, 0.2);
/// let section = UniformSection::rectangle(e, 2770.0, t, h).unwrap();
/// let link = LinkModel::new(Arc::new(SineBasis::new(1).unwrap()), &section, l).unwrap();
/// let leg = LegKinematics::default();
/// let input = AxialInput {
///     leg: &leg,
///     guide_direction: Vector2::x(),
///     link: &link,
///     reactions: None,
///     index: 0,
/// };
/// let model = Pretension(100.0);
/// let load = model.load(&input);
/// let loaded = frequencies(&link.integrals, &load, Coupling::Full).unwrap();
/// let free = frequencies(&link.integrals, &AxialLoad::uniform(0.0), Coupling::Full).unwrap();
/// let p_cr = std::f64::consts::PI.powi(2) * (e * h * t.powi(3) / 12.0) / (l * l);
/// let expected = free.modes[0].frequency_hz * (1.0 + 100.0 / p_cr).sqrt();
/// assert!((loaded.modes[0].frequency_hz - expected).abs() <= 1e-10 * expected);
/// ```
pub trait AxialForceModel: std::fmt::Debug + Send + Sync {
    /// Name used in outputs (`"none"`, `"paper"`, `"joint-reaction"`, the scene-file spelling).
    fn name(&self) -> &'static str;
    /// Whether [`AxialForceModel::load`] needs the rigid joint reactions.
    fn needs_inverse_dynamics(&self) -> bool;
    /// Coefficients of `P(x)` for one link.
    fn load(&self, input: &AxialInput<'_>) -> AxialLoad;
}

/// No axial force: `P = 0` (the model of Zhang et al.'s earlier paper).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoAxialForce;

/// The paper's axial force, eq. (12).
#[derive(Debug, Clone, Copy, Default)]
pub struct PaperAxialForce;

/// The joint-reaction form of model.md section 5.
#[derive(Debug, Clone, Copy, Default)]
pub struct JointReactionAxialForce;

/// The shared inertia part `P1 x + P2 x^2` of eq. (11).
#[inline]
fn inertia_part(input: &AxialInput<'_>) -> (f64, f64) {
    let rho_a = input.link.mass_per_length();
    let cos_ba = input.leg.e.dot(&input.guide_direction);
    (
        rho_a * input.leg.rho_ddot * cos_ba,
        -0.5 * rho_a * input.leg.beta_dot * input.leg.beta_dot,
    )
}

impl AxialForceModel for NoAxialForce {
    fn name(&self) -> &'static str {
        "none"
    }
    fn needs_inverse_dynamics(&self) -> bool {
        false
    }
    fn load(&self, _input: &AxialInput<'_>) -> AxialLoad {
        AxialLoad {
            p0: 0.0,
            p1: 0.0,
            p2: 0.0,
        }
    }
}

impl AxialForceModel for PaperAxialForce {
    fn name(&self) -> &'static str {
        "paper"
    }
    fn needs_inverse_dynamics(&self) -> bool {
        true
    }
    fn load(&self, input: &AxialInput<'_>) -> AxialLoad {
        let (p1, p2) = inertia_part(input);
        let f_b = input
            .reactions
            .map_or(Vector2::zeros(), |r| r.slider_on_link[input.index]);
        let cos_ba = input.leg.e.dot(&input.guide_direction);
        AxialLoad {
            p0: -f_b.dot(&input.guide_direction) * cos_ba,
            p1,
            p2,
        }
    }
}

impl AxialForceModel for JointReactionAxialForce {
    fn name(&self) -> &'static str {
        "joint-reaction"
    }
    fn needs_inverse_dynamics(&self) -> bool {
        true
    }
    fn load(&self, input: &AxialInput<'_>) -> AxialLoad {
        let (p1, p2) = inertia_part(input);
        let f_b = input
            .reactions
            .map_or(Vector2::zeros(), |r| r.slider_on_link[input.index]);
        AxialLoad {
            p0: -f_b.dot(&input.leg.e),
            p1,
            p2,
        }
    }
}

/// The axial force at both ends, `(P(0), P(l))` (N).
pub fn end_forces(load: &AxialLoad, length: f64) -> (f64, f64) {
    (
        load.p0,
        load.p0 + load.p1 * length + load.p2 * length * length,
    )
}
