//! The outputs as plug-ins: the run's list of files comes from the producers and covers
//! every file a run writes; a program's own output is declared to the scene layer, selected
//! from a scene, produced, written and asked for its quantity; a scene that requests an
//! output the run has no producer for fails with a typed error instead of leaving it out.

use std::path::Path;
use std::sync::Arc;

use flexprr_run::producer::{Needs, StudyQuantity};
use flexprr_run::{
    OutputContext, OutputProducer, OutputRegistry, RUN_PRODUCTS, RunError, RunResult, Table,
    run_registered, write_outputs,
};
use flexprr_scene::{Registry, Scene};

fn config(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../configs/{name}"));
    std::fs::read_to_string(path).expect("a shipped scene")
}

/// Every output of the servo scene with a motor (control, viewer and figures included) over
/// a short span.
fn servo_all() -> String {
    config("servo_motor_f20.toml")
        .replace("end = 0.2", "end = 0.02")
        .replace(
            r#"requests = ["kinematics", "driving_forces", "actuators", "deflections"]"#,
            r#"requests = ["kinematics", "driving_forces", "joint_reactions", "axial_forces",
"frequencies", "deflections", "energies", "viewer", "snapshots", "machine", "tracking",
"actuators", "machine_frequencies"]"#,
        )
}

#[test]
fn every_file_a_run_writes_is_a_product_of_its_producers() {
    let text = servo_all();
    assert!(
        text.contains("\"tracking\""),
        "the scene's requests were replaced"
    );
    let scene = Scene::from_text("servo.toml", "servo", &text).expect("scene");
    let result = flexprr_run::run(&scene, &mut |_| {}).expect("run");
    let dir = tempfile::tempdir().expect("tempdir");
    let written = write_outputs(&scene, &result, dir.path()).expect("writes");
    let names: Vec<String> = written
        .iter()
        .map(|p| {
            Path::new(p)
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    for name in [
        "tracking.csv",
        "tracking.svg",
        "actuators.csv",
        "actuators.svg",
    ] {
        assert!(
            names.iter().any(|n| n == name),
            "{name} not written: {names:?}"
        );
    }
    for name in &names {
        assert!(
            RUN_PRODUCTS.is_product(name),
            "{name} is not in RUN_PRODUCTS"
        );
    }
    // The list is the producers' files, nothing else: each built-in producer's files are in
    // it, and it holds no name that no producer declares.
    let outputs = OutputRegistry::built_in();
    for p in outputs.producers() {
        for f in p.files() {
            assert!(RUN_PRODUCTS.names.contains(f), "{f} of {}", p.name());
        }
    }
    for f in RUN_PRODUCTS.names.iter() {
        let declared = outputs.producers().iter().any(|p| p.files().contains(f));
        assert!(
            declared || *f == "summary.json",
            "{f} declared by no producer"
        );
    }
}

/// The number of output times: `samples.csv`, one column.
#[derive(Debug)]
struct Samples;

impl OutputProducer for Samples {
    fn name(&self) -> &'static str {
        "sample_count"
    }
    fn needs(&self) -> Needs {
        Needs {
            samples: true,
            ..Needs::default()
        }
    }
    fn files(&self) -> &'static [&'static str] {
        &["sample_count.csv"]
    }
    fn quantities(&self) -> &'static [StudyQuantity] {
        &[StudyQuantity {
            name: "samples",
            unit: "",
            label: "output samples",
        }]
    }
    fn produce(&self, ctx: &mut OutputContext<'_>, result: &mut RunResult) -> Result<(), RunError> {
        let mut table = Table::new("sample_count", ctx.times());
        let phi = ctx.motions().iter().map(|m| m.pose.phi).collect();
        table.push(
            flexprr_run::Column::of(flexprr_run::Quantity::PlatformPhi),
            phi,
        );
        result.tables.push(table);
        Ok(())
    }
    fn quantity(&self, result: &RunResult, name: &str) -> Option<Result<f64, String>> {
        let t = result.table("sample_count")?;
        (name == "samples").then(|| Ok(t.rows() as f64))
    }
}

#[test]
fn a_registered_output_is_selected_written_and_asked_for_its_quantity() {
    let mut scenes = Registry::default();
    let mut outputs = OutputRegistry::built_in();
    outputs.register(&mut scenes, Arc::new(Samples));
    assert!(outputs.products().is_product("sample_count.csv"));
    assert!(!RUN_PRODUCTS.is_product("sample_count.csv"));

    let text =
        config("paper_f20.toml").replace("[output]", "[output]\ncustom = [\"sample_count\"]");
    let scene = Scene::from_text_with(&scenes, "paper.toml", "paper", &text).expect("scene");
    let result = run_registered(&scene, &outputs, &mut |_| {}).expect("run");
    let n = scene.output_times.len() as f64;
    assert_eq!(result.quantity("samples").map(|r| r.ok()), Some(Some(n)));
    assert!(result.quantity("nothing").is_none());
    let dir = tempfile::tempdir().expect("tempdir");
    write_outputs(&scene, &result, dir.path()).expect("writes");
    let csv = std::fs::read_to_string(dir.path().join("sample_count.csv")).expect("file");
    assert_eq!(csv.lines().next(), Some("t_s,phi_rad"));
    assert_eq!(csv.lines().count(), scene.output_times.len() + 1);

    // The run without its producer says so, with the output's name and a kind of its own.
    let failure = flexprr_run::run(&scene, &mut |_| {}).expect_err("no producer");
    assert_eq!(failure.error.kind(), "output");
    assert!(
        failure.error.to_string().contains("sample_count"),
        "{}",
        failure.error
    );

    // The scene layer refuses an undeclared name, a built-in one and a repeated one, at
    // their place.
    for (custom, needle) in [
        (
            "[\"sample_cnt\"]",
            "unknown output \"sample_cnt\": expected one of \"sample_count\"",
        ),
        ("[\"kinematics\"]", "is a built-in output"),
        ("[\"sample_count\", \"sample_count\"]", "requested twice"),
    ] {
        let text =
            config("paper_f20.toml").replace("[output]", &format!("[output]\ncustom = {custom}"));
        let e = Scene::from_text_with(&scenes, "paper.toml", "paper", &text).expect_err(custom);
        assert!(e.to_string().contains("output.custom."), "{e}");
        assert!(e.to_string().contains(needle), "{e}");
    }
}
