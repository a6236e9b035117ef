//! The `viewer`, `snapshots` and `machine` outputs carry the run's real results: slider
//! positions from the closed-form inverse kinematics, the sine basis, modal coordinates
//! that reproduce the run's deflections, first-mode frequencies that follow the axial
//! force by the closed form, buckling intervals, the coupled platform deviation, and a
//! viewer of the computed part of a failed run.

use std::f64::consts::PI;
use std::path::Path;

use flexprr_kinematics::{Circle, Geometry, Trajectory};
use flexprr_run::run;
use flexprr_scene::Scene;

/// A shipped config with its time span shortened to `end` and extra outputs requested.
fn scene(config: &str, end: f64, extra: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs")
        .join(config);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with("end = ") {
            out.push_str(&format!("end = {end}\n"));
        } else if let Some(rest) = line.strip_prefix("requests = [") {
            out.push_str(&format!("requests = [{extra}{rest}\n"));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    Scene::from_text(config, config.trim_end_matches(".toml"), &out).unwrap()
}

fn names(documents: &[(String, String)]) -> Vec<&str> {
    documents.iter().map(|(n, _)| n.as_str()).collect()
}

/// The paper scene: every frame against independent closed forms and the run's tables.
#[test]
fn paper_viewer_data_is_the_run() {
    let scene = scene("paper_f20.toml", 0.05, "");
    let result = run(&scene, &mut |_| {}).unwrap();
    assert_eq!(
        names(&result.documents),
        ["machine.svg", "viewer.html", "snapshots.svg"]
    );
    let html = &result.documents[1].1;
    assert!(html.starts_with("<!DOCTYPE html>") && html.len() < 2_000_000);
    let data = result.viewer.as_ref().expect("viewer data");
    assert_eq!(data.frames(), 501, "0.05 s at 0.1 ms");
    assert!(data.deviation.is_none(), "KED has no platform deviation");

    // Slider positions: the closed-form inverse kinematics of the paper's circle.
    let (geometry, circle) = (Geometry::paper(), Circle::paper(20.0).unwrap());
    for (k, &t) in data.time.iter().enumerate() {
        let legs = geometry.inverse_position(&circle.motion(t).pose).unwrap();
        for (i, leg) in legs.iter().enumerate() {
            assert!(
                (data.sliders[k][i] - leg.rho).abs() < 1e-12,
                "t = {t}, slider {}",
                i + 1
            );
        }
    }

    let deflections = result.table("deflections").unwrap();
    let frequencies = result.table("frequencies").unwrap();
    let kinematics = result.table("kinematics").unwrap();
    // Euler-Bernoulli pinned-pinned beam (model.md section 7): f0 = (pi/l)^2 sqrt(EI/(rho A))
    // / 2 pi, buckling load P_cr = pi^2 EI / l^2; 2 mm x 30 mm aluminium, l = 0.2 m.
    let (e, density, l, b, h): (f64, f64, f64, f64, f64) = (7.3e10, 2770.0, 0.2, 0.03, 0.002);
    let ei = e * b * h * h * h / 12.0;
    let f0 = (PI / l).powi(2) * (ei / (density * b * h)).sqrt() / (2.0 * PI);
    let p_cr = PI * PI * ei / (l * l);
    for (i, link) in data.links.iter().enumerate() {
        assert_eq!(link.basis, "sine (pinned-pinned)");
        assert!((link.length - l).abs() < 1e-15);
        // The sine basis, psi_j(xi) = sin(j pi xi).
        assert_eq!(link.mode_shapes.len(), 3);
        for (j, shape) in link.mode_shapes.iter().enumerate() {
            for (x, psi) in link.xi.iter().zip(shape) {
                assert!((psi - ((j + 1) as f64 * PI * x).sin()).abs() < 1e-12);
            }
        }
        // The modal sum at xi = 0.5 is the run's deflection there.
        let mid = link
            .xi
            .iter()
            .position(|x| (x - 0.5).abs() < 1e-15)
            .unwrap();
        let w = deflections.column(&format!("w_{}_xi0.5_m", i + 1)).unwrap();
        let scale = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 1e-4, "link {} barely deflects: {scale}", i + 1);
        assert_eq!(w.len(), data.frames());
        for (k, wk) in w.iter().enumerate() {
            assert!((link.deflection(k, mid) - wk).abs() < 1e-12 * scale);
        }
        // The axial force is the mean of the end forces. With the paper's diagonal K_p and
        // the sine basis, mode 1 stiffens by the closed form f = f0 sqrt(1 + P_eff / P_cr)
        // with P_eff = 2 int_0^1 P(xi l) cos^2(pi xi) dxi; for the paper's quadratic
        // P = P0 + P1 x + P2 x^2 with P2 = -rhoA beta'^2 / 2 (model.md section 5) that is
        // P_eff = P0 + P1 l / 2 + P2 l^2 (1/3 + 1/(2 pi^2)).
        let pb = frequencies.column(&format!("P_B_{}_N", i + 1)).unwrap();
        let pc = frequencies.column(&format!("P_C_{}_N", i + 1)).unwrap();
        let beta_dot = kinematics
            .column(&format!("beta_dot_{}_rad_s", i + 1))
            .unwrap();
        let mut largest = 0.0f64;
        for k in 0..data.frames() {
            let p = link.axial_force[k];
            assert!((p - 0.5 * (pb[k] + pc[k])).abs() < 1e-9 * (1.0 + p.abs()));
            largest = largest.max(p.abs());
            let p2l2 = -0.5 * density * b * h * beta_dot[k].powi(2) * l * l;
            let p1l = pc[k] - pb[k] - p2l2;
            let p_eff = pb[k] + 0.5 * p1l + p2l2 * (1.0 / 3.0 + 0.5 / (PI * PI));
            let expected = f0 * (1.0 + p_eff / p_cr).sqrt();
            let got = link.first_frequency[k];
            assert!(
                (got - expected).abs() < 1e-6 * expected,
                "link {} at t = {}: {got} Hz, closed form {expected} Hz (P = {p} N)",
                i + 1,
                data.time[k]
            );
        }
        assert!(
            largest > 50.0,
            "link {}: axial force up to {largest} N",
            i + 1
        );
        assert!(link.buckling.is_empty(), "the paper scene does not buckle");
    }
}

