//! The `auto` method: the exponential integrator for systems that are linear in the state,
//! generalized-alpha for mechanical systems, Adams-Bashforth-Moulton for every other system.

use super::{Magnus, MagnusOrder};
use crate::{
    Abm, DynIntegrator, GeneralizedAlpha, Interrupted, Observer, OdeSystem, Options, Solution,
};

/// Chooses the method per system: [`Magnus`] when [`OdeSystem::linear_form`] offers the linear
/// time-varying form (the KED modal equations), [`GeneralizedAlpha`] when
/// [`OdeSystem::second_order_form`] offers a mechanical form covering the whole state (the
/// nonlinear model: its stiff axial modes are damped, not resolved), [`Abm`] otherwise (the
/// coupled model, whose coefficients depend on the state, so the Magnus expansion of a
/// linear operator does not apply).
///
/// This is the one definition of `auto` in the workspace: the scene registry names the same
/// three methods ([`Auto::LINEAR`], [`Auto::MECHANICAL`], [`Auto::GENERAL`]) and resolves
/// `auto` at load from the model's capabilities, which predict the two forms this type asks
/// the system for, so a run records the method actually used.
///
/// The choice costs one call of `linear_form` and `second_order_form` per solve.
/// [`Auto::choose`] tells which method a system gets, so that a caller can record the method
/// actually used.
///
/// ```
/// use flexprr_integrators::{Auto, DynIntegrator, OdeSystem, Options};
///
/// /// y' = -y y: nonlinear, no linear form.
/// struct Riccati;
/// impl OdeSystem for Riccati {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = -y[0] * y[0]; }
/// }
/// let auto = Auto::new(Options::default().rtol(1e-10).atol(1e-12));
/// assert_eq!(auto.choose(&mut Riccati).name(), Auto::GENERAL);
/// // y(t) = 1 / (1 + t)
/// let sol = auto.solve_dyn(&mut Riccati, 0.0, &[1.0], &[0.0, 1.0], &[], &mut ()).unwrap();
/// assert!((sol.y(1)[0] - 0.5).abs() < 1e-8);
/// ```
#[derive(Debug, Clone)]
pub struct Auto {
    linear: Magnus,
    mechanical: GeneralizedAlpha,
    general: Abm,
}

impl Auto {
    /// Registered name of the method for systems linear in the state.
    pub const LINEAR: &'static str = "magnus6";
    /// Registered name of the method for systems with a mechanical form over the whole state.
    pub const MECHANICAL: &'static str = "generalized_alpha";
    /// Registered name of the method for every other system.
    pub const GENERAL: &'static str = "abm";

    /// `auto` with the 6th-order Magnus method for linear systems (the faster of the two
    /// orders on the KED scenes, see docs/performance.md), generalized-alpha for mechanical
    /// systems and ABM otherwise.
    pub fn new(options: Options) -> Self {
        Self::with_order(options, MagnusOrder::Six)
    }

    /// `auto` with the given Magnus order for linear systems.
    pub fn with_order(options: Options, order: MagnusOrder) -> Self {
        Self {
            linear: Magnus::new(options.clone(), order),
            mechanical: GeneralizedAlpha::new(options.clone()),
            general: Abm::new(options),
        }
    }

    /// The method `system` gets.
    pub fn choose(&self, system: &mut dyn OdeSystem) -> &dyn DynIntegrator {
        if system.linear_form().is_some() {
            return &self.linear;
        }
        let dim = system.dim();
        match system.second_order_form() {
            Some(form) if 2 * form.coordinates() == dim => &self.mechanical,
            _ => &self.general,
        }
    }
}

impl DynIntegrator for Auto {
    fn name(&self) -> &str {
        "auto"
    }

    fn options(&self) -> &Options {
        &self.general.options
    }

    fn solve_dyn(
        &self,
        system: &mut dyn OdeSystem,
        t0: f64,
        y0: &[f64],
        t_out: &[f64],
        stops: &[f64],
        observer: &mut dyn Observer,
    ) -> Result<Solution, Interrupted> {
        self.choose(system)
            .solve_dyn(system, t0, y0, t_out, stops, observer)
    }
}
