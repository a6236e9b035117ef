//! `machine_frequencies.svg`: the whole machine's lowest frequencies along the motion beside
//! each link's first KED frequency (the per-link pinned-pinned estimate), all of the
//! tabulated whole-machine frequencies on a logarithmic axis, and their damping ratios (as
//! points) when any mode is damped.

use flexprr_dynamics::{Column, Quantity as Q, Table};
use flexprr_plot::{Axis, Dash, Figure, Panel, Series, Style};

/// A whole-machine mode's column.
fn machine(quantity: Q, k: usize) -> Column {
    Column {
        quantity,
        link: None,
        mode: Some(k),
        xi: None,
    }
}

/// The whole-machine lines: one colour, labelled once.
fn machine_style() -> Style {
    Style::nth(5)
}

/// Whole-machine modes whose highest frequency along the motion stays below this multiple
/// of the highest first KED frequency are drawn with the links' first modes.
const NEAR_FIRST_FAMILY: f64 = 2.5;

/// The figure of a `machine_frequencies` table, described by `about`.
pub(crate) fn machine_frequencies_figure(t: &Table, about: &str) -> Figure {
    let time = t.time();
    let modes: Vec<&[f64]> = (0..)
        .map_while(|k| t.get(&machine(crate::columns::MACHINE_FREQUENCY, k)))
        .collect();
    let ked: Vec<&[f64]> = (0..3)
        .filter_map(|i| t.get(&Column::mode(Q::Frequency, i, 0)))
        .collect();
    let ked_top = ked
        .iter()
        .flat_map(|c| c.iter())
        .fold(0.0_f64, |m, v| m.max(*v));
    let mut near = Panel::new(Axis::new("f", "Hz"));
    let mut labelled = false;
    for f in &modes {
        let top = f.iter().fold(0.0_f64, |m, v| m.max(*v));
        if ked_top > 0.0 && top > NEAR_FIRST_FAMILY * ked_top {
            continue;
        }
        let label = if labelled { "" } else { "whole machine" };
        labelled = true;
        near = near.series(Series::new(label, time, f, machine_style()));
    }
    for (i, f) in ked.iter().enumerate() {
        let label = format!("link {}, first KED mode", i + 1);
        near = near.series(Series::new(
            label,
            time,
            f,
            Style::nth(i).dash(Dash::Dashed),
        ));
    }
    let mut all = Panel::new(Axis::log(format!("f, lowest {}", modes.len()), "Hz"));
    for f in &modes {
        all = all.series(Series::new("", time, f, machine_style()));
    }
    let mut figure = Figure::new(Axis::new("t", "s"))
        .title("Whole-machine frequencies along the motion")
        .description(about)
        .panel(near)
        .panel(all);
    let damping: Vec<&[f64]> = (0..)
        .map_while(|k| t.get(&machine(crate::columns::MACHINE_DAMPING_RATIO, k)))
        .collect();
    if damping
        .iter()
        .flat_map(|z| z.iter())
        .any(|z| z.abs() > 1e-6)
    {
        let mut panel = Panel::new(Axis::new("ζ", ""));
        for z in &damping {
            let (x, y) = broken(time, z);
            panel = panel.series(Series::new("", &x, &y, machine_style()));
        }
        figure = figure.panel(panel);
    }
    figure
}

/// A jump of the damping ratio between two instants larger than this breaks its line.
const DAMPING_JUMP: f64 = 0.05;

/// The `k`-th lowest mode changes identity where two modes cross, and its damping ratio
/// then jumps (between a servo mode's and a bending mode's): the line is broken there (a
/// non-finite point between the two instants), not drawn across.
fn broken(t: &[f64], z: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut y) = (Vec::with_capacity(t.len()), Vec::with_capacity(z.len()));
    for k in 0..t.len().min(z.len()) {
        if k > 0 && (z[k] - z[k - 1]).abs() > DAMPING_JUMP {
            x.push(0.5 * (t[k] + t[k - 1]));
            y.push(f64::NAN);
        }
        x.push(t[k]);
        y.push(z[k]);
    }
    (x, y)
}
