//! The generalized-alpha method for structural dynamics, with Newton iterations on the
//! mechanical form, local error control and dense output.
//!
//! # Method
//!
//! For `M(t, q) q'' = F(t, q, q')` ([`SecondOrderForm`](crate::SecondOrderForm)) the method of Chung & Hulbert
//! ("A time integration algorithm for structural dynamics with improved numerical
//! dissipation: the generalized-alpha method", *J. Appl. Mech.* 60, 1993) in the form of
//! Arnold & Brüls ("Convergence of the generalized-alpha scheme for constrained mechanical
//! systems", *Multibody Syst. Dyn.* 18, 2007, eqs. 8-9) advances the positions `q`, the
//! velocities `v`, the accelerations `a_dd = q''` that satisfy the equations of motion at
//! `t_{n+1}`, and an auxiliary acceleration `a`:
//!
//! ```text
//! q_{n+1} = q_n + h v_n + h^2 (1/2 - beta) a_n + h^2 beta a_{n+1}
//! v_{n+1} = v_n + h (1 - gamma) a_n + h gamma a_{n+1}
//! (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) a_dd_{n+1} + alpha_f a_dd_n
//! M(q_{n+1}) a_dd_{n+1} = F(t_{n+1}, q_{n+1}, v_{n+1}),     a_0 = a_dd_0
//! ```
//!
//! with the parameters of the user's spectral radius at infinite frequency `rho_inf`
//! (Chung & Hulbert 1993, eqs. 25, 17, 20):
//! `alpha_m = (2 rho - 1)/(rho + 1)`, `alpha_f = rho/(rho + 1)`,
//! `gamma = 1/2 - alpha_m + alpha_f`, `beta = (1 - alpha_m + alpha_f)^2 / 4`. The method is
//! second-order accurate and unconditionally stable for linear problems; `rho_inf = 1` is the
//! trapezoidal rule (no dissipation), `rho_inf = 0` annihilates the highest frequencies in one
//! step. The default [`DEFAULT_SPECTRAL_RADIUS`] = 0.7 (Exudyn's default is 0.9; HHT with
//! `alpha = -0.2`, a common choice, corresponds to 0.67): the stiff axial modes of beam
//! elements, which the steps need not resolve, are damped by 0.7 per step while the
//! resolved bending modes keep their energy to second order.
//!
//! # Newton iterations
//!
//! The unknown of a step is `x = a_dd_{n+1}`, started from the accelerations of the last two
//! accepted points extrapolated to `t_{n+1}`; `q_{n+1} = q* + beta' h^2 x`,
//! `v_{n+1} = v* + gamma' h x` with `beta' = beta (1 - alpha_f)/(1 - alpha_m)`,
//! `gamma' = gamma (1 - alpha_f)/(1 - alpha_m)`. The residual is the form's
//! `r(x) = M(q) x - F` ([`SecondOrderForm::residual`](crate::SecondOrderForm::residual)) when
//! it offers one, with the corrections `(M + gamma' h C + beta' h^2 K) dx = -r`; otherwise
//! `r(x) = x - M^-1 F` from [`OdeSystem::rhs`], whose Newton matrix
//! `M^-1 (M + gamma' h C + beta' h^2 K)` gives `(M + gamma' h C + beta' h^2 K) dx = -M r`;
//! `M`, `C` and `K` are those of [`SecondOrderForm::matrices`](crate::SecondOrderForm::matrices).
//! Both have the same solution; the first needs no solve with `M` per iteration. The
//! iteration is modified Newton after CVODE (Hindmarsh et al., ACM TOMS 31, 2005): the
//! matrices are kept for [`MATRIX_MAX_AGE`] accepted steps, renewed when an iteration
//! converges slowly or fails, and the factorisation is kept while the step size stays within
//! a factor [`REFACTOR_RATIO`] of the one it was made for. The factorisation is the
//! banded-bordered LU of [`crate::structured`] (a banded LU with partial pivoting per block, the Schur
//! complement of the border) when the form declares a
//! [`BlockBanded`](crate::BlockBanded) structure
//! ([`SecondOrderForm::structure`](crate::SecondOrderForm::structure)), and the products with
//! `M` use the same storage; otherwise dense LU with partial pivoting (faer's `lu_in_place`
//! into preallocated storage) and dense products. A form whose matrices have a non-zero
//! entry outside the structure it declared at the first evaluation is refused; later
//! evaluations zero, check and read only the entries inside the structure. The convergence test is CVODE's: the
//! rate `R` from successive corrections and `min(1, R) |dx|_w <= 0.002`, where `|.|_w` is
//! the weighted RMS norm of the position corrections `beta' h^2 dx` with the error test's
//! weights (velocities are not tested: an unresolved mode's velocity is `omega` times its
//! position), at most [`NEWTON_MAX_ITERATIONS`] iterations.
//!
//! # Error control and dense output
//!
//! The local error is estimated as in Zienkiewicz & Xie ("A simple error estimator and
//! adaptive time stepping procedure for dynamic analysis", *Earthquake Eng. Struct. Dyn.*
//! 20, 1991; for the generalized-alpha method Géradin & Cardona, *Flexible Multibody
//! Dynamics*, 2001, ch. 14): the Taylor term the scheme misses in the positions. With the
//! auxiliary acceleration lagging the true one by `delta h`, `a_n = q''(t_n + delta h) +
//! O(h^2)`, `delta = alpha_m - alpha_f` (Arnold & Brüls 2007, section 3), the positions'
//! local error is `(beta + delta / 2 - 1/6) h^3 q'''`, estimated as
//! `e_q = (beta + delta / 2 - 1/6) h^2 (a_dd_{n+1} - a_dd_n)`. (Newmark's constant
//! `beta - 1/6`, exact for `alpha_m = alpha_f`, overestimates it twice at `rho_inf = 0.7`:
//! `tests/genalpha.rs` compares both with the error of one step of the oscillator.) The
//! auxiliary acceleration's lag is tied to the step size: when a step of size `h` follows
//! one of size `h_old`, `a_n` is first moved by `delta (h - h_old) q'''` (with `q'''` from the
//! last two accelerations), which keeps the velocities second-order accurate under
//! variable steps (without it a change of step makes an `O(h^2)` error in `v`, and a
//! sequence of changes costs an order). The estimate is filtered through the iteration
//! matrix, `e <- (M + gamma' h C + beta' h^2 K)^-1 M e`, as stiff solvers filter
//! theirs (Shampine 1980; Hairer & Wanner II, IV.8, eq. 8.20 for Radau5): a mode of
//! frequency `omega` keeps its estimate when `omega h << 1` and loses it by
//! `1 / (1 + beta' (omega h)^2)` beyond, so the axial modes of the links, which the method
//! damps rather than resolves, do not dictate the step. A step is accepted when the
//! weighted RMS norm of `e_q` is at most 1 (positions only, as Zienkiewicz & Xie: the
//! velocities of modes near `omega h ~ 1` would set the step otherwise), with the weights of
//! [`crate::Options::for_system`] (a system's tolerance scales bound them below, so that an
//! absolute coordinate passing zero does not set the step). The next step comes from the
//! PI controller of Gustafsson (1991; Hairer & Wanner II, IV.2, eq. 2.43a):
//! `h 0.9 err_n^(-0.7/3) err_{n-1}^(0.4/3)` (`err_{n-1}` of the last accepted step, at least
//! 1e-4), bounded to `[0.2, 5] h`, and not increased below [`MIN_INCREASE`] (each change of
//! step may cost a factorisation); after a rejection, `h 0.9 err^(-1/3)`. Its smoother step
//! sequence, with the two corrections above, makes the global error fall steadily with the
//! tolerance (docs/performance.md, "A tolerance that orders the error"). Dense output is cubic Hermite
//! interpolation of `q` from `(q, v)` and of `v` from `(v, a_dd)` at both ends of the step.
//!
//! Nothing is allocated after [`crate::Integrator::start`].

