//! The system trait: the least surface an ODE must offer.

use faer::MatMut;

use crate::{BlockBanded, LinearSecondOrder};

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

    /// The system's mechanical (second-order) form `M(t, q) q'' = F(t, q, q')`, when it has
    /// one: its mass, damping and stiffness matrices for the iteration matrix of implicit
    /// methods for structural dynamics ([`crate::GeneralizedAlpha`] solves with the `n x n`
    /// matrix `M + c_C C + c_K K` instead of the `2n x 2n` `I - c J`). `None` (the default)
    /// for systems without one.
    fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> {
        None
    }

    /// Called by the stepping loop at the start of every integration segment (the start
    /// time and every stop time) with the state there, before the integrator (re)starts: a
    /// system with discrete updates (a sampled controller's zero-order hold) takes them here,
    /// at stop times it asked for. Between two such calls the right-hand side must be smooth.
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        let _ = (t, y);
    }

    /// The system's own next stop time strictly after `t` (forwards in time), when it has
    /// stop times (`None`, the default, when not): a sampled controller's next sample time,
    /// where its zero-order hold jumps. The stepping loop asks for it at the start of every
    /// integration segment and ends the segment there (as for a listed stop time, see
    /// [`crate::Integrator::solve_observed`]), so a system with a million samples never
    /// lists them: they are generated as the run goes.
    fn next_stop(&self, t: f64) -> Option<f64> {
        let _ = t;
        None
    }

    /// Called by the stepping loop after every accepted step with its end time and state,
    /// before the step's outputs and observers. What the right-hand side met in the trial
    /// evaluations of rejected attempts (a failure it recorded to explain the NaN it wrote)
    /// no longer matters once a step is accepted: a system that records such failures
    /// forgets them here, so that the failure it reports is one met after the last accepted
    /// step.
    fn step_accepted(&mut self, t: f64, y: &[f64]) {
        let _ = (t, y);
    }

    /// The system's terminal event function `g(t, y)`, when it has one (`None`, the
    /// default, when not): the integration ends where `g` is first reached, i.e. is no longer
    /// negative (`g >= 0` or NaN), such as a deflection passing its collapse limit.
    ///
    /// The stepping loop evaluates it on accepted states only: at the start, at the end of
    /// every accepted step and at every output time within it (by dense output), in time
    /// order. Where it is reached, the loop locates the first crossing after the last point
    /// where it was not by bisection on the dense output, to [`crate::EVENT_RESOLUTION`]
    /// times the step (or a few ulps of `t`), writes the outputs up to that time and ends with
    /// [`crate::Interruption::Event`] there; its last call is at that time, with the state
    /// it reports, so a system can record what it found there. Only the sign matters.
    /// Called once per step and output: it should cost less than a right-hand side.
    fn terminal_event(&mut self, t: f64, y: &[f64]) -> Option<f64> {
        let _ = (t, y);
        None
    }

    /// The magnitude of each state component that the relative tolerance is measured
    /// against at least, written into `scales` (`dim` entries, `0` for none); `false` (the
    /// default) when the system has none.
    ///
    /// A component's error weight is `atol + rtol |y_i|`: for a coordinate whose zero is
    /// only the origin of a frame (an absolute position or angle), that weight depends on
    /// where the origin is, and a component passing near zero asks for an accuracy that
    /// means nothing physically. A system with such coordinates gives their natural scale
    /// here (a length of the machine, one radian) and the integrators use
    /// `max(atol, rtol scale_i)` as the component's absolute tolerance
    /// ([`crate::Options::with_scales`]), so that the error test does not depend on the
    /// frame.
    fn tolerance_scales(&self, scales: &mut [f64]) -> bool {
        let _ = scales;
        false
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
    fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> {
        (**self).second_order_form()
    }
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        (**self).segment_start(t, y);
    }
    fn tolerance_scales(&self, scales: &mut [f64]) -> bool {
        (**self).tolerance_scales(scales)
    }
    fn step_accepted(&mut self, t: f64, y: &[f64]) {
        (**self).step_accepted(t, y);
    }
    fn next_stop(&self, t: f64) -> Option<f64> {
        (**self).next_stop(t)
    }
    fn terminal_event(&mut self, t: f64, y: &[f64]) -> Option<f64> {
        (**self).terminal_event(t, y)
    }
}

