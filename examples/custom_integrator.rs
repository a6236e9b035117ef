//! Registers a new integrator from outside the crates and runs a scene that names it.
//!
//! The method is the classical fourth-order Runge-Kutta scheme with a fixed step
//! (Hairer, Norsett & Wanner, *Solving ODEs I*, section II.1, table 1.2), with cubic Hermite
//! dense output between steps (ibid. section II.6). It implements the integrators'
//! `Integrator` and `Stepper` traits; the registry turns it into the name `rk4` that
//! `integrator.method` can give. The scene (the paper's 20 Hz circle, 0.05 s) is run with
//! `rk4` and with the built-in `abm`, and the mid-point deflections of link 1 must agree.
//! A second run with twice the step checks the fourth order: halving the step divides the
//! error against the tight `abm` solution by about 2^4 = 16.
//!
//! Run: `cargo run --release --example custom_integrator`

mod common;

use std::sync::Arc;

use flexprr_integrators::{Integrator, IntegratorError, OdeSystem, Options, Stats, Stepper};
use flexprr_scene::{Registry, Scene};

/// Classical RK4 with the fixed step `h`.
struct Rk4 {
    options: Options,
    h: f64,
}

/// One RK4 integration: the current and previous state with their derivatives (for the
/// Hermite interpolant) and preallocated stage vectors, so a step does not allocate.
struct Rk4Stepper {
    h: f64,
    t: f64,
    t_end: f64,
    y: Vec<f64>,
    f: Vec<f64>,
    t_prev: f64,
    y_prev: Vec<f64>,
    f_prev: Vec<f64>,
    k: [Vec<f64>; 4],
    tmp: Vec<f64>,
    stats: Stats,
}

impl Integrator for Rk4 {
    type Stepper = Rk4Stepper;

    fn name(&self) -> &'static str {
        "rk4"
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
    ) -> Result<Rk4Stepper, IntegratorError> {
        if y0.len() != system.dim() || y0.iter().any(|v| !v.is_finite()) {
            return Err(IntegratorError::InvalidInput(
                "y0 must be finite and of the system's dimension".into(),
            ));
        }
        if t_end <= t0 {
            return Err(IntegratorError::InvalidInput(
                "this RK4 integrates forwards only".into(),
            ));
        }
        let n = y0.len();
        let mut f = vec![0.0; n];
        system.rhs(t0, y0, &mut f);
        let stats = Stats {
            rhs_evaluations: 1,
            ..Stats::default()
        };
        Ok(Rk4Stepper {
            h: self.h,
            t: t0,
            t_end,
            y: y0.to_vec(),
            f: f.clone(),
            t_prev: t0,
            y_prev: y0.to_vec(),
            f_prev: f,
            k: [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            tmp: vec![0.0; n],
            stats,
        })
    }
}

impl Stepper for Rk4Stepper {
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn t_previous(&self) -> f64 {
        self.t_prev
    }

    fn step<S: OdeSystem + ?Sized>(&mut self, system: &mut S) -> Result<(), IntegratorError> {
        // The last step lands on t_end exactly.
        let h = self.h.min(self.t_end - self.t);
        let (t, n) = (self.t, self.y.len());
        self.k[0].copy_from_slice(&self.f);
        for (stage, c) in [(1, 0.5), (2, 0.5), (3, 1.0)] {
            for i in 0..n {
                self.tmp[i] = self.y[i] + c * h * self.k[stage - 1][i];
            }
            let (done, rest) = self.k.split_at_mut(stage);
            let _ = done;
            system.rhs(t + c * h, &self.tmp, &mut rest[0]);
        }
        self.y_prev.copy_from_slice(&self.y);
        self.f_prev.copy_from_slice(&self.f);
        for i in 0..n {
            self.y[i] +=
                h / 6.0 * (self.k[0][i] + 2.0 * self.k[1][i] + 2.0 * self.k[2][i] + self.k[3][i]);
        }
        self.t_prev = t;
        self.t = if self.t_end - (t + h) <= 1e-12 * h {
            self.t_end
        } else {
            t + h
        };
        system.rhs(self.t, &self.y, &mut self.f);
        self.stats.rhs_evaluations += 4;
        self.stats.accepted_steps += 1;
        if self.y.iter().any(|v| !v.is_finite()) {
            return Err(IntegratorError::InvalidInput(format!(
                "non-finite state at t = {} s",
                self.t
            )));
        }
        Ok(())
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        // Cubic Hermite on [t_prev, t] from the states and derivatives at both ends.
        let h = self.t - self.t_prev;
        let s = if h > 0.0 { (t - self.t_prev) / h } else { 1.0 };
        let (h00, h10) = (
            (1.0 + 2.0 * s) * (1.0 - s) * (1.0 - s),
            s * (1.0 - s) * (1.0 - s),
        );
        let (h01, h11) = (s * s * (3.0 - 2.0 * s), s * s * (s - 1.0));
        for (i, o) in out.iter_mut().enumerate() {
            *o = h00 * self.y_prev[i]
                + h10 * h * self.f_prev[i]
                + h01 * self.y[i]
                + h11 * h * self.f[i];
        }
    }

    fn stats(&self) -> &Stats {
        &self.stats
    }
}

/// Link 1's mid-point deflections of the paper's scene integrated by `method` (loaded
/// through `registry`).
fn deflections(registry: &Registry, method: &str) -> Vec<f64> {
    let text = common::paper_scene_text(&format!("custom_integrator_{method}"), "ked", method);
    let scene = Scene::from_text_with(registry, "custom_integrator.toml", "custom", &text)
        .unwrap_or_else(|e| panic!("scene rejected: {e}"));
    common::link1_deflections(&scene)
}

fn main() {
    let mut registry = Registry::default();
    for (name, h) in [("rk4", 2.5e-6), ("rk4_coarse", 5e-6)] {
        registry.register_integrator(name, Arc::new(move |options| Box::new(Rk4 { options, h })));
    }
    let reference = deflections(&registry, "abm");
    let fine = deflections(&registry, "rk4");
    let coarse = deflections(&registry, "rk4_coarse");
    let peak = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (e_fine, e_coarse) = (
        common::max_difference(&fine, &reference),
        common::max_difference(&coarse, &reference),
    );
    println!("link 1 mid-point deflection, 0.05 s of the paper's 20 Hz circle:");
    println!("  peak |w| (abm, rtol 1e-10)       {peak:.6e} m");
    println!("  rk4 h = 2.5e-6 s, max |rk4 - abm| {e_fine:.3e} m");
    println!("  rk4 h = 5.0e-6 s, max |rk4 - abm| {e_coarse:.3e} m");
    println!(
        "  error ratio (4th order: ~16)      {:.2}",
        e_coarse / e_fine
    );
    assert!(peak > 1e-6, "the scene must deflect the link");
    assert!(
        e_fine < 1e-4 * peak,
        "rk4 and abm disagree: {e_fine:e} m against a peak of {peak:e} m"
    );
    let ratio = e_coarse / e_fine;
    assert!(
        (8.0..32.0).contains(&ratio),
        "halving the step should divide the error by about 16, got {ratio}"
    );
    println!("ok");
}
