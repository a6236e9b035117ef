//! The mass and bending stiffness a patch adds to its links (`added_mass`,
//! `added_bending_stiffness` of `[[links.patches]]`), against closed forms of the modal
//! integrals of a sine basis on a uniform link.

use std::f64::consts::PI;
use std::path::Path;

use flexprr_scene::Scene;

fn shipped() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/piezo_f20.toml");
    std::fs::read_to_string(path).unwrap()
}

/// The shipped piezo scene with its patch on `links` over `[a, b]` adding `extra`.
fn scene(links: &str, a: f64, b: f64, extra: &str) -> Result<Scene, String> {
    let text = shipped()
        .replacen(
            "[[links.patches]]",
            &format!("[[links.patches]]\nlinks = {links}\n{extra}"),
            1,
        )
        .replacen("xi_start = 0.45", &format!("xi_start = {a}"), 1)
        .replacen("xi_end = 0.55", &format!("xi_end = {b}"), 1);
    Scene::from_text("piezo_layers.toml", "piezo_layers", &text).map_err(|e| e.to_string())
}

#[test]
fn a_patch_adds_its_mass_and_stiffness_to_the_links_it_is_on() {
    let bare = scene("[1]", 0.4, 0.6, "").unwrap();
    let (dm, dei) = (0.004, 0.05);
    let layered = scene(
        "[1]",
        0.4,
        0.6,
        &format!("added_mass = {dm}\nadded_bending_stiffness = {dei}"),
    )
    .unwrap();
    let l = bare.machine.links[0].length();
    let (m0, m1) = (
        &bare.machine.links[0].integrals,
        &layered.machine.links[0].integrals,
    );
    for j in 0..m0.r() {
        let n = (j + 1) as f64;
        // psi_j = sin(n pi xi): int psi^2 over the span, and int psi''^2 = (n pi)^4 int sin^2
        let span = {
            let f = |x: f64| x / 2.0 - (2.0 * n * PI * x).sin() / (4.0 * n * PI);
            f(0.6) - f(0.4)
        };
        let mass = dm / (0.2 * l) * l * span;
        let stiffness = dei / l.powi(3) * (n * PI).powi(4) * span;
        let dmass = m1.mass[(j, j)] - m0.mass[(j, j)];
        let dstiff = m1.stiffness[(j, j)] - m0.stiffness[(j, j)];
        assert!(
            (dmass - mass).abs() < 1e-10 * mass,
            "mode {n}: {dmass} against {mass}"
        );
        assert!(
            (dstiff - stiffness).abs() < 1e-10 * stiffness,
            "mode {n}: {dstiff} against {stiffness}"
        );
    }
    assert!((m1.total_mass - m0.total_mass - dm).abs() < 1e-12);
    // Links 2 and 3 carry no patch mass.
    for i in 1..3 {
        assert_eq!(
            bare.machine.links[i].integrals.mass,
            layered.machine.links[i].integrals.mass
        );
    }
}

/// A layer over the whole link that doubles `rhoA` and `EI` leaves every frequency as it
/// was (`omega^2 = EI (n pi)^4 / (rhoA l^4)`); doubling `EI` alone raises them by `sqrt 2`.
#[test]
fn a_whole_link_layer_scales_the_frequencies_as_the_uniform_beam() {
    let bare = scene("[2]", 0.0, 1.0, "").unwrap();
    let link = &bare.machine.links[1].integrals;
    let (m, ei) = (link.total_mass, {
        // EI from the first modal stiffness of the sine basis: K_11 = EI pi^4 / (2 l^3)
        let l = bare.machine.links[1].length();
        link.stiffness[(0, 0)] * 2.0 * l.powi(3) / PI.powi(4)
    });
    let frequencies = |s: &Scene| -> Vec<f64> {
        let g = &s.machine.links[1].integrals;
        (0..g.r())
            .map(|j| (g.stiffness[(j, j)] / g.mass[(j, j)]).sqrt())
            .collect()
    };
    let both = scene(
        "[2]",
        0.0,
        1.0,
        &format!("added_mass = {m}\nadded_bending_stiffness = {ei}"),
    )
    .unwrap();
    let stiff = scene("[2]", 0.0, 1.0, &format!("added_bending_stiffness = {ei}")).unwrap();
    for ((f0, f1), f2) in frequencies(&bare)
        .iter()
        .zip(frequencies(&both))
        .zip(frequencies(&stiff))
    {
        assert!((f1 / f0 - 1.0).abs() < 1e-10, "{f1} {f0}");
        assert!((f2 / f0 - 2f64.sqrt()).abs() < 1e-10, "{f2} {f0}");
    }
}

#[test]
fn added_mass_is_refused_where_it_cannot_be_modelled_or_is_negative() {
    let e = scene("[1]", 0.4, 0.6, "added_mass = -0.001").unwrap_err();
    assert!(e.contains("links.patches.0.added_mass"), "{e}");
    let text = shipped()
        .replacen(
            "[[links.patches]]",
            "[[links.patches]]\nadded_mass = 0.003",
            1,
        )
        .replacen(
            "[model]",
            "[model]\ncoupling = \"nonlinear\"\nelements = 8",
            1,
        );
    if let Err(e) = Scene::from_text("n.toml", "n", &text) {
        let e = e.to_string();
        assert!(
            e.contains("links.patches.0.added_mass") && e.contains("nonlinear"),
            "the refusal names the key and the model: {e}"
        );
    } else {
        panic!("the nonlinear model cannot carry patch mass");
    }
}
