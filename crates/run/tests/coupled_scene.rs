//! A scene with `coupling = "coupled"` runs the coupled model and agrees with the external
//! Exudyn model of `validation/` (independent data), while the KED twin does not.

use flexprr_run::run;
use flexprr_scene::Scene;

fn scene(coupling: &str) -> Scene {
    let text = format!(
        r#"
[trajectory]
kind = "circle"
frequency = 20.0
[model]
formulation = "consistent"
coupling = "{coupling}"
[integrator]
rtol = 1e-9
atol = 1e-13
[time]
end = 0.1
output_step = 2.5e-4
[output]
requests = ["deflections", "axial_forces"]
plots = false
"#
    );
    Scene::from_text("coupled.toml", "coupled", &text).unwrap()
}

/// Mid-point deflections of the three links from the external coupled model at 20 Hz.
fn external() -> Vec<[f64; 4]> {
    let text = include_str!("../../../validation/data/coupled_f20.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| h.trim() == name).unwrap();
    let (t, w1, w2, w3) = (
        col("t_s"),
        col("w_mid_1_m"),
        col("w_mid_2_m"),
        col("w_mid_3_m"),
    );
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
            [v[t], v[w1], v[w2], v[w3]]
        })
        .collect()
}

fn relative_l2(scene: &Scene) -> f64 {
    let result = run(scene, &mut |_| {}).unwrap();
    let table = result.table("deflections").unwrap();
    let (mut num, mut den) = (0.0, 0.0);
    for row in external().iter().filter(|r| r[0] <= 0.1 + 1e-12) {
        let k = (row[0] / 2.5e-4).round() as usize;
        for (i, external) in row.iter().enumerate().skip(1) {
            let ours = table.column(&format!("w_{i}_xi0.5_m")).unwrap()[k];
            num += (ours - external).powi(2);
            den += external.powi(2);
        }
    }
    (num / den).sqrt()
}

#[test]
fn coupled_scene_matches_the_external_model_and_ked_does_not() {
    let coupled = scene("coupled");
    let e_coupled = relative_l2(&coupled);
    let e_ked = relative_l2(&scene("ked"));
    println!("relative L2 vs Exudyn over 0-0.1 s: coupled {e_coupled:.4}, KED {e_ked:.4}");
    assert!(e_coupled < 0.05, "coupled {e_coupled}");
    assert!(
        e_ked > 4.0 * e_coupled,
        "KED {e_ked} vs coupled {e_coupled}"
    );
    let result = run(&coupled, &mut |_| {}).unwrap();
    assert!(result.table("platform_deviation").is_some());
    assert!(result.table("coupled_forces").is_some());
}

#[test]
fn coupled_requires_the_consistent_formulation() {
    let text = "[trajectory]\nkind = \"circle\"\nfrequency = 10.0\n[model]\nformulation = \"paper\"\ncoupling = \"coupled\"\n[time]\nend = 0.1\n";
    let err = Scene::from_text("bad.toml", "bad", text)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bad.toml:6:1")
            && err.contains("model.coupling")
            && err.contains("consistent"),
        "{err}"
    );
}
