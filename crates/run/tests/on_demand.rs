//! Outputs are computed only when requested, and the run statistics prove it: a
//! frequencies-only scene never integrates, a kinematics-only scene never solves the inverse
//! dynamics, a scene without axial force integrates without a single inverse-dynamics solve
//! unless driving forces are asked for.
//!
//! Besides the counters, each test checks one number of the output it did compute against
//! an independent value (closed form or the trajectory's own definition), so that "did no
//! work" cannot pass by producing nothing.

use std::f64::consts::{PI, TAU};

use flexprr_run::{RunStats, run};
use flexprr_scene::Scene;

/// The paper's machine and links on the 20 Hz circle, with `model`, `time` and `output`
/// tables supplied by the test.
fn scene(model: &str, time: &str, requests: &str) -> Scene {
    let text = format!(
        r#"
[links]
length = 0.2
modes = 3
material = {{ youngs_modulus = 7.3e10, density = 2770.0 }}
section = {{ kind = "uniform", thickness = 0.002, height = 0.03 }}

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 20.0
phi_deg = 45.0

[model]
{model}

[integrator]
method = "abm"
rtol = 1e-7
atol = 1e-11

[time]
{time}

[output]
requests = {requests}
plots = false
"#
    );
    Scene::from_text("on_demand.toml", "on_demand", &text).expect("valid scene")
}

fn stats_of(scene: &Scene) -> (flexprr_run::RunResult, RunStats) {
    let result = run(scene, &mut |_| {}).expect("the run succeeds");
    let stats = result.stats.clone();
    (result, stats)
}

#[test]
fn frequencies_only_never_integrates() {
    let scene = scene(
        "formulation = \"paper\"",
        "end = 0.05\noutput_step = 0.001",
        "[\"frequencies\"]",
    );
    assert!(!scene.needs_integration());
    let (result, stats) = stats_of(&scene);
    assert!(!stats.integrated);
    assert_eq!(stats.rhs_evaluations, 0);
    assert!(stats.integrator.is_none());
    assert!(result.table("modes").is_none() && result.table("deflections").is_none());
    // The unloaded sine modes of a uniform pinned-pinned link are exact: f_j = (j pi / l)^2
    // sqrt(EI / rhoA) / (2 pi) (e.g. Meirovitch, Fundamentals of Vibrations, 2001, 8.6).
    let (e, rho, t, h, l): (f64, f64, f64, f64, f64) = (7.3e10, 2770.0, 0.002, 0.03, 0.2);
    let ei = e * h * t.powi(3) / 12.0;
    let rho_a = rho * t * h;
    let history = result.frequencies.as_ref().expect("frequencies computed");
    let link_one: Vec<_> = history.ranges.iter().filter(|r| r.link == 0).collect();
    assert_eq!(link_one.len(), 3);
    for range in link_one {
        let k = (range.mode + 1) as f64 * PI / l;
        let exact = k * k * (ei / rho_a).sqrt() / TAU;
        assert!(
            ((range.nominal_hz - exact) / exact).abs() < 1e-8,
            "mode {}: {} vs {exact}",
            range.mode + 1,
            range.nominal_hz
        );
        assert!(range.min_hz <= range.nominal_hz.max(range.max_hz));
    }
}

#[test]
fn kinematics_only_never_solves_inverse_dynamics() {
    let scene = scene(
        "formulation = \"paper\"",
        "end = 0.05\noutput_step = 0.001",
        "[\"kinematics\"]",
    );
    let (result, stats) = stats_of(&scene);
    assert!(!stats.integrated);
    assert_eq!(stats.rhs_evaluations, 0);
    assert_eq!(stats.inverse_dynamics_solves, 0);
    assert_eq!(result.tables.len(), 1);
    // The platform follows x = 0.05 cos(2 pi 20 t) - 0.05, y = 0.05 sin(2 pi 20 t).
    let table = result.table("kinematics").expect("kinematics table");
    let (t, x, y) = (
        table.column("t_s").unwrap(),
        table.column("x_m").unwrap(),
        table.column("y_m").unwrap(),
    );
    assert_eq!(t.len(), 51);
    for k in 0..t.len() {
        let angle = TAU * 20.0 * t[k];
        assert!((x[k] - (0.05 * angle.cos() - 0.05)).abs() < 1e-14);
        assert!((y[k] - 0.05 * angle.sin()).abs() < 1e-14);
    }
}

#[test]
fn deflections_without_axial_force_need_no_inverse_dynamics() {
    let scene = scene(
        "formulation = \"consistent\"\naxial_force = \"none\"",
        "end = 0.01\noutput_step = 0.001",
        "[\"deflections\"]",
    );
    assert!(scene.needs_integration());
    let (result, stats) = stats_of(&scene);
    assert!(stats.integrated);
    assert!(stats.rhs_evaluations > 0);
    assert_eq!(stats.inverse_dynamics_solves, 0);
    // The counted evaluations are the integrator's own.
    let integrator = stats.integrator.as_ref().expect("integrator statistics");
    assert_eq!(stats.rhs_evaluations, integrator.rhs_evaluations);
    // Zero initial state (the paper's): every deflection starts at exactly zero.
    let table = result.table("deflections").expect("deflections table");
    for i in 1..=3 {
        let w = table.column(&format!("w_{i}_xi0.5_m")).unwrap();
        assert!(w[0].abs() < 1e-300);
        assert!(w.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn driving_forces_alone_take_one_rigid_solve_per_output_time() {
    let scene = scene(
        "formulation = \"consistent\"\naxial_force = \"none\"",
        "end = 0.05\noutput_step = 0.001",
        "[\"driving_forces\"]",
    );
    let (result, stats) = stats_of(&scene);
    assert!(!stats.integrated);
    assert_eq!(stats.rhs_evaluations, 0);
    assert_eq!(stats.inverse_dynamics_solves, scene.output_times.len());
    let table = result
        .table("driving_forces")
        .expect("driving forces table");
    assert!(table.column("F_a_1_rigid_N").is_some());
    assert!(table.column("F_a_1_flexible_N").is_none());
}

#[test]
fn driving_forces_with_deflections_add_a_flexible_solve_per_output_time() {
    let scene = scene(
        "formulation = \"consistent\"\naxial_force = \"none\"",
        "end = 0.01\noutput_step = 0.001",
        "[\"deflections\", \"driving_forces\"]",
    );
    let (result, stats) = stats_of(&scene);
    assert!(stats.integrated && stats.rhs_evaluations > 0);
    // No axial force: nothing inside the ODE; one rigid and one flexible solve per sample.
    assert_eq!(stats.inverse_dynamics_solves, 2 * scene.output_times.len());
    let table = result
        .table("driving_forces")
        .expect("driving forces table");
    let (rigid, flexible, difference) = (
        table.column("F_a_1_rigid_N").unwrap(),
        table.column("F_a_1_flexible_N").unwrap(),
        table.column("F_a_1_difference_N").unwrap(),
    );
    for k in 0..rigid.len() {
        let scale = rigid[k].abs().max(1.0);
        assert!((flexible[k] - rigid[k] - difference[k]).abs() < 1e-12 * scale);
    }
}

#[test]
fn axial_force_from_joint_reactions_solves_inside_the_ode() {
    let scene = scene(
        "formulation = \"consistent\"",
        "end = 0.01\noutput_step = 0.001",
        "[\"deflections\"]",
    );
    let (_, stats) = stats_of(&scene);
    assert!(stats.integrated);
    // The joint-reaction axial force needs the rigid reactions inside the right-hand side.
    assert!(stats.rhs_evaluations > 0);
    assert!(stats.inverse_dynamics_solves > 0);
}
