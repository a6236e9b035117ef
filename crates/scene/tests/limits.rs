//! Input limits of issue 13 and the registry: each case breaks one value of a valid scene
//! and checks the refusal names the key, its place and the rule (positions found by plain
//! text search, independent of the crate's locator).

use std::sync::Arc;

use flexprr_scene::{Registry, ScenarioError, Scene, read_input_file};

const BASE: &str = r#"name = "base"

[links]
length = 0.2
modes = 3
section = { kind = "uniform", thickness = 0.002, height = 0.03 }
basis = { kind = "sine" }

[trajectory]
kind = "circle"
frequency = 2.0

[integrator]
atol = 1e-12

[time]
end = 0.1
output_step = 0.01

[output]
requests = ["frequencies"]
plots = false
"#;

fn edit(old: &str, new: &str) -> String {
    assert_eq!(BASE.matches(old).count(), 1, "`{old}` must occur once");
    BASE.replacen(old, new, 1)
}

fn place(text: &str, needle: &str) -> String {
    let offset = text.find(needle).expect("needle in text");
    let line = text[..offset].matches('\n').count() + 1;
    let column = offset - text[..offset].rfind('\n').map_or(0, |i| i + 1) + 1;
    format!("scene.toml:{line}:{column}: ")
}

#[track_caller]
fn rejects(text: &str, at: &str, key: &str, phrases: &[&str]) {
    let err = Scene::from_text("scene.toml", "scene", text).expect_err("must be refused");
    let message = err.to_string();
    assert!(err.is_input(), "{message}");
    assert!(message.starts_with(&place(text, at)), "{message}");
    assert!(message.contains(&format!("{key}: ")), "{message}");
    for p in phrases {
        assert!(message.contains(p), "`{p}` missing from: {message}");
    }
    assert!(!message.contains('\n'), "{message}");
}

#[test]
fn the_base_scene_is_valid() {
    let scene = Scene::from_text("scene.toml", "scene", BASE).unwrap();
    // No method named: the default `auto` chooses `magnus6` for the KED model.
    assert_eq!(scene.method.name(), "magnus6");
    assert!(scene.stop_times.is_empty());
}

#[test]
fn a_key_of_another_basis_is_refused_where_it_is() {
    let text = edit(
        "basis = { kind = \"sine\" }",
        "basis = { kind = \"sine\", ends = \"clamped-free\" }",
    );
    rejects(&text, "ends", "links.basis.ends", &["unknown field `ends`"]);
}

#[test]
fn zero_atol_is_refused_with_the_reason() {
    let text = edit("atol = 1e-12\n", "atol = 0.0\n");
    rejects(
        &text,
        "atol",
        "integrator.atol",
        &["purely relative tolerance cannot be met"],
    );
}

#[test]
fn rtol_of_one_is_refused() {
    let text = edit("atol = 1e-12\n", "atol = 1e-12\nrtol = 1.0\n");
    rejects(&text, "rtol", "integrator.rtol", &["below 1", "got 1.0"]);
}

#[test]
fn output_step_longer_than_the_span_is_refused() {
    let text = edit("output_step = 0.01\n", "output_step = 0.5\n");
    rejects(
        &text,
        "output_step",
        "time.output_step",
        &["longer than the time span 0.1 s"],
    );
}

#[test]
fn a_thick_link_is_refused_with_the_slenderness_rule() {
    // 0.2 m / 817 m: not a beam; 0.2 m / 0.03 m = 6.7 < 10: too stubby for Euler-Bernoulli.
    for (thickness, ratio) in [("817.0", "0.000"), ("0.03", "6.667")] {
        let text = edit("thickness = 0.002", &format!("thickness = {thickness}"));
        rejects(
            &text,
            "thickness",
            "links.section.thickness",
            &["length / thickness", ratio, "below 10"],
        );
    }
}

#[test]
fn unsafe_names_are_refused() {
    // As written in TOML (\u0007 is a control character).
    for name in [
        r#""../../x""#,
        r#""""#,
        r#""/abs""#,
        r#"".hidden""#,
        r#""a\u0007b""#,
        r#""a b""#,
    ] {
        let text = edit("name = \"base\"", &format!("name = {name}"));
        rejects(&text, "name", "name", &["must be 1 to 100 characters"]);
    }
    let long = "n".repeat(101);
    let text = edit("name = \"base\"", &format!("name = \"{long}\""));
    rejects(&text, "name", "name", &["101 characters"]);
}

#[test]
fn a_file_stem_is_made_safe() {
    let text = BASE.replacen("name = \"base\"\n", "", 1);
    let scene = Scene::from_text("x.toml", ".my scene", &text).unwrap();
    assert_eq!(scene.name, "my_scene");
}