use faer::Mat;

use crate::common::{DenseLu, Span};
use crate::structured::BandedBordered;
use crate::{IntegratorError, OdeSystem, Options, Stats, Stepper, error_norm, initial_step};

/// The spectral radius at infinite frequency used by [`GeneralizedAlpha::new`].
///
/// Measured on the nonlinear 3-PRR (8 elements per link, docs/performance.md, "Implicit
/// integration"): against 0.9, the links' axial vibration, which the undamped model keeps
/// from its start, is damped enough that it stops setting the steps and the error
/// estimate stops jumping from step to step: a 0.5 s run at 24.8 Hz takes 43 000 steps
/// (393 rejected) instead of 57 000 (10 600 rejected), and the 30 Hz collapse stays within
/// 0.27 % of the converged external model at rtol 1e-5 (0.31 % at 0.9). 0.5 and 0.6 cost
/// the same and are further off (0.64 %, 0.44 %).
pub const DEFAULT_SPECTRAL_RADIUS: f64 = 0.7;

/// Accepted steps after which the matrices `M`, `C`, `K` are re-evaluated.
pub const MATRIX_MAX_AGE: usize = 50;

/// The factorisation is kept while `h / h_factor` stays within `[1 / REFACTOR_RATIO,
/// REFACTOR_RATIO]`: in a stiff mode (`beta' h^2 K >> M`) a matrix made for another step
/// converges at the rate `|h^2 / h_factor^2 - 1|`, at most 0.21 here, and an iteration more
/// costs less than a factorisation. On the 30 Hz collapse (8 elements, rtol 1e-5) 1.1
/// halves the factorisations (505 against 892 for any change) for 2 % fewer residuals;
/// 1.25 saves another quarter of them but costs 7 % more residuals and rejected steps.
pub const REFACTOR_RATIO: f64 = 1.1;

/// A proposed step increase below this ratio is not taken.
pub const MIN_INCREASE: f64 = 1.25;

/// Newton iterations allowed per attempt.
pub const NEWTON_MAX_ITERATIONS: usize = 8;

/// A convergence rate above this renews the matrices at the next step.
const SLOW_RATE: f64 = 0.3;

