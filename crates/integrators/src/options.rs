//! Options shared by every method.

use crate::IntegratorError;

/// Absolute tolerance: one value for all components or one per component.
#[derive(Debug, Clone, PartialEq)]
pub enum Tolerance {
    /// The same absolute tolerance for every component.
    Scalar(f64),
    /// One absolute tolerance per component.
    PerComponent(Vec<f64>),
}

impl Tolerance {
    /// Absolute tolerance of component `i`.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Tolerance::Scalar(a) => *a,
            Tolerance::PerComponent(v) => v[i],
        }
    }
}

/// Options shared by all integrators.
///
/// The local error of a step is accepted when its weighted RMS norm (see
/// [`crate::error_norm`]) is at most 1, with weights `atol_i + rtol * max(|y_i|, |y_new_i|)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Relative tolerance (> 0).
    pub rtol: f64,
    /// Absolute tolerance (>= 0, not all zero with `rtol`).
    pub atol: Tolerance,
    /// Initial step size; `None` selects it automatically (Hairer's algorithm, see
    /// [`crate::initial_step`]).
    pub initial_step: Option<f64>,
    /// Largest step size allowed (default: unbounded, i.e. `|t_end - t0|`).
    pub max_step: f64,
    /// Largest number of steps (accepted + rejected) before giving up.
    pub max_steps: usize,
    /// The spectral radius at infinite frequency, `0 <= rho_inf <= 1`, of methods with
    /// numerical dissipation ([`crate::GeneralizedAlpha`]); `None` for the method's default.
    /// Every method checks its range ([`Options::validate`]); those without numerical
    /// dissipation do not use it.
    pub spectral_radius: Option<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: Tolerance::Scalar(1e-9),
            initial_step: None,
            max_step: f64::INFINITY,
            max_steps: 1_000_000,
            spectral_radius: None,
        }
    }
}

impl Options {
    /// Sets the relative tolerance.
    #[must_use]
    pub fn rtol(mut self, rtol: f64) -> Self {
        self.rtol = rtol;
        self
    }
    /// Sets one absolute tolerance for all components.
    #[must_use]
    pub fn atol(mut self, atol: f64) -> Self {
        self.atol = Tolerance::Scalar(atol);
        self
    }
    /// Sets one absolute tolerance per component.
    #[must_use]
    pub fn atol_per_component(mut self, atol: Vec<f64>) -> Self {
        self.atol = Tolerance::PerComponent(atol);
        self
    }
    /// Sets the initial step size.
    #[must_use]
    pub fn initial_step(mut self, h0: f64) -> Self {
        self.initial_step = Some(h0);
        self
    }
    /// Sets the maximum step size.
    #[must_use]
    pub fn max_step(mut self, h_max: f64) -> Self {
        self.max_step = h_max;
        self
    }
    /// Sets the maximum number of steps.
    #[must_use]
    pub fn max_steps(mut self, n: usize) -> Self {
        self.max_steps = n;
        self
    }
    /// Sets the spectral radius at infinite frequency of methods with numerical
    /// dissipation (`0` to `1`).
    #[must_use]
    pub fn spectral_radius(mut self, rho_inf: f64) -> Self {
        self.spectral_radius = Some(rho_inf);
        self
    }

    /// The options for `system`: where it gives [`crate::OdeSystem::tolerance_scales`], the
    /// absolute tolerance of component `i` becomes `max(atol_i, rtol scale_i)`, so that the
    /// relative tolerance is measured against at least the component's natural scale.
    /// Otherwise a copy of these options. Called once when an integration starts.
    #[must_use]
    pub fn for_system<S: crate::OdeSystem + ?Sized>(&self, system: &S) -> Self {
        let dim = system.dim();
        let mut scales = vec![0.0; dim];
        if !system.tolerance_scales(&mut scales) {
            return self.clone();
        }
        self.with_scales(&scales)
    }

    /// These options with the absolute tolerance of component `i` raised to
    /// `rtol scales[i]` where that is larger (see [`Options::for_system`]); non-finite or
    /// negative scales count as none.
    #[must_use]
    pub fn with_scales(&self, scales: &[f64]) -> Self {
        let atol = scales
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let floor = if s.is_finite() && *s > 0.0 {
                    self.rtol * s
                } else {
                    0.0
                };
                self.atol.get(i).max(floor)
            })
            .collect();
        let mut out = self.clone();
        out.atol = Tolerance::PerComponent(atol);
        out
    }

    /// Checks the options against a system of dimension `dim`.
    ///
    /// # Errors
    /// [`IntegratorError::InvalidOptions`] naming the offending option and value.
    pub fn validate(&self, dim: usize) -> Result<(), IntegratorError> {
        let bad = |what: String| Err(IntegratorError::InvalidOptions(what));
        if !(self.rtol.is_finite() && self.rtol > 0.0) {
            return bad(format!(
                "rtol must be positive and finite, got {}",
                self.rtol
            ));
        }
        if self.rtol < 4.0 * f64::EPSILON {
            return bad(format!(
                "rtol = {:e} is below what double precision can deliver (4 eps = {:e})",
                self.rtol,
                4.0 * f64::EPSILON
            ));
        }
        match &self.atol {
            Tolerance::Scalar(a) => {
                if !(a.is_finite() && *a >= 0.0) {
                    return bad(format!("atol must be non-negative and finite, got {a}"));
                }
            }
            Tolerance::PerComponent(v) => {
                if v.len() != dim {
                    return bad(format!(
                        "atol has {} components but the system has {dim}",
                        v.len()
                    ));
                }
                if let Some((i, a)) = v
                    .iter()
                    .enumerate()
                    .find(|(_, a)| !(a.is_finite() && **a >= 0.0))
                {
                    return bad(format!(
                        "atol[{i}] must be non-negative and finite, got {a}"
                    ));
                }
            }
        }
        if let Some(h0) = self.initial_step {
            if !(h0.is_finite() && h0 > 0.0) {
                return bad(format!(
                    "initial_step must be positive and finite, got {h0}"
                ));
            }
        }
        if let Some(rho) = self.spectral_radius {
            if !(0.0..=1.0).contains(&rho) {
                return bad(format!(
                    "spectral_radius must be between 0 and 1, got {rho}"
                ));
            }
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return bad(format!("max_step must be positive, got {}", self.max_step));
        }
        if self.max_steps == 0 {
            return bad("max_steps must be at least 1".to_string());
        }
        Ok(())
    }
}
