//! `model.coupling = "nonlinear"`: a scene selects the co-rotational link model, which gives
//! deflections (anywhere along the link), platform deviation, forces and energies, agrees
//! with the coupled model where both are valid (small deflection: a second method), and
//! refuses, at the key, what it cannot give.

use flexprr_run::run;
use flexprr_scene::Scene;

fn scene_text(coupling: &str, model_extra: &str, requests: &str) -> String {
    format!(
        r#"
[trajectory]
kind = "circle"
frequency = 20.0
[model]
formulation = "consistent"
coupling = "{coupling}"
{model_extra}
[integrator]
rtol = 1e-8
atol = 1e-12
[time]
end = 0.03
output_step = 2.5e-4
[output]
requests = {requests}
deflection_xi = [0.5, 0.3]
plots = false
"#
    )
}

fn relative_l2(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den).sqrt()
}

#[test]
fn a_nonlinear_scene_runs_the_nonlinear_model_and_agrees_with_the_coupled_one() {
    let requests = r#"["deflections", "energies", "axial_forces"]"#;
    let nonlinear = Scene::from_text(
        "nl.toml",
        "nl",
        &scene_text("nonlinear", "elements = 16", requests),
    )
    .unwrap();
    let coupled = Scene::from_text("co.toml", "co", &scene_text("coupled", "", requests)).unwrap();
    let nl = run(&nonlinear, &mut |_| {}).unwrap();
    let co = run(&coupled, &mut |_| {}).unwrap();
    for name in [
        "deflections",
        "platform_deviation",
        "nonlinear_forces",
        "energies",
    ] {
        assert!(nl.table(name).is_some(), "{name}");
    }
    assert!(nl.warnings.is_empty() && co.warnings.is_empty());
    // Deflections at a node (xi = 0.5) and between nodes (xi = 0.3, inside element 5 of 16)
    // against the coupled model: at 20 Hz both are within 1.3-1.6 % of the external ANCF
    // model over 0.2 s (docs/coupled.md), so within ~3 % of each other; the window here is
    // the start-up (largest relative differences: the impulsive start), bound 5 %.
    let (dn, dc) = (
        nl.table("deflections").unwrap(),
        co.table("deflections").unwrap(),
    );
    for xi in ["0.5", "0.3"] {
        for link in 1..=3 {
            let name = format!("w_{link}_xi{xi}_m");
            let e = relative_l2(dn.column(&name).unwrap(), dc.column(&name).unwrap());
            println!("{name}: {:.2} %", 100.0 * e);
            assert!(e < 0.05, "{name}: {e}");
        }
    }
    // The platform rotation against the coupled model's with the quasi-static axial stretch
    // (the nonlinear links are axially elastic): at 20 Hz the coupled one is 1.2 % from the
    // external model (docs/coupled.md); bound 5 % over the start-up.
    let (pn, pc) = (
        nl.table("platform_deviation").unwrap(),
        co.table("platform_deviation").unwrap(),
    );
    let e = relative_l2(
        pn.column("dphi_rad").unwrap(),
        pc.column("dphi_with_stretch_rad").unwrap(),
    );
    println!("dphi: {:.2} %", 100.0 * e);
    assert!(e < 0.05, "{e}");
    // Energies are positive and the strain energy is the links' bending + stretch.
    let energies = nl.table("energies").unwrap();
    assert!(
        energies
            .column("kinetic_J")
            .unwrap()
            .iter()
            .all(|v| *v > 0.0)
    );
    for link in 1..=3 {
        let strain = energies.column(&format!("strain_{link}_J")).unwrap();
        assert!(strain.iter().all(|v| *v >= 0.0));
    }
    // The run's largest deflection is taken over the guard's points (0.1, ..., 0.9) at the
    // output times: at least the largest of the table's (xi = 0.3 and 0.5, two of them),
    // and within a few per cent of it (the first mode dominates: sin(0.4 pi) = 0.95).
    let peak = ["0.3", "0.5"]
        .iter()
        .flat_map(|xi| (1..=3).map(move |i| format!("w_{i}_xi{xi}_m")))
        .flat_map(|name| dn.column(&name).unwrap().to_vec())
        .fold(0.0_f64, |m, w| m.max(w.abs()));
    let reported = nl.stats.max_deflection_m.unwrap();
    assert!(
        reported >= peak * (1.0 - 1e-12) && reported <= 1.1 * peak,
        "{reported} {peak}"
    );
}

#[test]
fn what_the_nonlinear_model_cannot_give_is_refused_at_its_key() {
    let cases = [
        (
            scene_text("nonlinear", "", r#"["deflections", "modes"]"#),
            "output.requests.1",
            "modal output",
        ),
        (
            scene_text("coupled", "elements = 16", r#"["deflections"]"#),
            "model.elements",
            "nonlinear model",
        ),
        (
            scene_text("nonlinear", "elements = 15", r#"["deflections"]"#),
            "model.elements",
            "even",
        ),
        (
            scene_text("ked", "collapse_deflection = 0.2", r#"["deflections"]"#),
            "model.collapse_deflection",
            "cannot collapse",
        ),
        (
            scene_text("nonlinear", "damping = [0.01]", r#"["deflections"]"#),
            "model.damping",
            "no modes",
        ),
        (
            scene_text("nonlinear", "", r#"["deflections"]"#).replace(
                "[model]",
                "[links.section]\nkind = \"tapered\"\nthickness_start = 0.003\nthickness_end = 0.002\nheight = 0.03\n[model]",
            ),
            "links.section",
            "uniform links",
        ),
    ];
    for (text, key, words) in cases {
        let message = Scene::from_text("bad.toml", "bad", &text)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("bad.toml:") && message.contains(key) && message.contains(words),
            "{key}: {message}"
        );
    }
}