/// Weight of the Newton convergence test relative to the error test (CVODE's `nlscoef` is 0.1).
/// The 30 Hz collapse at rtol 1e-5 (8 elements): 0.01 halved the error of 0.1 for fewer steps;
/// with the residual form `M a - F`, 0.002 against 0.01 takes 12 % fewer steps (2 920 against
/// 3 304) and 0.210 % against 0.246 % from the external model, and keeps the undamped energy
/// balance at rtol 1e-7 at 1.5e-4 of the energy change instead of 2.4e-4.
const NEWTON_COEFFICIENT: f64 = 0.002;

/// Consecutive failed attempts before giving up.
const MAX_CONSECUTIVE_FAILURES: usize = 10;

/// Step reduction after a Newton failure with fresh matrices.
const NEWTON_FAILURE_FACTOR: f64 = 0.25;

const SAFETY: f64 = 0.9;
/// The PI controller's exponents (Gustafsson 1991, with `k = 3` for a local error of third
/// order): `err_n^(-0.7/k) err_{n-1}^(0.4/k)`.
const PI_INTEGRAL: f64 = 0.7 / 3.0;
const PI_PROPORTIONAL: f64 = 0.4 / 3.0;
/// The smallest previous error the PI controller uses (Hairer & Wanner's 1e-4).
const MIN_OLD_ERROR: f64 = 1e-4;
const MIN_FACTOR: f64 = 0.2;
const MAX_FACTOR: f64 = 5.0;

/// The generalized-alpha method (see the module documentation).
///
/// Needs a system with a [`SecondOrderForm`](crate::SecondOrderForm) (state `(q, q')`); others are refused at
/// [`crate::Integrator::start`] with a message saying so.
#[derive(Debug, Clone)]
pub struct GeneralizedAlpha {
    /// Shared options.
    pub options: Options,
    /// Spectral radius at infinite frequency, `0 <= rho_inf <= 1`.
    pub spectral_radius: f64,
}

impl GeneralizedAlpha {
    /// The method with the options' spectral radius ([`Options::spectral_radius`]), or
    /// [`DEFAULT_SPECTRAL_RADIUS`] when they give none.
    pub fn new(options: Options) -> Self {
        Self {
            spectral_radius: options.spectral_radius.unwrap_or(DEFAULT_SPECTRAL_RADIUS),
            options,
        }
    }

    /// Sets the spectral radius at infinite frequency (`0` to `1`), in the options too, so
    /// that [`crate::Integrator::options`] reports the value the method uses.
    #[must_use]
    pub fn spectral_radius(mut self, rho_inf: f64) -> Self {
        self.spectral_radius = rho_inf;
        self.options.spectral_radius = Some(rho_inf);
        self
    }
}

/// The parameters of one `rho_inf` (Chung & Hulbert 1993, eqs. 25, 17, 20).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameters {
    /// `alpha_m = (2 rho - 1) / (rho + 1)`.
    pub alpha_m: f64,
    /// `alpha_f = rho / (rho + 1)`.
    pub alpha_f: f64,
    /// `gamma = 1/2 - alpha_m + alpha_f`.
    pub gamma: f64,
    /// `beta = (1 - alpha_m + alpha_f)^2 / 4`.
    pub beta: f64,
}

