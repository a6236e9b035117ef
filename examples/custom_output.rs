//! Registers a new output from outside the crates, selects it from a scene, writes its CSV
//! file with the run's other outputs, and reaches its quantity from a study by name.
//!
//! The output, `slider_power`, is the power each slider's drive delivers along the commanded
//! rigid motion, `P_i = F_ai rho_i'` (the rigid driving force times the slider speed), in
//! `slider_power.csv`; it offers studies the quantity `slider_power_peak_W`, the largest
//! `|P_i|` over the sliders and the output times. Two independent checks:
//!
//! * power balance: the rigid joint reactions do no work on the machine as a whole, so the
//!   work of the three drives equals the change of the rigid kinetic energy,
//!   `int sum_i P_i dt = T(t_end) - T(0)` (T from the dynamics layer's
//!   `rigid_kinetic_energy` at the inverse kinematics of the end poses; the integral by the
//!   trapezoidal rule over the output times), over 0.6 of a revolution so that the energy
//!   changes;
//! * the study's `slider_power_peak_W` equals the peak of `F_ai rho_i'` computed here from the
//!   `driving_forces` and `kinematics` tables of the same case.
//!
//! Run: `cargo run --release --example custom_output`

use std::sync::Arc;

use flexprr_dynamics::{NamedQuantity, rigid_kinetic_energy};
use flexprr_run::producer::{Needs, StudyQuantity};
use flexprr_run::{
    Column, OutputContext, OutputProducer, OutputRegistry, Quantity, RunError, RunResult, Table,
};
use flexprr_scene::{Registry, Scene};
use flexprr_studies::{Plugins, Study};

/// Power delivered by a slider's drive (W): `P_slider_<i>_W`.
const SLIDER_POWER: Quantity = Quantity::Named(NamedQuantity::new("P_slider", "W", "P", "W"));

/// The `slider_power` output.
#[derive(Debug)]
struct SliderPower;

impl OutputProducer for SliderPower {
    fn name(&self) -> &'static str {
        "slider_power"
    }

    fn needs(&self) -> Needs {
        Needs {
            samples: true,
            ..Needs::default()
        }
    }

    fn files(&self) -> &'static [&'static str] {
        &["slider_power.csv"]
    }

    fn quantities(&self) -> &'static [StudyQuantity] {
        &[StudyQuantity {
            name: "slider_power_peak_W",
            unit: "W",
            label: "largest slider drive power",
        }]
    }

    fn produce(&self, ctx: &mut OutputContext<'_>, result: &mut RunResult) -> Result<(), RunError> {
        let speeds: [Vec<f64>; 3] =
            std::array::from_fn(|i| ctx.states().iter().map(|s| s.legs[i].rho_dot).collect());
        let t = ctx.times().to_vec();
        let reactions = ctx.reactions()?;
        let mut table = Table::new("slider_power", &t);
        for (i, speed) in speeds.iter().enumerate() {
            let power = reactions
                .iter()
                .zip(speed)
                .map(|(r, v)| r.driving_force[i] * v)
                .collect();
            table.push(Column::link(SLIDER_POWER, i), power);
        }
        result.tables.push(table);
        Ok(())
    }

    fn quantity(&self, result: &RunResult, name: &str) -> Option<Result<f64, String>> {
        if name != "slider_power_peak_W" {
            return None;
        }
        let Some(table) = result.table("slider_power") else {
            return Some(Err("the run has no slider_power table".into()));
        };
        let peak = table.data[1..]
            .iter()
            .flatten()
            .fold(0.0_f64, |m, p| m.max(p.abs()));
        Some(Ok(peak))
    }
}

const SCENE: &str = r#"name = "custom_output"

[links]
length = 0.2
modes = 3
material = { youngs_modulus = 7.3e10, density = 2770.0 }
section = { kind = "uniform", thickness = 0.002, height = 0.03 }
basis = { kind = "sine" }

[trajectory]
kind = "circle"
frequency = 20.0

[time]
end = 0.03
output_step = 0.0002

[output]
requests = ["kinematics", "driving_forces"]
custom = ["slider_power"]
plots = false
"#;

/// The column `header` of `table`.
fn column<'a>(table: &'a Table, header: &str) -> &'a [f64] {
    table
        .column(header)
        .unwrap_or_else(|| panic!("{} has no column {header}", table.name))
}

/// The rigid kinetic energy of `scene`'s machine on its commanded motion at `t` (J).
fn kinetic_energy(scene: &Scene, t: f64) -> f64 {
    let motion = scene.trajectory.motion(t);
    let state = scene
        .machine
        .geometry
        .inverse_kinematics(&motion)
        .unwrap_or_else(|e| panic!("pose at t = {t}: {e}"));
    rigid_kinetic_energy(&scene.machine, &state)
}

