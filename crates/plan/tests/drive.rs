//! The motor's torque-speed envelope in the plan (`[actuators]` with `torque_constant`,
//! `resistance`, `bus_voltage`): with a vanishing winding resistance the bus voltage is a
//! speed limit at the no-load speed `V / K_e` (closed form), so the plan equals the plan with
//! that `max_speed` and no drive; with a real resistance the planned circle, re-run by the run
//! layer at ten times the plan's resolution, keeps the winding voltage `R tau / K_t + K_e
//! omega` computed from the run's own kinematics and rigid drive forces within the bus.

use flexprr_plan::{Options, plan_scene, scene_toml};
use flexprr_scene::{OutputKind, Scene};

const NO_RUNS: Options = Options {
    flexible_check: false,
};

const TORQUE_CONSTANT: f64 = 0.2;
const BUS: f64 = 100.0;

fn circle(actuator_extra: &str, max_speed: f64) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/plan_circle_motor.toml");
    let text = std::fs::read_to_string(path).unwrap().replace(
        "max_speed = 100 ",
        &format!("max_speed = {max_speed}\n{actuator_extra}\n"),
    );
    assert!(text.contains(&format!("max_speed = {max_speed}")));
    Scene::from_text("drive.toml", "drive", &text).unwrap()
}

#[test]
fn a_drive_without_resistance_limits_the_speed_at_its_no_load_speed() {
    // V / K_e = 500 rad/s = 79.58 rev/s, below the motor's own 100 rev/s.
    let no_load_rev_s = BUS / TORQUE_CONSTANT / std::f64::consts::TAU;
    let drive =
        format!("torque_constant = {TORQUE_CONSTANT}\nresistance = 1e-6\nbus_voltage = {BUS}\n");
    let with_drive = plan_scene(&circle(&drive, 100.0), NO_RUNS, &mut |_| {}).unwrap();
    let as_speed = plan_scene(&circle("", no_load_rev_s), NO_RUNS, &mut |_| {}).unwrap();
    let (f_drive, f_speed) = (
        with_drive.plan.frequency().unwrap(),
        as_speed.plan.frequency().unwrap(),
    );
    assert!(
        (f_drive / f_speed - 1.0).abs() <= 2e-4,
        "{f_drive} Hz with the drive, {f_speed} Hz with max_speed = V / K_e"
    );
    // And the bus voltage is what binds.
    let voltage = with_drive
        .plan
        .check
        .constraints
        .iter()
        .find(|u| u.constraint == "motor_voltage")
        .unwrap();
    assert!(
        voltage.usage > 0.999 && voltage.usage <= 1.0 + 1e-9,
        "{voltage:?}"
    );
}

#[test]
fn the_planned_motion_keeps_the_winding_voltage_within_the_bus() {
    let (resistance, current_limit) = (1.5, 12.0);
    let drive = format!(
        "torque_constant = {TORQUE_CONSTANT}\nresistance = {resistance}\nbus_voltage = {BUS}\ncurrent_limit = {current_limit}\n"
    );
    let scene = circle(&drive, 100.0);
    let outcome = plan_scene(&scene, NO_RUNS, &mut |_| {}).unwrap();
    let without = plan_scene(&circle("", 100.0), NO_RUNS, &mut |_| {}).unwrap();
    let f = outcome.plan.frequency().unwrap();
    assert!(f < without.plan.frequency().unwrap());

    // Re-run the planned scene densely and evaluate the drive from the run's own tables.
    let mut file = outcome.planned_file.clone();
    let step = outcome.plan.timing.duration() / (outcome.plan.grid_points as f64 * 10.0);
    file.time.output_step = Some(step);
    file.output.requests = vec![OutputKind::Kinematics, OutputKind::DrivingForces];
    file.output.plots = false;
    let text = scene_toml(&file, "planned").unwrap();
    assert!(
        text.contains("bus_voltage = 100"),
        "the drive is kept in the planned scene"
    );
    let planned = Scene::from_text("planned.toml", "planned", &text).unwrap();
    let result = flexprr_run::run(&planned, &mut |_| {}).unwrap();
    let column =
        |table: &str, name: String| result.table(table).unwrap().column(&name).unwrap().to_vec();
    // The motor as in the scene (docs/control.md): lead 10 mm, efficiency 0.9, rotor
    // 1.6e-5 kg m^2, viscous 1e-4 N m s/rad, Coulomb 0.02 N m.
    let (lead, eta, rotor, viscous, coulomb) = (0.01, 0.9, 1.6e-5, 1e-4, 0.02);
    let g = std::f64::consts::TAU / lead;
    let reflected = rotor * g * g;
    let (mut worst_voltage, mut worst_current) = (0.0f64, 0.0f64);
    for leg in 1..=3 {
        let v = column("kinematics", format!("rho_dot_{leg}_m_s"));
        let a = column("kinematics", format!("rho_ddot_{leg}_m_s2"));
        let force = column("driving_forces", format!("F_a_{leg}_rigid_N"));
        for k in 0..v.len() {
            let omega = g * v[k];
            let torque = (force[k] + reflected * a[k]) / (g * eta)
                + viscous * omega
                + coulomb * v[k].signum();
            let voltage = resistance * torque / TORQUE_CONSTANT + TORQUE_CONSTANT * omega;
            worst_voltage = worst_voltage.max(voltage.abs());
            worst_current = worst_current.max((torque / TORQUE_CONSTANT).abs());
        }
    }
    assert!(
        worst_voltage <= BUS * 1.001,
        "winding voltage {worst_voltage} V"
    );
    // The envelope is used: the bus binds within 1 % somewhere.
    assert!(
        worst_voltage >= BUS * 0.99,
        "winding voltage {worst_voltage} V"
    );
    assert!(
        worst_current <= current_limit * 1.001,
        "current {worst_current} A"
    );
}