impl Parameters {
    /// The parameters for `rho_inf` in `[0, 1]`.
    pub fn new(rho_inf: f64) -> Self {
        let alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let alpha_f = rho_inf / (rho_inf + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        let beta = 0.25 * (1.0 - alpha_m + alpha_f).powi(2);
        Self {
            alpha_m,
            alpha_f,
            gamma,
            beta,
        }
    }

    /// `beta' = beta (1 - alpha_f) / (1 - alpha_m)`: `dq_{n+1} / d a_dd_{n+1}` over `h^2`.
    fn beta_prime(&self) -> f64 {
        self.beta * (1.0 - self.alpha_f) / (1.0 - self.alpha_m)
    }

    /// `gamma' = gamma (1 - alpha_f) / (1 - alpha_m)`: `dv_{n+1} / d a_dd_{n+1}` over `h`.
    fn gamma_prime(&self) -> f64 {
        self.gamma * (1.0 - self.alpha_f) / (1.0 - self.alpha_m)
    }

    /// `delta = alpha_m - alpha_f`: the auxiliary acceleration lags the true one by
    /// `delta h` (`a_n = q''(t_n + delta h) + O(h^2)`, Arnold & Brüls 2007).
    pub fn lag(&self) -> f64 {
        self.alpha_m - self.alpha_f
    }

    /// The positions' local error constant `C`: one step from exact values misses
    /// `C h^3 q'''`, `C = beta + delta / 2 - 1/6` (module documentation).
    pub fn error_constant(&self) -> f64 {
        self.beta + 0.5 * self.lag() - 1.0 / 6.0
    }
}

/// Why one attempt at a step failed.
#[derive(Debug)]
enum AttemptFailure {
    /// Newton did not converge; `non_finite` names a component if the rhs was NaN/inf.
    Newton { non_finite: Option<usize> },
    /// The iteration matrix had a zero (or non-finite) pivot.
    Singular,
    /// A matrix of the form has a non-finite entry in this row.
    NonFiniteMatrix { row: usize },
    /// A matrix of the form has a non-zero entry outside the structure it declared.
    OutsideStructure { row: usize, column: usize },
}

/// How the iteration matrix is stored, factored and multiplied.
enum Algebra {
    /// Dense LU (faer); products with the dense `M`.
    Dense(DenseLu),
    /// The form's [`crate::BlockBanded`] structure: the iteration matrix's banded-bordered LU
    /// and `M` in the same compact storage.
    Structured {
        lu: Box<BandedBordered>,
        mass: Box<BandedBordered>,
    },
}

/// The state of one generalized-alpha integration.
pub struct GeneralizedAlphaStepper {
    options: Options,
    parameters: Parameters,
    /// Coordinates `n` (the state has `2 n` components).
    n: usize,
    span: Span,
    direction: f64,
    /// Step size magnitude wanted for the next step.
    h_next: f64,
    /// `(q, v)`, `a_dd` and `a` at the current point.
    y: Vec<f64>,
    acc: Vec<f64>,
    aux: Vec<f64>,
    /// The auxiliary acceleration of the current attempt: `aux` moved to its step size.
    aux_step: Vec<f64>,
    /// The same at the start of the last accepted step (dense output).
    y_old: Vec<f64>,
    acc_old: Vec<f64>,
    /// The attempt's state, unknown `x = a_dd_{n+1}` and fixed parts `(q*, v*)`.
    y_new: Vec<f64>,
    x: Vec<f64>,
    fixed: Vec<f64>,
    f: Vec<f64>,
    delta: Vec<f64>,
    error: Vec<f64>,
    mass: Mat<f64>,
    damping: Mat<f64>,
    stiffness: Mat<f64>,
    algebra: Algebra,
    /// The form's residual `M a - F` is used in the Newton iterations (instead of
    /// `a - M^-1 F` from the right-hand side).
    residual_form: bool,
    /// Signed step the factorisation was made for, if any.
    lu_h: Option<f64>,
    /// The matrices were evaluated at the current accepted point.
    matrices_current: bool,
    /// Whether the matrices were ever evaluated.
    matrices_valid: bool,
    steps_since_matrices: usize,
    /// Newton rate estimate carried between steps while the factorisation is unchanged.
    newton_rate: f64,
    /// Error norm of the last accepted step (PI control), 0 before the first.
    error_old: f64,
}

impl std::fmt::Debug for GeneralizedAlphaStepper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GeneralizedAlphaStepper")
            .field("t", &self.span.t)
            .field("h_next", &self.h_next)
            .field("parameters", &self.parameters)
            .field("stats", &self.span.stats)
            .finish_non_exhaustive()
    }
}

/// First non-finite entry of `v`.
fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}

/// `out = sign * mass x` column by column (contiguous, vectorizable).
#[inline]
fn multiply_dense(mass: &Mat<f64>, x: &[f64], sign: f64, out: &mut [f64]) {
    out.fill(0.0);
    for (j, xj) in x.iter().enumerate() {
        let w = sign * xj;
        if w != 0.0 {
            for (o, m) in out.iter_mut().zip(mass.col_as_slice(j)) {
                *o += w * m;
            }
        }
    }
}

/// Cubic Hermite interpolation at `theta` in `[0, 1]` of a step of length `h` from values
/// `p0, p1` and derivatives `d0, d1`.
#[inline]
fn hermite(theta: f64, h: f64, p0: f64, d0: f64, p1: f64, d1: f64) -> f64 {
    let t2 = theta * theta;
    let t3 = t2 * theta;
    (2.0 * t3 - 3.0 * t2 + 1.0) * p0
        + (t3 - 2.0 * t2 + theta) * h * d0
        + (-2.0 * t3 + 3.0 * t2) * p1
        + (t3 - t2) * h * d1
}

