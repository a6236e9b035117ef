//! The system trait: the least surface an ODE must offer.

use faer::MatMut;

use crate::LinearSecondOrder;

/// A first-order ODE system `y' = f(t, y)` of fixed dimension.
///
/// Only [`OdeSystem::dim`] and [`OdeSystem::rhs`] are required. The Jacobian defaults to
/// forward differences; systems that know it in closed form override
/// [`OdeSystem::jacobian`] and return `true` from [`OdeSystem::has_analytic_jacobian`].
///
/// ```
/// use faer::Mat;
/// use flexprr_integrators::OdeSystem;
///
/// /// Linear decay `y' = -k y` with its exact Jacobian `-k`.
/// struct Decay { k: f64 }
/// impl OdeSystem for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = -self.k * y[0]; }
///     fn jacobian(&mut self, _t: f64, _y: &[f64], mut jac: faer::MatMut<'_, f64>) {
///         jac[(0, 0)] = -self.k;
///     }
///     fn has_analytic_jacobian(&self) -> bool { true }
/// }
///
/// /// The same without a Jacobian: forward differences are provided.
/// struct Differenced { k: f64 }
/// impl OdeSystem for Differenced {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = -self.k * y[0]; }
/// }
///
/// let (mut exact, mut approx) = (Mat::<f64>::zeros(1, 1), Mat::<f64>::zeros(1, 1));
/// Decay { k: 3.0 }.jacobian(0.0, &[2.0], exact.as_mut());
/// let mut d = Differenced { k: 3.0 };
/// d.jacobian(0.0, &[2.0], approx.as_mut());
/// assert!((exact[(0, 0)] - approx[(0, 0)]).abs() < 1e-6);
/// assert_eq!((Decay { k: 3.0 }.jacobian_rhs_evaluations(), d.jacobian_rhs_evaluations()), (0, 2));
/// ```
pub trait OdeSystem {
    /// Number of state components.
    fn dim(&self) -> usize;

    /// Writes `f(t, y)` into `dy`. Called millions of times: must not allocate.
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]);

    /// Writes the Jacobian `df/dy` at `(t, y)` into `jac` (`dim x dim`).
    ///
    /// The provided version uses forward differences (allocating two work vectors; Jacobians
    /// are evaluated rarely) and costs `dim + 1` right-hand-side evaluations, which
    /// [`OdeSystem::jacobian_rhs_evaluations`] reports so integrators can count them.
    fn jacobian(&mut self, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
        let n = self.dim();
        let mut f0 = vec![0.0; n];
        self.rhs(t, y, &mut f0);
        let mut work = vec![0.0; 2 * n];
        finite_difference_jacobian(self, t, y, &f0, jac, &mut work);
    }

    /// Whether [`OdeSystem::jacobian`] is exact (overridden) rather than differenced.
    fn has_analytic_jacobian(&self) -> bool {
        false
    }

    /// Right-hand-side evaluations one call of [`OdeSystem::jacobian`] costs.
    fn jacobian_rhs_evaluations(&self) -> usize {
        if self.has_analytic_jacobian() {
            0
        } else {
            self.dim() + 1
        }
    }

    /// The system's linear time-varying second-order form, when it has one (exponential
    /// integrators need it; `None` for nonlinear systems).
    fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> {
        None
    }

    /// Called by the stepping loop at the start of every integration segment (the start
    /// time and every stop time) with the state there, before the integrator (re)starts: a
    /// system with discrete updates (a sampled controller's zero-order hold) takes them here,
    /// at stop times it asked for. Between two such calls the right-hand side must be smooth.
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        let _ = (t, y);
    }
}

impl<S: OdeSystem + ?Sized> OdeSystem for &mut S {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        (**self).rhs(t, y, dy);
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: MatMut<'_, f64>) {
        (**self).jacobian(t, y, jac);
    }
    fn has_analytic_jacobian(&self) -> bool {
        (**self).has_analytic_jacobian()
    }
    fn jacobian_rhs_evaluations(&self) -> usize {
        (**self).jacobian_rhs_evaluations()
    }
    fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> {
        (**self).linear_form()
    }
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        (**self).segment_start(t, y);
    }
}

/// Forward-difference Jacobian `J[:, j] = (f(y + d_j e_j) - f(y)) / d_j` with
/// `d_j = sqrt(eps) * max(|y_j|, 1)` (Dennis & Schnabel, *Numerical Methods for
/// Unconstrained Optimization*, 5.4).
///
/// `f0` is `f(t, y)`; `work` needs `2 * dim` entries.
pub fn finite_difference_jacobian<S: OdeSystem + ?Sized>(
    system: &mut S,
    t: f64,
    y: &[f64],
    f0: &[f64],
    mut jac: MatMut<'_, f64>,
    work: &mut [f64],
) {
    let n = y.len();
    let (yp, fp) = work.split_at_mut(n);
    yp.copy_from_slice(y);
    let sqrt_eps = f64::EPSILON.sqrt();
    for j in 0..n {
        let delta = sqrt_eps * y[j].abs().max(1.0);
        yp[j] = y[j] + delta;
        // Use the representable increment to cancel rounding in y + delta.
        let delta = yp[j] - y[j];
        system.rhs(t, yp, &mut fp[..n]);
        for i in 0..n {
            jac[(i, j)] = (fp[i] - f0[i]) / delta;
        }
        yp[j] = y[j];
    }
}
