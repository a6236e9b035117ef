//! The control outputs against independent computations: `tracking` against the commanded
//! inverse kinematics (kinematics crate) and the integrated state; the feasibility check
//! against a hand computation from `driving_forces.csv`, `kinematics.csv` and the motor
//! formulas; the speed warning at the time the commanded slider speed first exceeds
//! `max_speed * lead`; the actuated motor's torque, speed and force against the same
//! formulas and the state.

use std::f64::consts::TAU;
use std::path::Path;

use flexprr_run::{integrate, run, write_outputs};
use flexprr_scene::Scene;

fn config(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../configs/{name}"));
    std::fs::read_to_string(path).expect("shipped config")
}

fn scene(text: &str) -> Scene {
    Scene::from_text("control.toml", "control", text).expect("valid scene")
}

/// A CSV file written by a run: columns by header.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn read(path: &Path) -> Csv {
        let text = std::fs::read_to_string(path).expect("csv written");
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
            .collect();
        Csv { header, rows }
    }
    fn column(&self, name: &str) -> Vec<f64> {
        let k = self
            .header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header));
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// The motor of the shipped motor scenes.
struct Motor {
    inertia: f64,
    lead: f64,
    efficiency: f64,
    viscous: f64,
    coulomb: f64,
    smoothing: f64,
}

const MOTOR: Motor = Motor {
    inertia: 1.6e-5,
    lead: 0.01,
    efficiency: 0.9,
    viscous: 1e-4,
    coulomb: 0.02,
    smoothing: 0.01,
};

impl Motor {
    fn ratio(&self) -> f64 {
        TAU / self.lead
    }
    /// Friction torque at the slider speed `v`: `b g v + tau_C tanh(g v / (2 pi omega_s))`.
    fn friction(&self, v: f64) -> f64 {
        let omega = self.ratio() * v;
        self.viscous * omega + self.coulomb * (omega / (TAU * self.smoothing)).tanh()
    }
    /// The torque that moves the slider with the force `f_a` (rigid driving force) at speed
    /// `v` and acceleration `a`: `(F_a + J g^2 a) / (g eta) + friction`.
    fn torque(&self, f_a: f64, v: f64, a: f64) -> f64 {
        let g = self.ratio();
        (f_a + self.inertia * g * g * a) / (g * self.efficiency) + self.friction(v)
    }
}

#[test]
fn tracking_is_the_commanded_ik_minus_the_integrated_sliders() {
    let text = config("servo_f20.toml").replace("end = 0.2", "end = 0.05");
    let scene = scene(&text);
    let result = run(&scene, &mut |_| {}).expect("runs");
    let tracking = result.table("tracking").expect("tracking");
    // The same integration, read from the state: y = (eta, rho, eta', rho').
    let (integration, model) = integrate(&scene, &mut |_| {}).expect("builds");
    assert!(integration.failure.is_none());
    let solution = &integration.solution;
    let n = 9;
    assert_eq!(model.dim(), 2 * (n + 3));
    let geometry = &scene.machine.geometry;
    let mut largest: f64 = 0.0;
    for k in 0..solution.len() {
        let t = solution.t[k];
        let commanded = geometry
            .inverse_kinematics(&scene.trajectory.motion(t))
            .expect("reachable");
        for i in 0..3 {
            let expected = commanded.legs[i].rho - solution.y(k)[n + i];
            let got = tracking
                .column(&format!("slider_error_{}_m", i + 1))
                .expect("column")[k];
            assert!((got - expected).abs() <= 1e-12, "t = {t}, slider {i}");
            largest = largest.max(expected.abs());
        }
    }
    // Microns: the servo tracks, and the errors are not all zero.
    assert!(largest > 1e-6 && largest < 1e-4, "largest error {largest}");
    // The platform error is minus the coupled model's platform deviation.
    let deviation = result.table("platform_deviation").expect("deviation");
    for (error, dev) in [
        ("platform_error_x_m", "dx_m"),
        ("platform_error_y_m", "dy_m"),
        ("platform_error_phi_rad", "dphi_rad"),
    ] {
        let (e, d) = (
            tracking.column(error).expect("error"),
            deviation.column(dev).expect("deviation"),
        );
        for (a, b) in e.iter().zip(d) {
            assert!((a + b).abs() <= 1e-15, "{error}: {a} vs -{b}");
        }
    }
    // The servo summary is the tracking table's peaks and RMS values.
    let servo = flexprr_run::control::report_of(&result)
        .servo
        .as_ref()
        .expect("servo summary");
    let e1 = tracking.column("slider_error_1_m").expect("e1");
    let peak = e1.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rms = (e1.iter().map(|x| x * x).sum::<f64>() / e1.len() as f64).sqrt();
    assert!((servo.sliders[0].error.value - peak).abs() <= 1e-18);
    assert!((servo.sliders[0].rms_error - rms).abs() <= 1e-15 * rms);
    // The viewer draws the commanded sliders (the IK) beside the actual ones.
    let viewer = result.viewer.as_ref().expect("viewer requested");
    let reference = viewer.reference_sliders.as_ref().expect("actuated");
    for (k, r) in reference.iter().enumerate() {
        let commanded = geometry
            .inverse_kinematics(&scene.trajectory.motion(viewer.time[k]))
            .expect("reachable");
        for (i, r) in r.iter().enumerate() {
            assert!((r - commanded.legs[i].rho).abs() <= 1e-15);
            assert!((viewer.sliders[k][i] - solution.y(k)[n + i]).abs() <= 1e-15);
        }
    }
    assert!(
        flexprr_run::control::report_of(&result)
            .feasibility
            .is_none(),
        "no motor, no ratings"
    );
}