impl GeneralizedAlphaStepper {
    /// Evaluates `M`, `C`, `K` at the current accepted point.
    fn evaluate_matrices<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
    ) -> Result<(), AttemptFailure> {
        // With a structure, after the first evaluation has shown that the form writes inside
        // it, only the entries inside are zeroed, checked and read (the dense storage of
        // the form's interface is n^2 per matrix; its structured part O(n p)).
        let first = !self.matrices_valid;
        match &self.algebra {
            Algebra::Structured { mass, .. } if !first => {
                mass.zero_within(&mut self.mass);
                mass.zero_within(&mut self.damping);
                mass.zero_within(&mut self.stiffness);
            }
            _ => {
                self.mass.fill(0.0);
                self.damping.fill(0.0);
                self.stiffness.fill(0.0);
            }
        }
        if let Some(form) = system.second_order_form() {
            form.matrices(
                self.span.t,
                &self.y,
                self.mass.as_mut(),
                self.damping.as_mut(),
                self.stiffness.as_mut(),
            );
        }
        self.span.stats.jacobian_evaluations += 1;
        self.matrices_current = true;
        self.matrices_valid = true;
        self.steps_since_matrices = 0;
        self.lu_h = None;
        for j in 0..self.n {
            let columns = [
                self.mass.col_as_slice(j),
                self.damping.col_as_slice(j),
                self.stiffness.col_as_slice(j),
            ];
            for column in columns {
                match &self.algebra {
                    Algebra::Structured { mass, .. } if !first => {
                        if let Some(row) = mass.first_non_finite_within(j, column) {
                            return Err(AttemptFailure::NonFiniteMatrix { row });
                        }
                    }
                    algebra => {
                        // `v * 0` is NaN exactly for a non-finite `v`: one vectorized sum,
                        // and the position only when there is one.
                        if column.iter().map(|v| v * 0.0).sum::<f64>().is_nan() {
                            let row = column.iter().position(|v| !v.is_finite()).unwrap_or(0);
                            return Err(AttemptFailure::NonFiniteMatrix { row });
                        }
                        if let Algebra::Structured { mass, .. } = algebra {
                            if let Some(row) = mass.first_outside(j, column) {
                                return Err(AttemptFailure::OutsideStructure { row, column: j });
                            }
                        }
                    }
                }
            }
        }
        if let Algebra::Structured { mass, .. } = &mut self.algebra {
            mass.load(&[(1.0, &self.mass)]);
        }
        Ok(())
    }

    /// `out = sign M x` with the matrices' `M` (dense or in the structure).
    fn multiply_mass(&self, x: &[f64], sign: f64, out: &mut [f64]) {
        match &self.algebra {
            Algebra::Dense(_) => multiply_dense(&self.mass, x, sign, out),
            Algebra::Structured { mass, .. } => mass.multiply(x, sign, out),
        }
    }

    /// Forms and factors `M + gamma' h C + beta' h^2 K` for the signed step `h`.
    fn factor(&mut self, h: f64) -> Result<(), AttemptFailure> {
        let n = self.n;
        let cc = self.parameters.gamma_prime() * h;
        let ck = self.parameters.beta_prime() * h * h;
        self.span.stats.lu_decompositions += 1;
        self.newton_rate = 1.0;
        let regular = match &mut self.algebra {
            Algebra::Dense(lu) => {
                for j in 0..n {
                    let (m, c, k) = (
                        self.mass.col_as_slice(j),
                        self.damping.col_as_slice(j),
                        self.stiffness.col_as_slice(j),
                    );
                    for (i, a) in lu.matrix.col_as_slice_mut(j).iter_mut().enumerate() {
                        *a = m[i] + cc * c[i] + ck * k[i];
                    }
                }
                lu.factor()
            }
            Algebra::Structured { lu, .. } => {
                lu.load(&[
                    (1.0, &self.mass),
                    (cc, &self.damping),
                    (ck, &self.stiffness),
                ]);
                lu.factor()
            }
        };
        if !regular {
            self.lu_h = None;
            return Err(AttemptFailure::Singular);
        }
        self.lu_h = Some(h);
        Ok(())
    }

    /// Solves with the current factorisation in place in `self.delta`.
    fn solve_in_place(&mut self) {
        match &mut self.algebra {
            Algebra::Dense(lu) => lu.solve_in_place(&mut self.delta),
            Algebra::Structured { lu, .. } => lu.solve_in_place(&mut self.delta),
        }
    }

    /// The Newton residual at the attempt's state `y_new` and unknown `x`, times `-1`, into
    /// `delta`: `-(M x - F)` from the form's residual, or `-M (x - M^-1 F)` with the
    /// matrices' `M` from the right-hand side. `Err` with the first non-finite component.
    fn negative_residual<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t_new: f64,
    ) -> Result<(), usize> {
        let n = self.n;
        self.span.stats.rhs_evaluations += 1;
        self.span.stats.newton_iterations += 1;
        if self.residual_form {
            if let Some(form) = system.second_order_form() {
                form.residual(t_new, &self.y_new, &self.x, &mut self.delta);
            }
            for d in &mut self.delta {
                *d = -*d;
            }
            return first_non_finite(&self.delta).map_or(Ok(()), |i| Err(n + i));
        }
        system.rhs(t_new, &self.y_new, &mut self.f);
        if let Some(component) = first_non_finite(&self.f) {
            return Err(component);
        }
        for i in 0..n {
            self.error[i] = self.x[i] - self.f[n + i];
        }
        let mut delta = std::mem::take(&mut self.delta);
        self.multiply_mass(&self.error[..n], -1.0, &mut delta);
        self.delta = delta;
        Ok(())
    }

    /// Writes `(q, v)` of the attempt from the unknown `x` into `y_new`.
    fn positions_from_unknown(&mut self, h: f64) {
        let n = self.n;
        let cq = self.parameters.beta_prime() * h * h;
        let cv = self.parameters.gamma_prime() * h;
        for i in 0..n {
            self.y_new[i] = self.fixed[i] + cq * self.x[i];
            self.y_new[n + i] = self.fixed[n + i] + cv * self.x[i];
        }
    }

    /// Weighted RMS norm of the position corrections `beta' h^2 dx` of `dx = self.delta`.
    fn correction_norm(&self, h: f64) -> f64 {
        let n = self.n;
        let cq = self.parameters.beta_prime() * h * h;
        let mut sum = 0.0;
        for i in 0..n {
            let scale = self.options.atol.get(i) + self.options.rtol * self.y[i].abs();
            let r = cq * self.delta[i] / scale;
            sum += r * r;
        }
        (sum / n as f64).sqrt()
    }

    /// Newton's starting guess for `a_dd_{n+1}` in `x`: the accelerations of the last two
    /// accepted points extrapolated linearly to the end of the step (the last accepted
    /// accelerations when there is no previous step). Only the iterations' start changes;
    /// on the 30 Hz collapse it saves 17 % of the residuals against starting from `a_dd_n`.
    fn predict(&mut self, h: f64) {
        self.x.copy_from_slice(&self.acc);
        let h_old = self.span.t - self.span.t_previous;
        if h_old != 0.0 {
            let r = h / h_old;
            for ((x, a), a_old) in self.x.iter_mut().zip(&self.acc).zip(&self.acc_old) {
                *x += r * (a - a_old);
            }
        }
    }

    /// One attempt at a step of signed size `h` to `t_new`: predicts, then iterates Newton
    /// until the correction is small. On success `x` holds `a_dd_{n+1}` and `y_new` the
    /// state.
    fn attempt<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t_new: f64,
        h: f64,
    ) -> Result<(), AttemptFailure> {
        let n = self.n;
        let p = self.parameters;
        if !self.matrices_valid
            || (self.steps_since_matrices >= MATRIX_MAX_AGE && !self.matrices_current)
        {
            self.evaluate_matrices(system)?;
        }
        let reuse = self
            .lu_h
            .is_some_and(|hf| (h / hf) <= REFACTOR_RATIO && (hf / h) <= REFACTOR_RATIO);
        if !reuse {
            self.factor(h)?;
        }
        // The auxiliary acceleration for this step size: its lag `delta h_old` moved to
        // `delta h`, with `q'''` from the last two accelerations (none at the first step).
        let h_old = self.span.t - self.span.t_previous;
        let shift = if h_old == 0.0 {
            0.0
        } else {
            p.lag() * (h - h_old) / h_old
        };
        for i in 0..n {
            self.aux_step[i] = self.aux[i] + shift * (self.acc[i] - self.acc_old[i]);
        }
        // Fixed parts: everything of q_{n+1}, v_{n+1} but the terms in x.
        let scale = 1.0 / (1.0 - p.alpha_m);
        for i in 0..n {
            let a = self.aux_step[i];
            let known = scale * (p.alpha_f * self.acc[i] - p.alpha_m * a);
            self.fixed[i] =
                self.y[i] + h * self.y[n + i] + h * h * ((0.5 - p.beta) * a + p.beta * known);
            self.fixed[n + i] = self.y[n + i] + h * ((1.0 - p.gamma) * a + p.gamma * known);
        }
        self.predict(h);
        let mut previous = 0.0;
        for m in 0..NEWTON_MAX_ITERATIONS {
            self.positions_from_unknown(h);
            if let Err(component) = self.negative_residual(system, t_new) {
                return Err(AttemptFailure::Newton {
                    non_finite: Some(component),
                });
            }
            self.solve_in_place();
            for i in 0..n {
                self.x[i] += self.delta[i];
            }
            let norm = self.correction_norm(h);
            if !norm.is_finite() {
                return Err(AttemptFailure::Newton { non_finite: None });
            }
            if m > 0 {
                self.newton_rate = (0.3 * self.newton_rate).max(norm / previous);
                if norm > 2.0 * previous {
                    return Err(AttemptFailure::Newton { non_finite: None });
                }
            }
            if norm * self.newton_rate.min(1.0) <= NEWTON_COEFFICIENT || norm == 0.0 {
                self.positions_from_unknown(h);
                return Ok(());
            }
            previous = norm;
        }
        Err(AttemptFailure::Newton { non_finite: None })
    }

    /// The weighted norm of the local error estimate of the attempt (module documentation),
    /// filtered through the iteration matrix.
    fn local_error(&mut self, h: f64) -> f64 {
        let n = self.n;
        let c = self.parameters.error_constant() * h * h;
        for i in 0..n {
            self.error[i] = c * (self.x[i] - self.acc[i]);
        }
        let mut delta = std::mem::take(&mut self.delta);
        self.multiply_mass(&self.error[..n], 1.0, &mut delta);
        self.delta = delta;
        self.solve_in_place();
        for i in 0..n {
            self.error[i] = self.delta[i];
            self.error[n + i] = 0.0;
        }
        error_norm(
            &self.error[..n],
            &self.y[..n],
            &self.y_new[..n],
            &self.options,
        )
    }

    /// Accepts the attempt: the new point becomes the current one.
    fn accept(&mut self) {
        let p = self.parameters;
        let scale = 1.0 / (1.0 - p.alpha_m);
        for i in 0..self.n {
            self.aux[i] = scale
                * ((1.0 - p.alpha_f) * self.x[i] + p.alpha_f * self.acc[i]
                    - p.alpha_m * self.aux_step[i]);
        }
        self.y_old.copy_from_slice(&self.y);
        self.acc_old.copy_from_slice(&self.acc);
        self.y.copy_from_slice(&self.y_new);
        self.acc.copy_from_slice(&self.x);
    }

    /// The error for a failure of the form's matrices (`None` for other failures).
    fn matrix_error(&self, failure: &AttemptFailure) -> Option<IntegratorError> {
        match *failure {
            AttemptFailure::NonFiniteMatrix { row } => Some(IntegratorError::NonFinite {
                t: self.span.t,
                component: row,
            }),
            AttemptFailure::OutsideStructure { row, column } => {
                Some(IntegratorError::InvalidInput(format!(
                    "at t = {} s the mechanical form's matrices have a non-zero entry at \
                     ({row}, {column}), outside the sparsity structure the form declares",
                    self.span.t
                )))
            }
            _ => None,
        }
    }

    /// Turns a failed attempt into the reaction: `Ok(true)` to retry the same step with
    /// renewed matrices, `Ok(false)` to retry with a smaller step, `Err` to give up.
    fn recover<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        failure: AttemptFailure,
        failures: usize,
        t_new: f64,
        last_non_finite: &mut Option<usize>,
    ) -> Result<bool, IntegratorError> {
        if let Some(error) = self.matrix_error(&failure) {
            return Err(error);
        }
        let singular = matches!(failure, AttemptFailure::Singular);
        if let AttemptFailure::Newton { non_finite } = failure {
            *last_non_finite = non_finite;
        }
        if failures >= MAX_CONSECUTIVE_FAILURES {
            return Err(if singular {
                IntegratorError::SingularMatrix { t: self.span.t }
            } else if let Some(component) = *last_non_finite {
                IntegratorError::NonFinite {
                    t: t_new,
                    component,
                }
            } else {
                IntegratorError::NewtonFailure {
                    t: self.span.t,
                    h: self.h_next,
                }
            });
        }
        if !singular && !self.matrices_current && last_non_finite.is_none() {
            if let Err(failure) = self.evaluate_matrices(system) {
                if let Some(error) = self.matrix_error(&failure) {
                    return Err(error);
                }
            }
            return Ok(true);
        }
        Ok(false)
    }
}

