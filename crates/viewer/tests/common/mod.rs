//! The paper scene for the viewer tests: the real machine and trajectory from
//! `flexprr_kinematics` (paper geometry, 20 Hz circle at phi = 45 deg), with SYNTHETIC
//! flexible-link series (modal coordinates, axial forces, buckling) that only look
//! plausible. The lead replaces the synthetic part with a real run's output.

#![allow(dead_code)]

use std::f64::consts::{PI, TAU};

use flexprr_kinematics::{Circle, Geometry, Trajectory};
use flexprr_viewer::{GuideView, LinkView, ViewerData};

/// The paper's machine (model.md section 1).
pub fn paper_geometry() -> Geometry {
    Geometry::paper()
}

/// The paper's trajectory at 20 Hz.
pub fn paper_circle() -> Circle {
    Circle::paper(20.0).unwrap()
}

/// Flexural rigidity EI of the paper's link (N m^2): E = 7.3e10 Pa, 2 mm x 30 mm section.
pub const EI: f64 = 7.3e10 * 0.03 * 0.002 * 0.002 * 0.002 / 12.0;

/// Viewer data of the paper scene over `[0, duration]` with output step `step`.
///
/// Exact: guides, travel, platform joints, platform pose and slider positions (inverse
/// kinematics), the sine mode shapes. SYNTHETIC: axial forces (a 20 Hz sinusoid per link),
/// the first-mode frequency from the exact uniform-load formula of model.md section 7 at
/// that force, modal coordinates (forced 20 Hz part plus a free 116 Hz ringing), and, when
/// `with_buckling`, one made-up buckling interval on link 2 from 0.120 s to 0.130 s.
pub fn paper_scene(duration: f64, step: f64, with_buckling: bool) -> ViewerData {
    let geometry = paper_geometry();
    let circle = paper_circle();
    let n = (duration / step).round() as usize + 1;
    let time: Vec<f64> = (0..n).map(|k| k as f64 * step).collect();
    let mut pose = Vec::with_capacity(n);
    let mut sliders = Vec::with_capacity(n);
    for &t in &time {
        let m = circle.motion(t);
        let legs = geometry.inverse_position(&m.pose).unwrap();
        pose.push([m.pose.x, m.pose.y, m.pose.phi]);
        sliders.push([legs[0].rho, legs[1].rho, legs[2].rho]);
    }
    let xi: Vec<f64> = (0..=40).map(|j| j as f64 / 40.0).collect();
    let modes = 3;
    let shapes: Vec<Vec<f64>> = (1..=modes)
        .map(|k| xi.iter().map(|x| (k as f64 * PI * x).sin()).collect())
        .collect();
    let l = 0.2;
    let p_cr = PI * PI * EI / (l * l);
    let f10 = 116.4;
    let links = std::array::from_fn(|i| {
        let phase = TAU * i as f64 / 3.0;
        let mut axial = Vec::with_capacity(n);
        let mut freq = Vec::with_capacity(n);
        let mut modal = Vec::with_capacity(n);
        let mut buckling = Vec::new();
        for &t in &time {
            let w = TAU * 20.0 * t + phase;
            let mut p = 28.0 * w.sin() + 6.0 * (2.0 * w).cos();
            if with_buckling && i == 1 && (0.12..=0.13).contains(&t) {
                p = -1.05 * p_cr;
            }
            let ratio = 1.0 + p / p_cr;
            axial.push(p);
            freq.push(if ratio > 0.0 { f10 * ratio.sqrt() } else { 0.0 });
            modal.push(vec![
                1.2e-4 * w.sin() + 3.0e-5 * (TAU * f10 * t).sin() * (-8.0 * t).exp(),
                1.5e-5 * (w + 0.4).cos(),
                2.0e-6 * (2.0 * w).sin(),
            ]);
        }
        if with_buckling && i == 1 {
            buckling.push((0.12, 0.13));
        }
        LinkView {
            length: l,
            basis: "sine".into(),
            xi: xi.clone(),
            mode_shapes: shapes.clone(),
            modal,
            axial_force: axial,
            first_frequency: freq,
            buckling,
            patches: Vec::new(),
        }
    });
    ViewerData {
        title: "paper_f20 (synthetic link series)".into(),
        subtitle: "paper geometry and 20 Hz circle; modal coordinates and axial forces are \
                   SYNTHETIC test series"
            .into(),
        guides: std::array::from_fn(|i| {
            let g = &geometry.legs[i].guide;
            GuideView {
                anchor: [g.anchor.x, g.anchor.y],
                direction: [g.direction.x, g.direction.y],
                travel: g.travel,
            }
        }),
        attachments: std::array::from_fn(|i| {
            let c = geometry.legs[i].attachment;
            [c.x, c.y]
        }),
        links,
        time,
        pose,
        sliders,
        deviation: None,
        reference_sliders: None,
    }
}
