//! Properties of the scene layer over generated scenes: any valid scene, written back as
//! TOML (the echo a planned scene or a study case is made of), loads to the same scene; and a
//! value out of its range is refused at its key and line whatever the rest of the scene is.

use flexprr_scene::Scene;
use proptest::prelude::*;

/// A scene of the paper's machine with the generated values, one key per line.
fn text(
    frequency: f64,
    radius: f64,
    platform_mass: f64,
    thickness: f64,
    modes: usize,
    coupling: &str,
) -> String {
    format!(
        r#"name = "generated"
[machine]
platform_mass = {platform_mass:?}
[links]
modes = {modes}
section = {{ kind = "uniform", thickness = {thickness:?}, height = 0.03 }}
[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = {radius:?}
frequency = {frequency:?}
phi_deg = 45.0
[model]
coupling = "{coupling}"
[time]
end = 0.01
output_step = 1e-3
[output]
requests = ["deflections"]
"#
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn a_valid_scene_written_back_loads_to_the_same_scene(
        frequency in 0.1f64..30.0,
        radius in 0.005f64..0.06,
        platform_mass in 0.05f64..2.0,
        thickness in 1e-3f64..5e-3,
        modes in 1usize..6,
        coupled in any::<bool>(),
    ) {
        let coupling = if coupled { "coupled" } else { "ked" };
        let scene = Scene::from_text(
            "a.toml",
            "a",
            &text(frequency, radius, platform_mass, thickness, modes, coupling),
        )
        .unwrap();
        let echoed = toml::to_string(&scene.file).unwrap();
        let again = Scene::from_text("b.toml", "b", &echoed).unwrap();
        prop_assert_eq!(&again.file, &scene.file);
        prop_assert_eq!(&again.output_times, &scene.output_times);
        prop_assert_eq!(again.coupling.name(), scene.coupling.name());
        prop_assert_eq!(again.model_description(), scene.model_description());
    }

    #[test]
    fn a_thickness_out_of_range_is_refused_at_its_key_and_line(
        frequency in 0.1f64..30.0,
        thickness in -1.0f64..0.0,
        coupled in any::<bool>(),
    ) {
        let coupling = if coupled { "coupled" } else { "ked" };
        let text = text(frequency, 0.05, 0.2, thickness, 3, coupling);
        let error = Scene::from_text("bad.toml", "bad", &text).unwrap_err().to_string();
        let line = text.lines().position(|l| l.starts_with("section")).unwrap() + 1;
        prop_assert!(error.contains("links.section"), "{}", error);
        prop_assert!(error.contains(&format!("bad.toml:{line}:")), "{}", error);
        prop_assert!(!error.contains('\n'), "{}", error);
    }
}