impl GeneralizedAlphaStepper {
    /// Sets the size (magnitude) of the next step attempt, in place of the controller's
    /// proposal: for callers that drive a step sequence of their own (with error control
    /// off, `rtol` and `atol` so large that every step passes). `max_step` and the landing on
    /// `t_end` still apply.
    pub fn set_step(&mut self, h: f64) {
        if h.is_finite() && h > 0.0 {
            self.h_next = h;
        }
    }

    /// The method's parameters.
    pub fn parameters(&self) -> Parameters {
        self.parameters
    }
}

impl Stepper for GeneralizedAlphaStepper {
    fn t(&self) -> f64 {
        self.span.t
    }

    fn y(&self) -> &[f64] {
        &self.y
    }

    fn t_previous(&self) -> f64 {
        self.span.t_previous
    }

    fn step<S: OdeSystem + ?Sized>(&mut self, system: &mut S) -> Result<(), IntegratorError> {
        self.span.check_open()?;
        let mut h_abs = self.h_next.min(self.options.max_step);
        let mut failures = 0usize;
        let mut rejected = false;
        let mut last_non_finite: Option<usize> = None;
        loop {
            self.span.check_budget(self.options.max_steps)?;
            self.span
                .check_step_size(h_abs * self.direction, last_non_finite)?;
            let (h, last) = self
                .span
                .land(self.direction * h_abs, self.options.max_step);
            let t_new = if last {
                self.span.t_end
            } else {
                self.span.t + h
            };
            if let Err(failure) = self.attempt(system, t_new, h) {
                self.span.stats.rejected_steps += 1;
                failures += 1;
                rejected = true;
                let renewed =
                    self.recover(system, failure, failures, t_new, &mut last_non_finite)?;
                if !renewed {
                    h_abs = h.abs() * NEWTON_FAILURE_FACTOR;
                }
                continue;
            }
            let error = self.local_error(h);
            if error.is_nan() || error > 1.0 {
                self.span.stats.rejected_steps += 1;
                rejected = true;
                let factor = if error.is_finite() {
                    (SAFETY * error.powf(-1.0 / 3.0)).max(MIN_FACTOR)
                } else {
                    MIN_FACTOR
                };
                h_abs = h.abs() * factor;
                continue;
            }
            if let Some(component) = first_non_finite(&self.y_new) {
                return Err(IntegratorError::NonFinite {
                    t: t_new,
                    component,
                });
            }
            self.accept();
            self.span.advance(t_new, last);
            self.span.stats.accepted_steps += 1;
            self.span.stats.record_order(2);
            self.steps_since_matrices += 1;
            self.matrices_current = false;
            if self.newton_rate > SLOW_RATE {
                // Renew the matrices before the next step rather than after its failure.
                self.steps_since_matrices = MATRIX_MAX_AGE;
            }
            if last {
                self.span.finished = true;
                return Ok(());
            }
            let factor = if error > 0.0 {
                let integral = SAFETY * error.powf(-PI_INTEGRAL);
                let proportional = if self.error_old > 0.0 {
                    self.error_old.powf(PI_PROPORTIONAL)
                } else {
                    1.0
                };
                (integral * proportional).clamp(MIN_FACTOR, MAX_FACTOR)
            } else {
                MAX_FACTOR
            };
            self.error_old = error.max(MIN_OLD_ERROR);
            self.h_next = if rejected || (1.0..MIN_INCREASE).contains(&factor) {
                h.abs().min(h.abs() * factor)
            } else {
                h.abs() * factor
            };
            return Ok(());
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let n = self.n;
        let h = self.span.t - self.span.t_previous;
        if h == 0.0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let theta = (t - self.span.t_previous) / h;
        let (y0, y1) = (&self.y_old, &self.y);
        for i in 0..n {
            out[i] = hermite(theta, h, y0[i], y0[n + i], y1[i], y1[n + i]);
            out[n + i] = hermite(theta, h, y0[n + i], self.acc_old[i], y1[n + i], self.acc[i]);
        }
    }

    fn stats(&self) -> &Stats {
        &self.span.stats
    }
}

impl crate::Integrator for GeneralizedAlpha {
    type Stepper = GeneralizedAlphaStepper;