#[test]
fn stop_times_are_sorted_and_checked() {
    let text = edit("end = 0.1\n", "end = 0.1\nstops = [0.05, 0.02, 0.05]\n");
    let scene = Scene::from_text("scene.toml", "scene", &text).unwrap();
    assert_eq!(scene.stop_times.len(), 2);
    assert!((scene.stop_times[0] - 0.02).abs() < 1e-15);
    assert!((scene.stop_times[1] - 0.05).abs() < 1e-15);
    let text = edit("end = 0.1\n", "end = 0.1\nstops = [0.05, 0.2]\n");
    rejects(&text, "0.2]", "time.stops.1", &["outside the time span"]);
}

#[test]
fn a_deeply_nested_key_names_the_file() {
    let deep = vec!["a"; 400].join(".");
    let text = format!("{deep} = 1\n{BASE}");
    let err = Scene::from_text("scene.toml", "scene", &text).expect_err("refused");
    let message = err.to_string();
    assert!(message.starts_with("scene.toml"), "{message}");
    assert!(!message.starts_with(": "), "{message}");
}

#[test]
fn a_bad_section_kind_is_described_without_rust_names() {
    let text = edit("kind = \"uniform\"", "kind = \"round\"");
    let message = Scene::from_text("scene.toml", "scene", &text)
        .expect_err("refused")
        .to_string();
    assert!(message.contains("round"), "{message}");
    assert!(!message.contains("SectionConfig"), "{message}");
    assert!(!message.contains("internally tagged"), "{message}");
}

#[test]
fn a_missing_section_kind_is_described_without_rust_names() {
    let text = edit("kind = \"uniform\", ", "");
    let message = Scene::from_text("scene.toml", "scene", &text)
        .expect_err("refused")
        .to_string();
    assert!(!message.contains("SectionConfig"), "{message}");
    assert!(!message.contains("internally tagged"), "{message}");
}

#[cfg(unix)]
#[test]
fn a_device_is_refused_before_reading() {
    let err = read_input_file(std::path::Path::new("/dev/zero")).expect_err("refused");
    assert!(err.to_string().contains("not a regular file"), "{err}");
    let err = Scene::load(std::path::Path::new("/dev/zero")).expect_err("refused");
    assert!(matches!(err, ScenarioError::Input { .. }), "{err}");
}

#[test]
fn an_oversized_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.toml");
    let filler = format!("{BASE}\n{}", "# padding\n".repeat(500_000));
    std::fs::write(&path, filler).unwrap();
    let err = Scene::load(&path).expect_err("refused");
    assert!(err.to_string().contains("MiB"), "{err}");
}

#[test]
fn the_registry_resolves_names_and_reports_the_known_ones() {
    let registry = Registry::default();
    assert_eq!(
        registry.integrator_names(),
        [
            "abm",
            "auto",
            "bdf",
            "generalized_alpha",
            "magnus4",
            "magnus6",
            "rk45"
        ]
    );
    assert_eq!(registry.basis_names(), ["classical", "hermite", "sine"]);
    assert_eq!(
        registry.axial_force_names(),
        ["joint-reaction", "none", "paper"]
    );
    // A registered integrator name is accepted; an empty registry knows none.
    let mut custom = Registry::default();
    custom.register_integrator(
        "rk45-again",
        Arc::new(|o| Box::new(flexprr_integrators::Rk45::new(o))),
    );
    let text = edit("atol = 1e-12\n", "atol = 1e-12\nmethod = \"rk45-again\"\n");
    let scene = Scene::from_text_with(&custom, "scene.toml", "scene", &text).unwrap();
    assert_eq!(scene.method.name(), "rk45-again");
    assert_eq!(
        scene.method.integrator(scene.options.clone()).name(),
        "rk45"
    );
    let err = Scene::from_text("scene.toml", "scene", &text).expect_err("unknown by default");
    assert!(
        err.to_string().contains(
            "\"abm\", \"auto\", \"bdf\", \"generalized_alpha\", \"magnus4\", \"magnus6\", \"rk45\""
        ),
        "{err}"
    );
}

#[test]
fn a_registered_axial_force_model_is_used() {
    let mut registry = Registry::default();
    registry.register_axial_force("zero", Arc::new(flexprr_dynamics::NoAxialForce));
    let text = edit(
        "[integrator]",
        "[model]\naxial_force = \"zero\"\n\n[integrator]",
    );
    let scene = Scene::from_text_with(&registry, "scene.toml", "scene", &text).unwrap();
    assert_eq!(scene.axial_model.name(), "none");
    let err = Scene::from_text("scene.toml", "scene", &text).expect_err("unknown by default");
    assert!(
        err.to_string().contains("unknown axial force model"),
        "{err}"
    );
}
