//! `flexprr plan` as a library: the planned scene, written as TOML and read back, re-run by
//! the run layer at ten times the plan's resolution, keeps every limit to 0.1 % (the run's
//! own kinematics and rigid inverse dynamics, none of the planner's path form); the plan
//! agrees with the second method (phase-plane integration) and the constant-speed closed
//! form; bad settings are refused at their keys.

use flexprr_plan::{Options, PlanError, plan_scene, scene_toml};
use flexprr_planning::{Planner, SliderForce, SliderSpeed};
use flexprr_scene::{OutputKind, Scene};

fn config(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs")
        .join(name);
    std::fs::read_to_string(path).unwrap()
}

fn scene_with(base: &str, plan: &str) -> Scene {
    let text = format!("{}\n[plan]\n{plan}\n", config(base));
    Scene::from_text("test.toml", "test", &text).unwrap()
}

const NO_RUNS: Options = Options {
    flexible_check: false,
};

/// The largest `|value|` over the columns named `{stem}_{leg}_{unit}` of a table.
fn largest(result: &flexprr_run::RunResult, table: &str, stem: &str, unit: &str) -> f64 {
    let table = result.table(table).unwrap();
    (1..=3)
        .map(|leg| {
            table
                .column(&format!("{stem}_{leg}_{unit}"))
                .unwrap()
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()))
        })
        .fold(0.0, f64::max)
}

/// Re-runs a planned scene from its TOML text with the output step a tenth of the plan's
/// mean grid interval in time; returns the largest slider speed and rigid drive force.
fn rerun_dense(outcome: &flexprr_plan::PlanOutcome) -> (f64, f64) {
    let mut file = outcome.planned_file.clone();
    let step = outcome.plan.timing.duration() / (outcome.plan.grid_points as f64 * 10.0);
    file.time.output_step = Some(step);
    file.output.requests = vec![OutputKind::Kinematics, OutputKind::DrivingForces];
    file.output.plots = false;
    let text = scene_toml(&file, "planned").unwrap();
    assert!(text.contains("kind = \"planned\""));
    assert!(!text.contains("[plan]"));
    let scene = Scene::from_text("planned.toml", "planned", &text).unwrap();
    assert!(scene.output_times.len() > 10 * outcome.plan.grid_points);
    let result = flexprr_run::run(&scene, &mut |_| {}).unwrap();
    (
        largest(&result, "kinematics", "rho_dot", "m_s"),
        largest(&result, "driving_forces", "F_a", "rigid_N"),
    )
}

#[test]
fn planned_pick_and_place_rerun_densely_keeps_its_limits() {
    let scene = scene_with(
        "pick_and_place.toml",
        "slider_speed = 1.0\nslider_force = 400.0",
    );
    let outcome = plan_scene(&scene, NO_RUNS, &mut |_| {}).unwrap();
    let (speed, force) = rerun_dense(&outcome);
    // Within 0.1 %, and binding (the motion is not merely slow).
    assert!((0.999..=1.001).contains(&speed), "speed {speed}");
    assert!((399.0..=400.4).contains(&force), "force {force}");
    // The scene's own quintic timing breaks the speed limit (1.677 m/s), as checked.
    let own = outcome.scene_timing.check.as_ref().unwrap();
    let worst = own.worst().unwrap();
    assert_eq!(worst.constraint, "slider_speed");
    assert!((worst.value.abs() - 1.677).abs() < 1e-3, "{}", worst.value);
    // The second method: phase-plane integration on the same path and limits.
    let planner = Planner::new(&scene.machine, &outcome.path, Default::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap());
    let phase = planner.phase_plane(20_000).unwrap();
    let relative = (outcome.plan.duration - phase.duration).abs() / phase.duration;
    assert!(
        relative < 1e-4,
        "TOPP-RA {} phase plane {}",
        outcome.plan.duration,
        phase.duration
    );
    // The planned scene starts where the scene's move starts and keeps its settling time.
    assert!(outcome.start.abs() < 1e-15);
    assert!((outcome.settle_time - 0.05).abs() < 1e-12);
}

