//! The figures of a run: the paper's figures 6-15 that the run's tables can draw, and the
//! kinematics, energies and platform deviation (Zhang, Mills & Cleghorn 2007; the figure
//! numbers are in `docs/scenes.md`).

use flexprr_scene::Scene;

use super::{Axis, Dash, Figure, Panel, Series, Style};
use crate::table::{RunResult, Table};

/// A series of column `header` of `table` against its time, if the table has the column.
fn series(table: &Table, header: &str, label: &str, style: Style) -> Option<Series> {
    Some(Series::new(
        label,
        table.time(),
        table.column(header)?,
        style,
    ))
}

/// A panel from a y axis and the series found.
fn panel(y: Axis, series: impl IntoIterator<Item = Option<Series>>) -> Panel {
    Panel {
        y,
        series: series.into_iter().flatten().collect(),
    }
}

/// One series per link, `header(i)` and `label(i)` for links `i = 1..=3`, in the palette's
/// first three colours.
fn per_link(
    table: &Table,
    header: impl Fn(usize) -> String,
    label: impl Fn(usize) -> String,
) -> Vec<Option<Series>> {
    (1..=3)
        .map(|i| series(table, &header(i), &label(i), Style::nth(i - 1)))
        .collect()
}

fn time() -> Axis {
    Axis::new("t", "s")
}

/// A titled figure over time, with the run's description.
type Titled<'a> = &'a dyn Fn(&str) -> Figure;

/// A solid line in the `k`-th colour.
fn solid(k: usize) -> Style {
    Style::nth(k)
}

/// A dashed line in the `k`-th colour (a second variant of the same quantity).
fn dashed(k: usize) -> Style {
    Style::nth(k).dash(Dash::Dashed)
}

/// The run's figures as (file name, figure), for the tables `result` holds.
pub fn run_figures(scene: &Scene, result: &RunResult) -> Vec<(String, Figure)> {
    let about = format!("flexprr run of scene {}", scene.name);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    let modes = scene.machine.links[0].modes();
    let mut out = Vec::new();
    if let Some(t) = result.table("deflections") {
        out.extend(deflection_figures(
            t,
            &scene.file.output.deflection_xi,
            &figure,
        ));
    }
    if let Some(t) = result.table("modes") {
        out.push(modes_figure(t, modes, &figure));
    }
    if let Some(t) = result.table("modal_forces") {
        out.push(modal_forces_figure(t, &figure));
    }
    if let Some(t) = result.table("driving_forces") {
        out.push(driving_forces_figure(t, &figure));
    }
    if let Some(t) = result.table("frequencies") {
        out.extend(frequency_figures(t, modes, &figure));
    }
    if let Some(t) = result.table("axial_forces") {
        // The paper's figure 15.
        let s = per_link(t, |i| format!("P_B_{i}_N"), |i| format!("link {i}"));
        out.push((
            "axial_forces.svg".to_string(),
            figure("Axial forces at the sliders (tension positive)")
                .panel(panel(Axis::new("P_{B}", "N"), s)),
        ));
    }
    if let Some(t) = result.table("platform_deviation") {
        out.push(deviation_figure(t, &figure));
    }
    if let Some(t) = result.table("kinematics") {
        let rho = per_link(t, |i| format!("rho_{i}_m"), |i| format!("ρ_{{{i}}}"));
        let beta = per_link(t, |i| format!("beta_{i}_rad"), |i| format!("β_{{{i}}}"));
        let f = figure("Slider positions and link angles")
            .panel(panel(Axis::new("ρ", "m"), rho))
            .panel(panel(Axis::new("β", "rad"), beta));
        out.push(("kinematics.svg".to_string(), f));
    }
    if let Some(t) = result.table("energies") {
        let s = per_link(t, |i| format!("strain_{i}_J"), |i| format!("link {i}"));
        out.push((
            "energies.svg".to_string(),
            figure("Strain energy of the links").panel(panel(Axis::new("U", "J"), s)),
        ));
    }
    if let Some(t) = result.table("machine_frequencies") {
        let f = super::machine_frequencies_figure::machine_frequencies_figure(t, &about);
        out.push(("machine_frequencies.svg".to_string(), f));
    }
    out.extend(crate::control::figures(scene, result));
    out.extend(crate::piezo::figures(scene, result));
    out.retain(|(_, f)| f.panels.iter().any(|p| !p.series.is_empty()));
    out
}

