//! A model kind defined outside the crates runs through the whole run pipeline: outputs,
//! the failure outcome and the divergence guard, with nothing in the run layer knowing it.
//! Adding a model kind is one new type implementing `SceneModel`.
//!
//! The model: every link is one pinned-pinned sine mode (the scene's `modes = 1`) driven by
//! a constant modal force `F` from rest, `m q'' + k q = F` (the scene's own modal mass `m`
//! and stiffness `k`), so `q(t) = (F / k) (1 - cos(omega t))`, `omega^2 = k / m`: closed
//! forms for the deflection, the strain energy `k q^2 / 2` and the elastic kinetic energy
//! `m q'^2 / 2`. With a negative stiffness it grows as `(F / k) (1 - cosh(lambda t))`, and
//! the run layer's guard must stop it where the mid-point passes half the link length.

use std::sync::Arc;

use flexprr_dynamics::{
    DynamicsError, Machine, MachineSnapshot, ModelCounters, SceneModel, SliderMotion,
};
use flexprr_integrators::OdeSystem;
use flexprr_kinematics::Trajectory;
use flexprr_run::{RunError, run_model, write_outputs_with};
use flexprr_scene::Scene;

/// One sine mode per link under a constant modal force; optionally "collapses" (a model
/// failure, reported by the right-hand side) once a link's mid-point deflection passes a
/// limit.
struct Oscillators {
    machine: Arc<Machine>,
    trajectory: Arc<dyn Trajectory + Send + Sync>,
    /// Stiffness over mass `k / m` (1/s^2), negative for a runaway.
    omega_squared: f64,
    /// Modal force over mass `F / m` (m/s^2) on link `i`.
    forcing: [f64; 3],
    /// Mid-point deflection (m) beyond which the model reports a collapse.
    collapse_at: Option<f64>,
    evaluations: usize,
    failure: Option<DynamicsError>,
}

impl OdeSystem for Oscillators {
    fn dim(&self) -> usize {
        6
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.evaluations += 1;
        if let Some(limit) = self.collapse_at {
            if let Some(i) = (0..3).find(|&i| y[i].abs() > limit) {
                self.failure.get_or_insert(DynamicsError::Collapse {
                    t,
                    link: i + 1,
                    deflection: y[i],
                    length: self.machine.links[i].length(),
                    type_ii_measure: 1.0,
                });
                dy.fill(f64::NAN);
                return;
            }
        }
        for i in 0..3 {
            dy[i] = y[3 + i];
            dy[3 + i] = self.forcing[i] - self.omega_squared * y[i];
        }
    }
}

impl SceneModel for Oscillators {
    fn kind(&self) -> &'static str {
        "oscillators"
    }
    fn machine(&self) -> &Machine {
        &self.machine
    }
    fn modes(&self) -> usize {
        3
    }
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        link..link + 1
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        self.failure.take()
    }
    fn counters(&self) -> ModelCounters {
        ModelCounters {
            rhs_evaluations: self.evaluations,
            inverse_dynamics_solves: 0,
        }
    }
    fn snapshot(&mut self, t: f64, _y: &[f64]) -> Result<MachineSnapshot, DynamicsError> {
        let motion = self.trajectory.motion(t);
        let state = self
            .machine
            .geometry
            .inverse_kinematics_unchecked(&motion)
            .map_err(|source| DynamicsError::Kinematics { t, source })?;
        Ok(MachineSnapshot {
            t,
            nominal: motion,
            platform: motion,
            sliders: std::array::from_fn(|i| SliderMotion {
                position: state.legs[i].rho,
                velocity: state.legs[i].rho_dot,
                acceleration: state.legs[i].rho_ddot,
            }),
            axial_force_b: [0.0; 3],
            axial_force_c: [0.0; 3],
            driving_force: [0.0; 3],
            actuators: None,
        })
    }
}

/// The paper's machine with one mode per link, 20 ms at rtol 1e-10.
fn scene(requests: &str) -> Scene {
    let text = format!(
        r#"
[links]
modes = 1
[trajectory]
kind = "circle"
frequency = 20.0
[integrator]
method = "rk45"
rtol = 1e-10
atol = 1e-14
[time]
end = 0.02
output_step = 1e-4
[output]
requests = {requests}
deflection_xi = [0.5, 0.25]
plots = false
"#
    );
    Scene::from_text("outside.toml", "outside", &text).expect("scene")
}

/// `(k / m, psi(1/2) = 1)` of the scene's one sine mode.
fn omega_squared(scene: &Scene) -> f64 {
    let ints = &scene.machine.links[0].integrals;
    ints.stiffness[(0, 0)] / ints.mass[(0, 0)]
}

fn model(scene: &Scene, omega_squared: f64, collapse_at: Option<f64>) -> Box<dyn SceneModel> {
    Box::new(Oscillators {
        machine: scene.machine.clone(),
        trajectory: scene.trajectory.clone(),
        omega_squared,
        forcing: [1.0e2, -2.0e2, 3.0e2],
        collapse_at,
        evaluations: 0,
        failure: None,
    })
}