#[test]
fn periodic_circle_rerun_densely_keeps_its_limits_and_beats_constant_speed() {
    let scene = scene_with(
        "paper_f20.toml",
        "boundary = \"periodic\"\nslider_speed = 1.0\nslider_force = 400.0",
    );
    let outcome = plan_scene(&scene, NO_RUNS, &mut |_| {}).unwrap();
    let f = outcome.plan.frequency().unwrap();
    let (speed, force) = rerun_dense(&outcome);
    assert!(speed <= 1.001, "speed {speed}");
    assert!(force <= 400.0 * 1.001, "force {force}");
    // Constant speed: velocities scale with f, so the 20 Hz circle's largest slider speed
    // gives the closed form f_c = 20 v / v_20 (the force limit does not bind there).
    let v20 = outcome.scene_timing.check.as_ref().unwrap().constraints[0]
        .value
        .abs();
    let f_constant = 20.0 / v20;
    assert!(
        f > f_constant * 1.05,
        "time-optimal {f} Hz, constant speed {f_constant} Hz"
    );
    // The planned scene's span covers as many periods as the scene's.
    let span = scene.output_times[scene.output_times.len() - 1] - scene.output_times[0];
    let periods = (span * 20.0).round();
    let planned_span = outcome.planned_file.time.end - outcome.planned_file.time.start;
    assert!((planned_span - periods / f).abs() < 1e-9);
}

#[test]
fn a_scene_without_plan_and_impossible_limits_are_refused_with_where() {
    let scene = Scene::from_text("x.toml", "x", &config("pick_and_place.toml")).unwrap();
    let e = plan_scene(&scene, NO_RUNS, &mut |_| {}).unwrap_err();
    assert!(matches!(e, PlanError::NoPlan { .. }), "{e}");
    assert!(e.to_string().contains("[plan]"));
    // A motor whose Coulomb friction alone needs more than its peak torque at any speed:
    // no motion can meet the torque limit; the error names the limit, the leg and where.
    let text = format!(
        "{}\n[actuators]\nkind = \"motor_ballscrew\"\nrotor_inertia = 1e-5\nlead = 0.01\n\
         efficiency = 0.9\npeak_torque = 0.5\ncontinuous_torque = 0.3\nmax_speed = 100.0\n\
         coulomb_friction = 0.6\n[plan]\nslider_speed = 1.0\nmotor_rms = false\n",
        config("pick_and_place.toml")
    );
    let scene = Scene::from_text("m.toml", "m", &text).unwrap();
    let e = plan_scene(&scene, NO_RUNS, &mut |_| {}).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, PlanError::Planning { .. }), "{message}");
    assert!(
        message.contains("motor_torque") && message.contains("s = "),
        "{message}"
    );
    assert!(message.contains("pose"), "{message}");
}

#[test]
fn bad_plan_settings_are_refused_at_their_key_and_line() {
    let bad = |plan: &str| {
        let text = format!("{}\n[plan]\n{plan}\n", config("pick_and_place.toml"));
        Scene::from_text("bad.toml", "bad", &text)
            .unwrap_err()
            .to_string()
    };
    let lines = config("pick_and_place.toml").lines().count();
    let e = bad("slider_speed = -1.0");
    assert!(e.contains("plan.slider_speed") && e.contains("> 0"), "{e}");
    assert!(e.contains(&format!("bad.toml:{}:", lines + 3)), "{e}");
    let e = bad("boundary = \"periodic\"\nslider_speed = 1.0");
    assert!(
        e.contains("plan.boundary") && e.contains("closed path"),
        "{e}"
    );
    let e = bad("shaping = \"zv\"");
    assert!(e.contains("plan") && e.contains("no limit"), "{e}");
    let e = bad("slider_sped = 1.0");
    assert!(e.contains("plan.slider_sped"), "{e}");
    let e = bad("slider_speed = 1.0\nphi_min_deg = 10.0");
    assert!(
        e.contains("plan.phi_min_deg") && e.contains("no effect"),
        "{e}"
    );
}
