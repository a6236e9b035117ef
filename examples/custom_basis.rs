//! Registers a new assumed-mode basis from outside the crates and runs a scene that names it.
//!
//! The basis is polynomial and pinned-pinned: `psi_j(xi) = xi (1 - xi) P_{j-1}(2 xi - 1)`,
//! `j = 1..r`, with `P_n` the Legendre polynomials (three-term recurrence, Abramowitz &
//! Stegun 22.7.10). Every function vanishes at both ends, so it is admissible for the
//! Rayleigh-Ritz method (the moment condition `w'' = 0` is natural and need not be imposed;
//! Meirovitch, *Principles and Techniques of Vibrations*, section 8.5). The scene names it
//! with `basis = { kind = "legendre" }`.
//!
//! Checks: the unloaded frequencies of link 1 against the closed form
//! `f_j = (j pi)^2 / (2 pi l^2) sqrt(EI / rhoA)` of a uniform pinned-pinned beam (a Ritz
//! basis gives upper bounds, within 1e-5 for ten functions), and the
//! frequency ranges over the paper's 20 Hz circle (Table I) against the built-in sine basis
//! with the same number of functions: both Ritz bases converge to the same frequencies.
//!
//! Run: `cargo run --release --example custom_basis`

use std::sync::Arc;

use flexprr_beam::Basis;
use flexprr_scene::{BasisFactory, BasisParams, ModeCount, Registry, ScenarioError, Scene};

/// `xi (1 - xi) P_{j}(2 xi - 1)`, `j = 0..r-1`.
struct LegendreBubbles {
    r: usize,
}

impl Basis for LegendreBubbles {
    fn len(&self) -> usize {
        self.r
    }

    fn eval(&self, j: usize, xi: f64) -> [f64; 3] {
        // P_n(x) and its first two x-derivatives by the recurrences
        // (n + 1) P_{n+1} = (2n + 1) x P_n - n P_{n-1},
        // P'_{n+1} = P'_{n-1} + (2n + 1) P_n, P''_{n+1} = P''_{n-1} + (2n + 1) P'_n.
        let x = 2.0 * xi - 1.0;
        let (mut p0, mut d0, mut s0) = (1.0, 0.0, 0.0);
        let (mut p1, mut d1, mut s1) = (x, 1.0, 0.0);
        let (p, dp, sp) = if j == 0 {
            (p0, d0, s0)
        } else {
            for n in 1..j {
                let nf = n as f64;
                let p2 = ((2.0 * nf + 1.0) * x * p1 - nf * p0) / (nf + 1.0);
                let d2 = d0 + (2.0 * nf + 1.0) * p1;
                let s2 = s0 + (2.0 * nf + 1.0) * d1;
                (p0, d0, s0) = (p1, d1, s1);
                (p1, d1, s1) = (p2, d2, s2);
            }
            (p1, d1, s1)
        };
        // d/dxi = 2 d/dx.
        let (q, dq, sq) = (p, 2.0 * dp, 4.0 * sp);
        let (b, db, sb) = (xi * (1.0 - xi), 1.0 - 2.0 * xi, -2.0);
        [b * q, db * q + b * dq, sb * q + 2.0 * db * dq + b * sq]
    }

    fn name(&self) -> String {
        format!("legendre bubbles (pinned-pinned), r = {}", self.r)
    }

    fn polynomial_degree(&self) -> Option<usize> {
        Some(self.r + 1)
    }
}

/// The factory the registry calls for `kind = "legendre"`: sized by `links.modes`, no keys
/// of its own (any key is refused with its location).
struct LegendreFactory;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct NoKeys {}

impl BasisFactory for LegendreFactory {
    fn mode_count(&self) -> ModeCount {
        ModeCount::FromModes
    }

    fn build(
        &self,
        params: &BasisParams<'_>,
        modes: Option<usize>,
    ) -> Result<Arc<dyn Basis>, ScenarioError> {
        let NoKeys {} = params.parse()?;
        let r = modes.ok_or_else(|| params.error("", "needs links.modes"))?;
        Ok(Arc::new(LegendreBubbles { r }))
    }
}

/// The paper's scene (20 Hz circle, consistent formulation), frequencies only, with `basis`.
fn scene_text(basis: &str, modes: usize) -> String {
    format!(
        r#"name = "custom_basis_{basis}"

[links]
length = 0.2
modes = {modes}
material = {{ youngs_modulus = 7.3e10, density = 2770.0 }}
section = {{ kind = "uniform", thickness = 0.002, height = 0.03 }}
basis = {{ kind = "{basis}" }}

[trajectory]
kind = "circle"
frequency = 20.0

[time]
end = 0.05
output_step = 0.0005

[output]
requests = ["frequencies"]
plots = false
"#
    )
}

fn main() {
    let mut registry = Registry::default();
    registry.register_basis("legendre", Arc::new(LegendreFactory));
    let modes = 10;
    let run = |basis: &str| {
        let scene = Scene::from_text_with(
            &registry,
            "custom_basis.toml",
            "custom",
            &scene_text(basis, modes),
        )
        .unwrap_or_else(|e| panic!("scene rejected: {e}"));
        let result = flexprr_run::run(&scene, &mut |_| {}).unwrap_or_else(|e| panic!("run: {e}"));
        let history = result.frequencies.expect("frequencies were requested");
        let ranges: Vec<_> = history.ranges.into_iter().filter(|r| r.link == 0).collect();
        (scene.machine.links[0].basis.name(), ranges)
    };
    let (name, legendre) = run("legendre");
    let (_, sine) = run("sine");
    // Closed form of the unloaded uniform pinned-pinned beam.
    let (e, rho, t, h, l): (f64, f64, f64, f64, f64) = (7.3e10, 2770.0, 0.002, 0.03, 0.2);
    let (ei, rho_a) = (e * h * t * t * t / 12.0, rho * t * h);
    println!("basis: {name}");
    println!(
        "| mode | closed form (Hz) | nominal (Hz) | min (Hz) | max (Hz) | sine min (Hz) | sine max (Hz) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (p, s) in legendre.iter().zip(&sine).take(3) {
        let j = (p.mode + 1) as f64;
        let exact = (j * std::f64::consts::PI).powi(2) / (2.0 * std::f64::consts::PI * l * l)
            * (ei / rho_a).sqrt();
        println!(
            "| {} | {exact:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
            p.mode + 1,
            p.nominal_hz,
            p.min_hz,
            p.max_hz,
            s.min_hz,
            s.max_hz
        );
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
        // Rayleigh-Ritz: an upper bound that converges fast (1e-5 for r = 10 on mode 3).
        assert!(
            p.nominal_hz >= exact * (1.0 - 1e-12) && rel(p.nominal_hz, exact) < 1e-5,
            "mode {}: nominal {} Hz against the closed form {exact} Hz",
            p.mode + 1,
            p.nominal_hz
        );
        for (a, b, what) in [
            (p.min_hz, s.min_hz, "minimum"),
            (p.max_hz, s.max_hz, "maximum"),
        ] {
            assert!(
                rel(a, b) < 1e-4,
                "mode {} {what}: legendre {a} Hz against sine {b} Hz",
                p.mode + 1
            );
        }
    }
    println!("ok");
}
