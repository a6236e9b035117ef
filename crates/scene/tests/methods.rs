//! The integrator `method` key: the exponential methods are refused, with a located error, on
//! models that are not linear in the state, and `auto` becomes the method it chooses for the
//! scene's model, so that runs and summaries name the method actually used.

use flexprr_scene::{MethodKind, Registry, ScenarioError, Scene};

fn scene(coupling: &str, method: &str) -> Result<Scene, ScenarioError> {
    Scene::from_text("m.toml", "m", &scene_text(coupling, method))
}

fn scene_text(coupling: &str, method: &str) -> String {
    format!(
        r#"name = "m"
[links]
modes = 3
[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 20.0
phi_deg = 45.0
[model]
formulation = "consistent"
coupling = "{coupling}"
[integrator]
method = "{method}"
[time]
end = 0.01
"#
    )
}

/// A scene that names no method runs `auto`'s choice for its model: `magnus6` on the KED
/// model, `abm` on the coupled one (whose right-hand side is nonlinear in the state); the
/// echo of the file keeps `auto`.
#[test]
fn a_scene_without_a_method_runs_auto() {
    for (coupling, chosen) in [("ked", "magnus6"), ("coupled", "abm")] {
        let text = scene_text(coupling, "none");
        let without = text.replace("method = \"none\"\n", "");
        assert_ne!(text, without, "the method line is removed");
        let s = Scene::from_text("m.toml", "m", &without).expect("valid");
        assert_eq!(s.method.name(), chosen, "{coupling}");
        assert_eq!(s.file.integrator.method, "auto", "{coupling}");
    }
}

#[test]
fn exponential_methods_run_ked_scenes() {
    for method in ["magnus4", "magnus6"] {
        let s = scene("ked", method).expect("a KED scene takes the exponential methods");
        assert_eq!(s.method.name(), method);
    }
}

#[test]
fn exponential_methods_refuse_the_coupled_model_at_the_method_key() {
    for method in ["magnus4", "magnus6"] {
        let err = scene("coupled", method).expect_err("the coupled model is nonlinear");
        let ScenarioError::Input {
            location,
            key,
            message,
        } = &err
        else {
            panic!("expected bad input, got {err}");
        };
        assert_eq!(key, "integrator.method");
        let location = location.as_ref().expect("located");
        // `method = "..."` is line 14 of the scene text.
        assert_eq!(location.line, 14, "{err}");
        assert_eq!(
            message,
            &format!(
                "method {method} needs a linear (KED) model; this scene is coupled: use abm or auto"
            )
        );
    }
}

#[test]
fn auto_resolves_to_the_exponential_method_for_ked_and_abm_for_coupled() {
    assert_eq!(scene("ked", "auto").expect("ked").method.name(), "magnus6");
    assert_eq!(
        scene("coupled", "auto").expect("coupled").method.name(),
        "abm"
    );
    // The general methods are kept as given on both models.
    for method in ["abm", "rk45", "bdf"] {
        for coupling in ["ked", "coupled"] {
            assert_eq!(
                scene(coupling, method).expect("valid").method.name(),
                method
            );
        }
    }
}

#[test]
fn the_registry_lists_the_new_methods_with_their_kinds() {
    let r = Registry::default();
    assert_eq!(
        r.integrator_names(),
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
    assert_eq!(r.method_kind("magnus4"), Some(&MethodKind::Linear));
    assert_eq!(r.method_kind("abm"), Some(&MethodKind::General));
    assert!(matches!(
        r.method_kind("auto"),
        Some(MethodKind::Auto { linear, general, mechanical })
            if linear == "magnus6" && general == "abm"
                && mechanical.as_deref() == Some("generalized_alpha")
    ));
    assert_eq!(
        r.method_kind("generalized_alpha"),
        Some(&MethodKind::Mechanical)
    );
    // auto: magnus6 for KED, generalized_alpha for a mechanical (nonlinear) model, abm else.
    let chosen = |linear, mechanical| {
        r.resolve_method_for("auto", linear, mechanical, "m")
            .unwrap()
            .name()
            .to_string()
    };
    assert_eq!(chosen(true, false), "magnus6");
    assert_eq!(chosen(false, true), "generalized_alpha");
    assert_eq!(chosen(false, false), "abm");
    let err = r
        .resolve_method_for("generalized_alpha", false, false, "coupled")
        .expect_err("refused");
    assert!(
        err.contains("needs a mechanical model") && err.contains("use abm"),
        "{err}"
    );
    let err = r.resolve_method("nope", true, "ked").expect_err("unknown");
    assert!(err.contains("unknown value \"nope\""), "{err}");
}
