//! Messages name state components by link, mode and derivative, never by an internal index.
//!
//! The expected names follow the state layout documented on `SceneModel::modes` and
//! `SceneModel::link_range` (every link's modal coordinates, then their rates), written out by
//! hand for three links of three modes each.

use flexprr_scene::Scene;

const SCENE: &str = r#"
[links]
length = 0.2
modes = 3
material = { youngs_modulus = 7.3e10, density = 2770.0 }
section = { kind = "uniform", thickness = 0.002, height = 0.03 }

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 20.0
phi_deg = 45.0

[time]
start = 0.0
end = 0.01
output_step = 0.001

[output]
requests = ["modes"]
plots = false
"#;

#[test]
fn ked_components_are_named_by_link_mode_and_derivative() {
    let scene = Scene::from_text("names.toml", "names", SCENE).expect("valid scene");
    let model = scene.build_model().expect("the model builds");
    let cases = [
        (0, "modal coordinate eta of link 1, mode 1"),
        (4, "modal coordinate eta of link 2, mode 2"),
        (8, "modal coordinate eta of link 3, mode 3"),
        (9, "modal rate d(eta)/dt of link 1, mode 1"),
        (14, "modal rate d(eta)/dt of link 2, mode 3"),
        (17, "modal rate d(eta)/dt of link 3, mode 3"),
        (18, "state component 18"),
    ];
    for (component, name) in cases {
        assert_eq!(
            model.component_name(component),
            name,
            "component {component}"
        );
    }
}

#[test]
fn coupled_components_of_the_links_are_named_too() {
    let text = format!("{SCENE}\n[model]\ncoupling = \"coupled\"\n");
    let scene = Scene::from_text("names.toml", "names", &text).expect("valid scene");
    let model = scene.build_model().expect("the model builds");
    assert_eq!(
        model.component_name(3),
        "modal coordinate eta of link 2, mode 1"
    );
    // No component is ever named by a bare index inside the elastic coordinates.
    for component in 0..2 * model.modes() {
        assert!(
            model.component_name(component).contains("of link"),
            "component {component}: {}",
            model.component_name(component)
        );
    }
}