#[test]
fn a_frequencies_only_ked_scene_with_a_motor_is_checked_without_integrating() {
    let text = config("servo_motor_f20.toml")
        .replace("coupling = \"coupled\"", "coupling = \"ked\"")
        .replace(
            "requests = [\"kinematics\", \"driving_forces\", \"actuators\", \"deflections\"]",
            "requests = [\"frequencies\"]",
        );
    let ked = scene(&text);
    let result = run(&ked, &mut |_| {}).expect("runs");
    assert!(!result.stats.integrated);
    let feasibility = flexprr_run::control::report_of(&result)
        .feasibility
        .as_ref()
        .expect("checked");
    let coupled = run(&scene(&config("servo_motor_f20.toml")), &mut |_| {}).expect("runs");
    // The requirement is the commanded rigid motion's, whatever the model.
    assert_eq!(
        Some(feasibility),
        flexprr_run::control::report_of(&coupled)
            .feasibility
            .as_ref()
    );
    assert!(result.warnings.iter().any(|w| w.contains("max_speed")));
}

#[test]
fn saturated_motors_on_the_20_hz_circle_let_the_mechanism_collapse() {
    // The motor scene under PD control: the motors saturate at once and the platform falls
    // behind until the chords reach a type-II pose. The run fails, keeps what it computed,
    // and the feasibility check still covers the whole commanded motion.
    let text = config("servo_motor_f20.toml") + "\n[control]\nkind = \"pd\"\nkp = 2e5\nkd = 2000\n";
    let text = text.replace(
        "requests = [\"kinematics\", \"driving_forces\", \"actuators\", \"deflections\"]",
        "requests = [\"tracking\", \"actuators\"]",
    );
    let scene = scene(&text);
    let failure = run(&scene, &mut |_| {}).expect_err("collapses");
    assert_eq!(failure.error.kind(), "collapse", "{}", failure.error);
    let partial = &failure.partial;
    let rows = partial.table("actuators").expect("actuators").rows();
    assert!(rows > 1 && rows < scene.output_times.len());
    let servo = flexprr_run::control::report_of(partial)
        .servo
        .as_ref()
        .expect("servo summary");
    assert!(
        servo
            .sliders
            .iter()
            .all(|s| s.saturated_fraction.is_some_and(|f| f > 0.5)),
        "{servo:?}"
    );
    let feasibility = flexprr_run::control::report_of(partial)
        .feasibility
        .as_ref()
        .expect("checked");
    let last = scene.output_times[scene.output_times.len() - 1];
    assert!((feasibility.span.1 - last).abs() <= 0.0);
}

#[test]
fn prescribed_sliders_track_exactly() {
    // KED: sliders and platform commanded, so every tracking error is zero.
    let text = config("paper_f20.toml").replace("end = 0.2", "end = 0.01");
    let requests = text
        .lines()
        .find(|l| l.starts_with("requests"))
        .expect("requests line");
    let text = text.replace(
        requests,
        "requests = [\"tracking\", \"actuators\", \"driving_forces\"]",
    );
    let scene = scene(&text);
    let result = run(&scene, &mut |_| {}).expect("runs");
    let tracking = result.table("tracking").expect("tracking");
    assert!(result.stats.integrated);
    for values in &tracking.data[1..] {
        assert!(values.iter().all(|v| v.abs() <= 0.0), "{values:?}");
    }
    // Without an actuator in the scene the actuators are ideal forces: the rigid driving
    // forces.
    let actuators = result.table("actuators").expect("actuators");
    assert!(actuators.column("motor_torque_1_N_m").is_none());
    let driving = result.table("driving_forces").expect("driving forces");
    for i in 1..=3 {
        let rigid = driving.column(&format!("F_a_{i}_rigid_N")).expect("rigid");
        let force = actuators
            .column(&format!("actuator_force_{i}_N"))
            .expect("force");
        let command = actuators
            .column(&format!("force_command_{i}_N"))
            .expect("command");
        assert_eq!(force, rigid);
        assert_eq!(command, rigid);
    }
}