/// The mechanical form of an [`OdeSystem`] whose state is `y = (q, q')`: `n` coordinates
/// `q` and their rates `v = q'`,
///
/// ```text
/// q' = v,   M(t, q) v' = F(t, q, v)
/// ```
///
/// with `OdeSystem::rhs` returning `(v, M^-1 F)`. The form gives what an implicit method for
/// structural dynamics needs beyond the right-hand side: the mass matrix `M`, the tangent
/// stiffness `K ~ -dF/dq` and damping `C ~ -dF/dv`, from which
/// [`crate::GeneralizedAlpha`] builds its `n x n` iteration matrix `M + c_C C + c_K K`
/// (instead of the `2n x 2n` `I - c J` of the first-order form). `K` and `C` may be
/// approximations (Newton's iteration converges to the same solution, a poorer matrix only
/// costs iterations); `M` should be the mass the right-hand side divides by. Two optional
/// parts make the iterations cheaper: the matrices' sparsity ([`SecondOrderForm::structure`])
/// and the residual `M a - F` ([`SecondOrderForm::residual`]).
///
/// ```
/// use flexprr_integrators::{
///     BlockBanded, GeneralizedAlpha, Integrator, OdeSystem, Options, SecondOrderForm,
/// };
///
/// /// Two masses on springs, `m q1'' = -k (2 q1 - q2)`, `m q2'' = -k (2 q2 - q1)`.
/// struct Chain { m: f64, k: f64 }
/// impl OdeSystem for Chain {
///     fn dim(&self) -> usize { 4 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
///         dy[0] = y[2];
///         dy[1] = y[3];
///         dy[2] = -self.k * (2.0 * y[0] - y[1]) / self.m;
///         dy[3] = -self.k * (2.0 * y[1] - y[0]) / self.m;
///     }
///     fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> { Some(self) }
/// }
/// impl SecondOrderForm for Chain {
///     fn coordinates(&self) -> usize { 2 }
///     fn matrices(
///         &mut self, _t: f64, _y: &[f64],
///         mut m: faer::MatMut<'_, f64>, _c: faer::MatMut<'_, f64>, mut k: faer::MatMut<'_, f64>,
///     ) {
///         for i in 0..2 {
///             m[(i, i)] = self.m;
///             k[(i, i)] = 2.0 * self.k;
///         }
///         k[(0, 1)] = -self.k;
///         k[(1, 0)] = -self.k;
///     }
///     // Optional: the matrices are one tridiagonal block (a chain: banded LU, no border).
///     fn structure(&self) -> Option<BlockBanded> {
///         BlockBanded::new(2, vec![0..2], 1).ok()
///     }
///     // Optional: Newton's residual M a - F without dividing by M.
///     fn has_residual(&self) -> bool { true }
///     fn residual(&mut self, _t: f64, y: &[f64], acc: &[f64], r: &mut [f64]) {
///         r[0] = self.m * acc[0] + self.k * (2.0 * y[0] - y[1]);
///         r[1] = self.m * acc[1] + self.k * (2.0 * y[1] - y[0]);
///     }
/// }
///
/// // The in-phase mode q1 = q2 = cos(w t), w^2 = k / m = 25.
/// let mut chain = Chain { m: 2.0, k: 50.0 };
/// let opts = Options::default().rtol(1e-9).atol(1e-12);
/// let sol = GeneralizedAlpha::new(opts).solve(&mut chain, 0.0, &[1.0, 1.0, 0.0, 0.0], &[1.0]).unwrap();
/// assert!((sol.y(0)[0] - 5.0_f64.cos()).abs() < 1e-4);
/// ```
pub trait SecondOrderForm {
    /// Number of coordinates `n` (the state is `(q, v)`, `n` each).
    fn coordinates(&self) -> usize;

    /// Writes `M`, `C` and `K` at `(t, y)` (`n x n` each, both triangles, into zeroed
    /// storage). Called rarely (when the iteration matrix is renewed), so it may cost a
    /// few right-hand sides, but must not allocate.
    fn matrices(
        &mut self,
        t: f64,
        y: &[f64],
        mass: MatMut<'_, f64>,
        damping: MatMut<'_, f64>,
        stiffness: MatMut<'_, f64>,
    );

    /// The sparsity of `M`, `C` and `K`, when they have one: banded blocks of coordinates
    /// joined by a dense border ([`BlockBanded`]). [`crate::GeneralizedAlpha`] then factors
    /// its iteration matrix block by block (`O(n p^2)` instead of `n^3 / 3`) and multiplies
    /// by `M` in the structure; it refuses matrices with a non-zero entry outside it. Asked
    /// once, at the start of an integration. `None` (the default): dense matrices.
    fn structure(&self) -> Option<BlockBanded> {
        None
    }

    /// Whether [`SecondOrderForm::residual`] is provided (`false` by default).
    fn has_residual(&self) -> bool {
        false
    }

    /// Writes the residual of the equations of motion for the accelerations `acc`,
    /// `r = M(t, q) acc - F(t, q, v)` at `y = (q, v)`, into `residual` (`n` entries), with
    /// non-finite entries where the system cannot be evaluated (as [`OdeSystem::rhs`]).
    /// Implicit methods then iterate on `M a - F` without solving with `M` in every
    /// iteration. Only called when [`SecondOrderForm::has_residual`] is `true`; like the
    /// right-hand side it is called in every iteration and must not allocate. The default
    /// writes NaN.
    fn residual(&mut self, t: f64, y: &[f64], acc: &[f64], residual: &mut [f64]) {
        let _ = (t, y, acc);
        residual.fill(f64::NAN);
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