    fn name(&self) -> &'static str {
        "generalized_alpha"
    }

    fn options(&self) -> &Options {
        &self.options
    }

    fn start<S: OdeSystem + ?Sized>(
        &self,
        system: &mut S,
        t0: f64,
        y0: &[f64],
        t_end: f64,
    ) -> Result<GeneralizedAlphaStepper, IntegratorError> {
        let dim = system.dim();
        crate::common::validate_start(&self.options, dim, y0, t0, t_end)?;
        let options = self.options.for_system(&*system);
        let rho = self.spectral_radius;
        if !(0.0..=1.0).contains(&rho) {
            return Err(IntegratorError::InvalidOptions(format!(
                "the generalized-alpha spectral radius must be between 0 and 1, got {rho}"
            )));
        }
        let Some(form) = system.second_order_form() else {
            return Err(IntegratorError::InvalidInput(
                "generalized_alpha needs a mechanical system (M q'' = F with its mass and \
                 stiffness matrices); this one has none: use abm, rk45 or bdf"
                    .to_string(),
            ));
        };
        let n = form.coordinates();
        let structure = form.structure();
        let residual_form = form.has_residual();
        if 2 * n != dim {
            return Err(IntegratorError::InvalidInput(format!(
                "generalized_alpha integrates states (q, q') only: this system has {n} \
                 coordinates and {} further first-order states; use abm, rk45 or bdf",
                dim as isize - 2 * n as isize
            )));
        }
        let algebra = match structure {
            Some(s) if s.coordinates() == n => Algebra::Structured {
                lu: Box::new(BandedBordered::new(&s)),
                mass: Box::new(BandedBordered::new(&s)),
            },
            Some(s) => {
                return Err(IntegratorError::InvalidInput(format!(
                    "the mechanical form has {n} coordinates but its structure {}",
                    s.coordinates()
                )));
            }
            None => Algebra::Dense(DenseLu::new(n)),
        };
        let mut stats = Stats {
            orders: vec![0; 3],
            ..Stats::default()
        };
        let direction = (t_end - t0).signum();
        let mut f0 = vec![0.0; dim];
        system.rhs(t0, y0, &mut f0);
        stats.rhs_evaluations += 1;
        if let Some(component) = first_non_finite(&f0) {
            return Err(IntegratorError::NonFinite { t: t0, component });
        }
        let h_max = options.max_step.min((t_end - t0).abs());
        let h0 = match options.initial_step {
            Some(h) => h.min(h_max),
            None => {
                let mut work = vec![0.0; 2 * dim];
                stats.rhs_evaluations += 1;
                initial_step(
                    system, t0, y0, &f0, 2, direction, h_max, &options, &mut work,
                )
            }
        };
        let acc = f0[n..].to_vec();
        Ok(GeneralizedAlphaStepper {
            options,
            parameters: Parameters::new(rho),
            n,
            span: Span::new(t0, t_end, stats),
            direction,
            h_next: h0,
            y: y0.to_vec(),
            aux: acc.clone(),
            aux_step: acc.clone(),
            acc_old: acc.clone(),
            acc,
            y_old: y0.to_vec(),
            y_new: vec![0.0; dim],
            x: vec![0.0; n],
            fixed: vec![0.0; dim],
            f: f0,
            delta: vec![0.0; n],
            error: vec![0.0; dim],
            mass: Mat::zeros(n, n),
            damping: Mat::zeros(n, n),
            stiffness: Mat::zeros(n, n),
            algebra,
            residual_form,
            lu_h: None,
            matrices_current: false,
            matrices_valid: false,
            steps_since_matrices: 0,
            newton_rate: 1.0,
            error_old: 0.0,
        })
    }
}