fn main() {
    let mut scenes = Registry::default();
    let mut outputs = OutputRegistry::built_in();
    outputs.register(&mut scenes, Arc::new(SliderPower));

    // The scene selects the output; the file is written beside the built-in ones.
    let scene = Scene::from_text_with(&scenes, "custom_output.toml", "custom_output", SCENE)
        .unwrap_or_else(|e| panic!("scene rejected: {e}"));
    let result = flexprr_run::run_registered(&scene, &outputs, &mut |_| {})
        .unwrap_or_else(|e| panic!("run: {}", e.error));
    let dir = tempfile::tempdir().expect("a temporary directory");
    let written = flexprr_run::write_outputs(&scene, &result, dir.path()).expect("writes");
    println!("{} files written", written.len());
    let text = std::fs::read_to_string(dir.path().join("slider_power.csv")).expect("the file");
    let header = text.lines().next().unwrap_or_default();
    println!("slider_power.csv: {header}");
    assert_eq!(header, "t_s,P_slider_1_W,P_slider_2_W,P_slider_3_W");
    assert_eq!(text.lines().count(), scene.output_times.len() + 1);

    // Without its producer the run refuses the scene; without the declaration, the scene
    // layer refuses the name at its place.
    let refused = flexprr_run::run(&scene, &mut |_| {}).expect_err("no producer");
    println!("run without the producer: {}", refused.error);
    assert_eq!(refused.error.kind(), "output");
    let unknown = Scene::from_text("custom_output.toml", "custom_output", SCENE)
        .expect_err("an undeclared output");
    println!("load without the declaration: {unknown}");
    assert!(unknown.to_string().contains("output.custom.0"), "{unknown}");

    // Power balance: the drives' work equals the change of the rigid kinetic energy.
    let table = result.table("slider_power").expect("the table");
    let t = table.time();
    let total: Vec<f64> = (0..t.len())
        .map(|k| {
            (1..=3)
                .map(|i| column(table, &format!("P_slider_{i}_W"))[k])
                .sum()
        })
        .collect();
    let trapezoid = |f: &dyn Fn(usize) -> f64| -> f64 {
        (1..t.len())
            .map(|k| 0.5 * (f(k) + f(k - 1)) * (t[k] - t[k - 1]))
            .sum()
    };
    let work = trapezoid(&|k| total[k]);
    let scale = trapezoid(&|k| total[k].abs());
    let delta_t = kinetic_energy(&scene, t[t.len() - 1]) - kinetic_energy(&scene, t[0]);
    println!("work of the drives {work:.6e} J, change of kinetic energy {delta_t:.6e} J");
    // 0.6 of a revolution: the end pose differs from the start, so the energy changes.
    assert!(
        delta_t.abs() > 1e-2 * scale,
        "the check needs a change of kinetic energy ({delta_t:e} J against {scale:e} J)"
    );
    assert!(
        (work - delta_t).abs() < 1e-3 * scale,
        "power balance: {work:e} J against {delta_t:e} J (scale {scale:e} J)"
    );

    // The quantity by name, from a study over two speeds.
    std::fs::write(dir.path().join("scene.toml"), SCENE).expect("writes the base scene");
    let study_text = "name = \"custom_output_study\"\nbase = \"scene.toml\"\n\
        quantities = [{ kind = \"output\", name = \"slider_power_peak_W\" }]\n\n\
        [[axis]]\nkey = \"trajectory.frequency\"\nvalues = [10.0, 20.0]\n";
    let plugins = Plugins {
        scenes,
        outputs,
        ..Plugins::default()
    };
    let study = Study::from_text_with(plugins, "study.toml", "study", study_text, dir.path())
        .unwrap_or_else(|e| panic!("study rejected: {e}"));
    for case in &study.cases {
        let (record, ran) = study.run_case(case);
        let (_, result) = ran.unwrap_or_else(|| panic!("case {}: {}", case.id, record.error));
        let forces = result.table("driving_forces").expect("driving forces");
        let kinematics = result.table("kinematics").expect("kinematics");
        let peak = (1..=3)
            .flat_map(|i| {
                let f = column(forces, &format!("F_a_{i}_rigid_N"));
                let v = column(kinematics, &format!("rho_dot_{i}_m_s"));
                f.iter()
                    .zip(v)
                    .map(|(f, v)| (f * v).abs())
                    .collect::<Vec<_>>()
            })
            .fold(0.0_f64, f64::max);
        let value: f64 = record.quantities[0].parse().expect("a number");
        println!(
            "case {} ({}): slider_power_peak_W = {value:.6e}, from the tables {peak:.6e}",
            case.id, record.parameters[0]
        );
        assert!(
            (value - peak).abs() <= 1e-9 * peak,
            "{value} against {peak}"
        );
    }
    println!("ok");
}