/// The paper's figures 6-7: per deflection point `xi`, the three links'
/// deflections with and without the axial force, one panel per link; with vibration
/// control, the controlled deflection (solid) against the same scene without control
/// (dashed, light).
fn deflection_figures(t: &Table, points: &[f64], figure: Titled<'_>) -> Vec<(String, Figure)> {
    points
        .iter()
        .map(|&xi| {
            let compared = t.column(&format!("w_1_xi{xi}_uncontrolled_m")).is_some();
            let title = if compared {
                format!("Deflection of the links at ξ = {xi}, with and without vibration control")
            } else {
                format!("Deflection of the links at ξ = {xi}")
            };
            let mut f = figure(&title);
            for i in 1..=3 {
                // The legend once, on the top panel: the styles are the same below.
                let first = i == 1;
                let legend = |s: &'static str| if first { s } else { "" };
                let main = if compared {
                    "with vibration control"
                } else {
                    "with axial force"
                };
                f = f.panel(panel(
                    Axis::new(format!("w_{{{i}}}"), "m"),
                    [
                        series(
                            t,
                            &format!("w_{i}_xi{xi}_uncontrolled_m"),
                            legend("without vibration control"),
                            light_dashed(),
                        ),
                        series(t, &format!("w_{i}_xi{xi}_m"), legend(main), solid(0)),
                        series(
                            t,
                            &format!("w_{i}_xi{xi}_no_axial_m"),
                            legend("without axial force"),
                            dashed(1),
                        ),
                    ],
                ));
            }
            (format!("deflections_xi{xi}.svg"), f)
        })
        .collect()
}

/// A light grey dashed line: the reference a result is compared with, drawn under it.
fn light_dashed() -> Style {
    Style {
        color: super::Color(150, 150, 150),
        ..Style::nth(0).dash(Dash::Dashed)
    }
}

/// The paper's figure 8: the modal coordinates of link 1, one panel per mode (at most
/// three of `modes`).
fn modes_figure(t: &Table, modes: usize, figure: Titled<'_>) -> (String, Figure) {
    let mut f = figure("Modal coordinates of link 1");
    for j in 1..=modes.min(3) {
        f = f.panel(panel(
            Axis::new(format!("η_{{1,{j}}}"), "m"),
            [series(t, &format!("eta_1_{j}_m"), "", solid(0))],
        ));
    }
    ("modes.svg".to_string(), f)
}

/// The paper's figure 9: the three modal forces on mode 1 of link 1 (eq. 16).
fn modal_forces_figure(t: &Table, figure: Titled<'_>) -> (String, Figure) {
    let s = [
        ("F_rho_1_1_N", "F₁ = −M_{ρ} ρ̈"),
        ("F_beta_1_1_N", "F₂ = −M_{β} β̈"),
        ("F_fg_1_1_N", "F₃ = F_{fg}"),
    ]
    .iter()
    .enumerate()
    .map(|(k, (c, l))| series(t, c, l, solid(k)));
    (
        "modal_forces.svg".to_string(),
        figure("Modal forces on mode 1 of link 1").panel(panel(Axis::new("modal force", "N"), s)),
    )
}

/// The paper's figures 10-11: the driving force of slider 1 with flexible and rigid links, and
/// their difference when the table has it.
fn driving_forces_figure(t: &Table, figure: Titled<'_>) -> (String, Figure) {
    let mut f = figure("Driving force of slider 1").panel(panel(
        Axis::new("F_{a1}", "N"),
        [
            series(t, "F_a_1_flexible_N", "flexible links", solid(0)),
            series(t, "F_a_1_rigid_N", "rigid links", dashed(1)),
        ],
    ));
    if let Some(s) = series(t, "F_a_1_difference_N", "", solid(2)) {
        f = f.panel(Panel::new(Axis::new("ΔF_{a1}", "N")).series(s));
    }
    ("driving_forces.svg".to_string(), f)
}

/// The paper's figures 12-14: per mode of link 1 (at most three of `modes`), the axial
/// force at both ends above the mode's frequency.
fn frequency_figures(t: &Table, modes: usize, figure: Titled<'_>) -> Vec<(String, Figure)> {
    (1..=modes.min(3))
        .map(|j| {
            let f = figure(&format!("Axial force and mode {j} frequency of link 1"))
                .panel(panel(
                    Axis::new("P₁", "N"),
                    [
                        series(t, "P_B_1_N", "at B (slider)", solid(0)),
                        series(t, "P_C_1_N", "at C (platform)", dashed(1)),
                    ],
                ))
                .panel(panel(
                    Axis::new(format!("f_{{1,{j}}}"), "Hz"),
                    [series(t, &format!("f_1_{j}_Hz"), "", solid(2))],
                ));
            (format!("axial_force_frequency_mode{j}.svg"), f)
        })
        .collect()
}

/// The platform's deviation from its nominal path (coupled and nonlinear models):
/// position above orientation.
fn deviation_figure(t: &Table, figure: Titled<'_>) -> (String, Figure) {
    let f = figure("Platform deviation from the nominal path")
        .panel(panel(
            Axis::new("Δx, Δy", "m"),
            [
                series(t, "dx_m", "Δx", solid(0)),
                series(t, "dy_m", "Δy", dashed(1)),
            ],
        ))
        .panel(panel(
            Axis::new("Δφ", "rad"),
            [series(t, "dphi_rad", "", solid(2))],
        ));
    ("platform_deviation.svg".to_string(), f)
}