#[test]
fn feasibility_is_the_hand_computation_from_the_written_tables() {
    let text = config("servo_motor_f20.toml");
    let scene = scene(&text);
    let result = run(&scene, &mut |_| {}).expect("runs");
    let dir = tempfile::tempdir().expect("tempdir");
    write_outputs(&scene, &result, dir.path()).expect("writes");
    let driving = Csv::read(&dir.path().join("driving_forces.csv"));
    let kinematics = Csv::read(&dir.path().join("kinematics.csv"));
    let actuators = Csv::read(&dir.path().join("actuators.csv"));
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("summary.json")).expect("summary"),
    )
    .expect("json");
    let feasibility = &summary["feasibility"];
    assert_eq!(feasibility["feasible"], false);
    for i in 1..=3 {
        let f_a = driving.column(&format!("F_a_{i}_rigid_N"));
        let v = kinematics.column(&format!("rho_dot_{i}_m_s"));
        let a = kinematics.column(&format!("rho_ddot_{i}_m_s2"));
        let torque: Vec<f64> = (0..f_a.len())
            .map(|k| MOTOR.torque(f_a[k], v[k], a[k]))
            .collect();
        let speed: Vec<f64> = v.iter().map(|v| v / MOTOR.lead).collect();
        // Per sample, the written requirement (10 significant digits in the CSV).
        let (written_torque, written_speed) = (
            actuators.column(&format!("motor_torque_{i}_N_m")),
            actuators.column(&format!("motor_speed_{i}_rev_s")),
        );
        for k in 0..torque.len() {
            assert!(
                (written_torque[k] - torque[k]).abs() <= 1e-8 * (1.0 + torque[k].abs()),
                "leg {i}, sample {k}: {} vs {}",
                written_torque[k],
                torque[k]
            );
            assert!((written_speed[k] - speed[k]).abs() <= 1e-8 * (1.0 + speed[k].abs()));
        }
        // The summary's peaks and RMS come from the motion between the samples: the
        // samples' peaks are at most them, and within the sampling error of them (at
        // 10 kHz, 1e-4 of a 20 Hz motion's peak); the RMS is the time mean's, which the
        // samples' trapezoidal mean approaches to 1e-4. Margins are the ratios.
        let leg = &feasibility["legs"][i - 1];
        let got = |key: &str| leg[key].as_f64().expect(key);
        let peak_torque = torque.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let peak_speed = speed.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let n = torque.len();
        let trapezoid = (0..n - 1)
            .map(|k| 0.5 * (torque[k] * torque[k] + torque[k + 1] * torque[k + 1]))
            .sum::<f64>()
            / (n - 1) as f64;
        for (key, sampled) in [
            ("peak_torque_N_m", peak_torque),
            ("peak_speed_rev_s", peak_speed),
        ] {
            let scanned = got(key);
            assert!(
                scanned >= sampled * (1.0 - 1e-12) && scanned <= sampled * (1.0 + 1e-4),
                "leg {i} {key}: {scanned} vs sampled {sampled}"
            );
        }
        let rms = got("rms_torque_N_m");
        assert!(
            (rms - trapezoid.sqrt()).abs() <= 1e-4 * rms,
            "leg {i}: RMS {rms} vs {}",
            trapezoid.sqrt()
        );
        let close = |key: &str, expected: f64| {
            assert!(
                (got(key) - expected).abs() <= 1e-12 * expected.abs(),
                "leg {i} {key}: {} vs {expected}",
                got(key)
            );
        };
        close("peak_torque_margin", 3.5 / got("peak_torque_N_m"));
        close("continuous_torque_margin", 1.2 / rms);
        close("speed_margin", 100.0 / got("peak_speed_rev_s"));
    }
    // Issue 24's estimate: 8.3 m/s on the 10 mm lead is about 50,000 rpm.
    let peak_speed = (0..3)
        .map(|i| feasibility["legs"][i]["peak_speed_rev_s"].as_f64().unwrap())
        .fold(0.0f64, f64::max);
    assert!((60.0 * peak_speed - 49_844.0).abs() < 1.0, "{peak_speed}");
}