/// The coupled model: the viewer carries its platform deviation and its actual chord
/// tension, frame by frame.
#[test]
fn coupled_viewer_has_the_platform_deviation() {
    let scene = scene("coupled_f20.toml", 0.02, "\"viewer\", ");
    let result = run(&scene, &mut |_| {}).unwrap();
    let data = result.viewer.as_ref().expect("viewer data");
    let deviation = data.deviation.as_ref().expect("coupled deviation");
    assert_eq!(deviation.len(), data.frames());
    let table = result.table("platform_deviation").unwrap();
    let dx = table.column("dx_m").unwrap();
    let dphi = table.column("dphi_rad").unwrap();
    assert!(dx.iter().any(|v| v.abs() > 1e-7), "the platform deviates");
    let forces = result.table("coupled_forces").unwrap();
    for k in 0..data.frames() {
        assert!(
            (deviation[k][0] - dx[k]).abs() <= 1e-15 && (deviation[k][2] - dphi[k]).abs() <= 1e-15
        );
        for i in 0..3 {
            let pb = forces.column(&format!("P_B_{}_N", i + 1)).unwrap()[k];
            let pc = forces.column(&format!("P_C_{}_N", i + 1)).unwrap()[k];
            let p = data.links[i].axial_force[k];
            assert!((p - 0.5 * (pb + pc)).abs() < 1e-9 * (1.0 + p.abs()));
        }
    }
}

/// The 35 Hz stress scene buckles and diverges: the failed run still has a viewer of what
/// it computed, ending at the last output time reached, with the buckling intervals
/// (where the lowest omega^2 <= 0 and the drawn frequency is 0).
#[test]
fn failed_run_has_a_viewer_up_to_the_failure() {
    let scene = scene("stress/high_speed_f35.toml", 0.2, "\"viewer\", ");
    let failure = run(&scene, &mut |_| {}).unwrap_err();
    let t_fail = failure.error.time().expect("failure time");
    let partial = &failure.partial;
    assert!(names(&partial.documents).contains(&"viewer.html"));
    let data = partial
        .viewer
        .as_ref()
        .expect("viewer of the computed part");
    let rows = partial.table("deflections").unwrap().rows();
    assert_eq!(data.frames(), rows);
    let last = *data.time.last().unwrap();
    assert!(
        last <= t_fail + 1e-12 && last > t_fail - 2e-4,
        "{last} vs {t_fail}"
    );
    let buckling: usize = data.links.iter().map(|l| l.buckling.len()).sum();
    assert!(buckling > 0, "no buckling interval before the divergence");
    for link in &data.links {
        for (k, &t) in data.time.iter().enumerate() {
            let inside = link
                .buckling
                .iter()
                .any(|&(a, b)| t >= a - 1e-4 && t <= b + 1e-4);
            if link.first_frequency[k] <= 0.0 {
                assert!(inside, "zero frequency at t = {t} outside every interval");
            }
            if link
                .buckling
                .iter()
                .any(|&(a, b)| t > a + 1e-4 && t < b - 1e-4)
            {
                assert!(link.first_frequency[k] <= 0.0, "t = {t} inside an interval");
            }
        }
    }
}