#[test]
fn an_outside_model_gives_every_output_from_its_closed_form() {
    let scene = scene(r#"["deflections", "energies", "modes", "driving_forces", "viewer"]"#);
    let w2 = omega_squared(&scene);
    let oscillators = model(&scene, w2, None);
    let result = run_model(&scene, oscillators, &mut |_| {}).expect("runs");
    let (omega, mass, stiffness) = {
        let ints = &scene.machine.links[0].integrals;
        (w2.sqrt(), ints.mass[(0, 0)], ints.stiffness[(0, 0)])
    };
    let forcing = [1.0e2, -2.0e2, 3.0e2];
    let q = |i: usize, t: f64| forcing[i] / w2 * (1.0 - (omega * t).cos());
    let q_dot = |i: usize, t: f64| forcing[i] / omega * (omega * t).sin();
    let deflections = result.table("deflections").expect("deflections");
    let energies = result.table("energies").expect("energies");
    let t = deflections.time().to_vec();
    assert_eq!(t.len(), scene.output_times.len());
    for (i, f) in forcing.iter().enumerate() {
        let peak = 2.0 * f.abs() / w2;
        for (xi, shape) in [(0.5, 1.0), (0.25, std::f64::consts::FRAC_1_SQRT_2)] {
            let w = deflections
                .column(&format!("w_{}_xi{xi}_m", i + 1))
                .expect("column");
            for (k, &tk) in t.iter().enumerate() {
                let exact = shape * q(i, tk);
                assert!(
                    (w[k] - exact).abs() <= 1e-7 * peak,
                    "link {i} xi {xi} t {tk}: {} vs {exact}",
                    w[k]
                );
            }
        }
        let strain = energies.column(&format!("strain_{}_J", i + 1)).unwrap();
        let kinetic = energies
            .column(&format!("elastic_kinetic_{}_J", i + 1))
            .unwrap();
        let scale = 0.5 * stiffness * peak * peak;
        for (k, &tk) in t.iter().enumerate() {
            let (qk, vk) = (q(i, tk), q_dot(i, tk));
            assert!((strain[k] - 0.5 * stiffness * qk * qk).abs() <= 1e-6 * scale);
            assert!((kinetic[k] - 0.5 * mass * vk * vk).abs() <= 1e-6 * scale);
        }
    }
    // The model's own driving forces (zero here) sit beside the rigid ones.
    let driving = result.table("driving_forces").expect("driving forces");
    assert!(
        driving
            .column("F_a_1_flexible_N")
            .unwrap()
            .iter()
            .all(|f| *f == 0.0)
    );
    // The viewer draws the model's deflection: its frames reproduce the table.
    let viewer = result.viewer.as_ref().expect("viewer data");
    let mid = (viewer.links[1].xi.len() - 1) / 2;
    for k in [0, t.len() / 2, t.len() - 1] {
        let w = deflections.column("w_2_xi0.5_m").unwrap()[k];
        assert!((viewer.links[1].deflection(k, mid) - w).abs() <= 1e-12 * (1.0 + w.abs()));
    }
    assert!(
        viewer.deviation.is_none(),
        "the platform follows the command"
    );
    assert!(result.stats.rhs_evaluations > 0);
}

#[test]
fn an_outside_model_failure_keeps_the_outputs_up_to_its_time() {
    let scene = scene(r#"["deflections"]"#);
    let w2 = omega_squared(&scene);
    // Link 3 peaks at 2 F / k; it "collapses" at half of that, at omega t = pi / 2.
    let limit = 3.0e2 / w2;
    let t_limit = std::f64::consts::FRAC_PI_2 / w2.sqrt();
    assert!(t_limit < 0.02, "the failure falls inside the scene");
    let failure =
        run_model(&scene, model(&scene, w2, Some(limit)), &mut |_| {}).expect_err("it collapses");
    assert_eq!(failure.error.kind(), "collapse");
    assert_eq!(failure.error.link(), Some(2));
    let t_fail = failure.error.time().expect("a time");
    assert!(
        t_fail >= 0.99 * t_limit && t_fail <= t_limit + 1e-4,
        "{t_fail} vs {t_limit}"
    );
    // The outputs up to the failure are kept and written, with the status.
    let table = failure
        .partial
        .table("deflections")
        .expect("partial deflections");
    let last = *table.time().last().expect("rows");
    assert!(last <= t_fail && last >= t_fail - 2e-4, "{last} {t_fail}");
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("out");
    write_outputs_with(
        &scene,
        &failure.partial,
        Some(&failure.error),
        &out,
        Default::default(),
    )
    .expect("written");
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    assert!(summary.contains("\"failed\""), "{summary}");
    assert!(out.join("deflections.csv").exists());
}

#[test]
fn the_divergence_guard_stops_an_outside_model_that_runs_away() {
    let scene = scene(r#"["deflections"]"#);
    // Negative stiffness: q = (F / k)(1 - cosh(lambda t)) with k / m = -lambda^2 grows until
    // the mid-point passes half the link length (the guard's limit), at
    // cosh(lambda t) = 1 + 0.5 l lambda^2 / F on the fastest link (F = 300).
    let lambda = 900.0;
    let length = scene.machine.links[2].length();
    let t_cross = (1.0 + 0.5 * length * lambda * lambda / 3.0e2).acosh() / lambda;
    assert!(t_cross < 0.02);
    let failure = run_model(&scene, model(&scene, -lambda * lambda, None), &mut |_| {})
        .expect_err("it diverges");
    match &failure.error {
        RunError::Diverged { link, t, .. } => {
            assert_eq!(*link, 2, "the link with the largest forcing");
            assert!(
                *t >= t_cross * (1.0 - 1e-9) && *t <= t_cross * 1.05,
                "{t} vs {t_cross}"
            );
        }
        other => panic!("expected a divergence, got {other}"),
    }
    assert!(failure.partial.table("deflections").is_some());
}