/// The first time `|x|` passes `limit`, interpolated linearly between output samples.
fn crossing(t: &[f64], x: &[f64], limit: f64) -> Option<f64> {
    let k = x.iter().position(|v| v.abs() > limit)?;
    if k == 0 {
        return Some(t[0]);
    }
    let (a, b) = (x[k - 1].abs(), x[k].abs());
    Some(t[k - 1] + (limit - a) / (b - a) * (t[k] - t[k - 1]))
}

#[test]
fn the_speed_warning_names_when_the_commanded_slider_first_outruns_the_motor() {
    // The shipped scene: the circle starts at full speed, beyond 100 rev/s x 10 mm = 1 m/s.
    let shipped = scene(&config("servo_motor_f20.toml"));
    let result = run(&shipped, &mut |_| {}).expect("runs");
    let kinematics = result.table("kinematics").expect("kinematics");
    let v1 = kinematics.column("rho_dot_1_m_s").expect("v1");
    assert!(v1[0].abs() > 100.0 * MOTOR.lead, "leg 1 starts too fast");
    let feasibility = flexprr_run::control::report_of(&result)
        .feasibility
        .as_ref()
        .expect("checked");
    assert_eq!(feasibility.first_over_speed(), Some((0.0, 0)));
    assert!(
        result
            .warnings
            .iter()
            .any(|w| w.contains("max_speed of 100 rev/s") && w.contains("from t = 0 ms on leg 1")),
        "{:?}",
        result.warnings
    );
    // A faster motor: the commanded speed first passes 750 rev/s x 10 mm = 7.5 m/s later,
    // on the leg and at the time kinematics.csv says.
    let text = config("servo_motor_f20.toml").replace("max_speed = 100 ", "max_speed = 750 ");
    let faster = scene(&text);
    let result = run(&faster, &mut |_| {}).expect("runs");
    let kinematics = result.table("kinematics").expect("kinematics");
    let (t, limit) = (kinematics.time(), 750.0 * MOTOR.lead);
    let expected = (0..3)
        .filter_map(|i| {
            let v = kinematics
                .column(&format!("rho_dot_{}_m_s", i + 1))
                .expect("v");
            crossing(t, v, limit).map(|t| (t, i))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .expect("7.5 m/s is passed");
    assert!(expected.0 > 0.0);
    let (time, leg) = flexprr_run::control::report_of(&result)
        .feasibility
        .as_ref()
        .and_then(|f| f.first_over_speed())
        .expect("over speed");
    assert_eq!(leg, expected.1);
    // The crossing located on the motion itself, against the linear interpolation of the
    // 10 kHz samples (whose error is about h^2 |v''| / (8 |v'|), 2e-7 s here).
    assert!((time - expected.0).abs() <= 1e-6, "{time} vs {expected:?}");
    let text = format!(
        "from t = {} ms on leg {}",
        format_sig(1e3 * time),
        expected.1 + 1
    );
    assert!(
        result.warnings.iter().any(|w| w.contains(&text)),
        "{text}: {:?}",
        result.warnings
    );
}

/// Four significant digits without trailing zeros, as the warnings print times.
fn format_sig(x: f64) -> String {
    let decimals = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

#[test]
fn an_actuated_motor_reports_its_torque_speed_and_force_by_the_motor_formulas() {
    let text = config("servo_motor_f2.toml")
        .replace("end = 0.5 ", "end = 0.1 ")
        .replace("\"viewer\"", "\"kinematics\"");
    let scene = scene(&text);
    let result = run(&scene, &mut |_| {}).expect("runs");
    let actuators = result.table("actuators").expect("actuators");
    let (integration, _) = integrate(&scene, &mut |_| {}).expect("builds");
    let solution = &integration.solution;
    let (n, coordinates) = (9, 12);
    let g = MOTOR.ratio();
    for k in 0..solution.len() {
        for i in 0..3 {
            let column = |name: &str| {
                actuators
                    .column(&format!("{name}_{}_{}", i + 1, unit(name)))
                    .expect(name)[k]
            };
            let v = solution.y(k)[coordinates + n + i];
            let command = column("force_command");
            let torque = command / (g * MOTOR.efficiency);
            assert!(torque.abs() < 3.5, "below the peak here");
            assert!((column("motor_torque") - torque).abs() <= 1e-12 * torque.abs().max(1e-3));
            assert!((column("motor_speed") - v / MOTOR.lead).abs() <= 1e-12);
            let force = g * MOTOR.efficiency * (torque - MOTOR.friction(v));
            assert!((column("actuator_force") - force).abs() <= 1e-9 * force.abs().max(1.0));
            assert!(column("motor_saturated").abs() <= 0.0);
        }
    }
    let servo = flexprr_run::control::report_of(&result)
        .servo
        .as_ref()
        .expect("servo summary");
    assert!(
        servo
            .sliders
            .iter()
            .all(|s| s.saturated_fraction == Some(0.0))
    );
    assert!(servo.first_over_speed().is_none());
    let feasibility = flexprr_run::control::report_of(&result)
        .feasibility
        .as_ref()
        .expect("checked");
    assert!(feasibility.feasible(), "{:?}", result.warnings);
    assert!(result.warnings.is_empty(), "{:?}", result.warnings);
}

fn unit(name: &str) -> &'static str {
    match name {
        "motor_torque" => "N_m",
        "motor_speed" => "rev_s",
        "motor_saturated" => "flag",
        _ => "N",
    }
}

#[test]
fn a_drive_reports_when_the_motion_needs_more_voltage_than_its_bus() {
    // The 2 Hz circle needs up to about 80 rev/s; K_e = 0.2 V s/rad on a 100 V bus leaves a
    // no-load speed of 79.6 rev/s, so the back-EMF alone nearly uses the bus.
    let (kt, resistance, bus, current_limit) = (0.2, 1.5, 100.0, 12.0);
    let text = config("servo_motor_f2.toml")
        .replace("output_step = 5e-4", "output_step = 1e-4")
        .replace(
            r#"requests = ["tracking", "actuators", "deflections", "viewer"]"#,
            r#"requests = ["kinematics", "driving_forces", "actuators"]"#,
        )
        .replace(
            "max_speed = 100 ",
            &format!(
                "torque_constant = {kt}\nresistance = {resistance}\nbus_voltage = {bus}\ncurrent_limit = {current_limit}\nmax_speed = 100 "
            ),
        );
    assert!(text.contains("bus_voltage") && text.contains("\"driving_forces\""));
    let scene = scene(&text);
    let result = run(&scene, &mut |_| {}).expect("runs");
    let feasibility = flexprr_run::control::report_of(&result)
        .feasibility
        .as_ref()
        .expect("checked");
    let driving = result.table("driving_forces").expect("driving forces");
    let kinematics = result.table("kinematics").expect("kinematics");
    let t = kinematics.time();
    // The steady-state winding voltage R tau / K_t + K_e omega from the run's own tables.
    let mut expected: Option<(f64, usize)> = None;
    for i in 0..3 {
        let f_a = driving
            .column(&format!("F_a_{}_rigid_N", i + 1))
            .expect("F_a");
        let v = kinematics
            .column(&format!("rho_dot_{}_m_s", i + 1))
            .expect("v");
        let a = kinematics
            .column(&format!("rho_ddot_{}_m_s2", i + 1))
            .expect("a");
        let torque: Vec<f64> = (0..v.len())
            .map(|k| MOTOR.torque(f_a[k], v[k], a[k]))
            .collect();
        let voltage: Vec<f64> = (0..v.len())
            .map(|k| resistance * torque[k] / kt + kt * MOTOR.ratio() * v[k])
            .collect();
        let electrical = feasibility.legs[i].electrical.expect("a drive");
        let sampled = voltage.iter().fold(0.0f64, |m, u| m.max(u.abs()));
        let scanned = electrical.peak_voltage.value;
        assert!(
            scanned >= sampled * (1.0 - 1e-9) && scanned <= sampled * (1.0 + 1e-4),
            "leg {}: peak voltage {scanned} vs sampled {sampled}",
            i + 1
        );
        let current = torque.iter().fold(0.0f64, |m, x| m.max(x.abs())) / kt;
        assert!((electrical.peak_current.value - current).abs() <= 1e-4 * current);
        assert!(
            electrical.over_current.is_none(),
            "{current} A is within 12 A"
        );
        if let Some(tc) = crossing(t, &voltage, bus) {
            if expected.is_none_or(|(te, _)| tc < te) {
                expected = Some((tc, i));
            }
        }
    }
    let expected = expected.expect("the bus voltage is exceeded");
    let (time, leg) = feasibility.first_over_voltage().expect("over voltage");
    assert_eq!(leg, expected.1);
    // Located on the motion itself, against the linear interpolation of the 10 kHz samples.
    assert!((time - expected.0).abs() <= 1e-5, "{time} vs {expected:?}");
    assert!(!feasibility.feasible());
    assert!(feasibility.first_over_current().is_none());
    assert!(
        result
            .warnings
            .iter()
            .any(|w| w.starts_with("infeasible motion: voltage:") && w.contains("100 V")),
        "{:?}",
        result.warnings
    );
}
