//! The figures of a run's tables: the paper's figures 6-15, and the kinematics, energies
//! and platform deviation (Zhang, Mills & Cleghorn 2007; the figure
//! numbers are in `docs/scenes.md`).

use flexprr_scene::Scene;

use flexprr_dynamics::{Column, Quantity as Q, Table};
use flexprr_plot::{Axis, Color, Dash, Figure, Panel, Series, Style};

use crate::columns::DEFLECTION_UNCONTROLLED;

/// A series of `column` of `table` against its time, if the table has the column.
fn series(table: &Table, column: Column, label: &str, style: Style) -> Option<Series> {
    Some(Series::new(
        label,
        table.time(),
        table.column(&column.header())?,
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

/// One series per link of `quantity`, labelled `label(i)` for links `i = 1..=3`, in the
/// palette's first three colours.
fn per_link(table: &Table, quantity: Q, label: impl Fn(usize) -> String) -> Vec<Option<Series>> {
    (1..=3)
        .map(|i| {
            series(
                table,
                Column::link(quantity, i - 1),
                &label(i),
                Style::nth(i - 1),
            )
        })
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

/// The run's description, for every figure's metadata.
fn about(scene: &Scene) -> String {
    format!("flexprr run of scene {}", scene.name)
}

/// The paper's figures 6-7 (`deflections_xi*.svg`) from the `deflections` table.
pub fn deflections(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let about = about(scene);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    deflection_figures(t, &scene.file.output.deflection_xi, &figure)
}

/// `modes.svg` from the `modes` table.
pub fn modes(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let about = about(scene);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    vec![modes_figure(t, scene.machine.links[0].modes(), &figure)]
}

/// `modal_forces.svg` (the paper's figure 9) from the `modal_forces` table.
pub fn modal_forces(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let about = about(scene);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    vec![modal_forces_figure(t, &figure)]
}

/// `driving_forces.svg` (the paper's figures 10-11) from the `driving_forces` table.
pub fn driving_forces(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let about = about(scene);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    vec![driving_forces_figure(t, &figure)]
}

/// `axial_force_frequency_mode*.svg` (the paper's figures 12-14) from the `frequencies`
/// table.
pub fn frequencies(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let about = about(scene);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    frequency_figures(t, scene.machine.links[0].modes(), &figure)
}

/// `axial_forces.svg` (the paper's figure 15) from the `axial_forces` table.
pub fn axial_forces(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let s = per_link(t, Q::AxialForceB, |i| format!("link {i}"));
    let f = Figure::new(time())
        .title("Axial forces at the sliders (tension positive)")
        .description(about(scene));
    vec![(
        "axial_forces.svg".to_string(),
        f.panel(panel(Axis::new("P_{B}", "N"), s)),
    )]
}

/// `platform_deviation.svg` from the `platform_deviation` table.
pub fn platform_deviation(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let about = about(scene);
    let figure = |title: &str| Figure::new(time()).title(title).description(&about);
    vec![deviation_figure(t, &figure)]
}

/// `kinematics.svg` from the `kinematics` table.
pub fn kinematics(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let rho = per_link(t, Q::SliderPosition, |i| format!("ρ_{{{i}}}"));
    let beta = per_link(t, Q::LinkAngle, |i| format!("β_{{{i}}}"));
    let f = Figure::new(time())
        .title("Slider positions and link angles")
        .description(about(scene))
        .panel(panel(Axis::new("ρ", "m"), rho))
        .panel(panel(Axis::new("β", "rad"), beta));
    vec![("kinematics.svg".to_string(), f)]
}

/// `energies.svg` from the `energies` table.
pub fn energies(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let s = per_link(t, Q::StrainEnergy, |i| format!("link {i}"));
    let f = Figure::new(time())
        .title("Strain energy of the links")
        .description(about(scene));
    vec![(
        "energies.svg".to_string(),
        f.panel(panel(Axis::new("U", "J"), s)),
    )]
}

/// `machine_frequencies.svg` from the `machine_frequencies` table.
pub fn machine_frequencies(scene: &Scene, t: &Table) -> Vec<(String, Figure)> {
    let f = crate::machine_frequencies::machine_frequencies_figure(t, &about(scene));
    vec![("machine_frequencies.svg".to_string(), f)]
}

/// The paper's figures 6-7: per deflection point `xi`, the three links'
/// deflections with and without the axial force, one panel per link; with vibration
/// control, the controlled deflection (solid) against the same scene without control
/// (dashed, light).
fn deflection_figures(t: &Table, points: &[f64], figure: Titled<'_>) -> Vec<(String, Figure)> {
    points
        .iter()
        .map(|&xi| {
            let uncontrolled = |i| Column::at(DEFLECTION_UNCONTROLLED, i, xi);
            let compared = t.column(&uncontrolled(0).header()).is_some();
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
                            uncontrolled(i - 1),
                            legend("without vibration control"),
                            light_dashed(),
                        ),
                        series(
                            t,
                            Column::at(Q::Deflection, i - 1, xi),
                            legend(main),
                            solid(0),
                        ),
                        series(
                            t,
                            Column::at(Q::DeflectionWithoutAxialForce, i - 1, xi),
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
        color: Color(150, 150, 150),
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
            [series(
                t,
                Column::mode(Q::ModalCoordinate, 0, j - 1),
                "",
                solid(0),
            )],
        ));
    }
    ("modes.svg".to_string(), f)
}

/// The paper's figure 9: the three modal forces on mode 1 of link 1 (eq. 16).
fn modal_forces_figure(t: &Table, figure: Titled<'_>) -> (String, Figure) {
    let s = [
        (Q::ModalForceRho, "F₁ = −M_{ρ} ρ̈"),
        (Q::ModalForceBeta, "F₂ = −M_{β} β̈"),
        (Q::ModalForceFg, "F₃ = F_{fg}"),
    ]
    .iter()
    .enumerate()
    .map(|(k, (q, l))| series(t, Column::mode(*q, 0, 0), l, solid(k)));
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
            series(
                t,
                Column::link(Q::DrivingForceFlexible, 0),
                "flexible links",
                solid(0),
            ),
            series(
                t,
                Column::link(Q::DrivingForceRigid, 0),
                "rigid links",
                dashed(1),
            ),
        ],
    ));
    if let Some(s) = series(t, Column::link(Q::DrivingForceDifference, 0), "", solid(2)) {
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
                        series(
                            t,
                            Column::link(Q::AxialForceB, 0),
                            "at B (slider)",
                            solid(0),
                        ),
                        series(
                            t,
                            Column::link(Q::AxialForceC, 0),
                            "at C (platform)",
                            dashed(1),
                        ),
                    ],
                ))
                .panel(panel(
                    Axis::new(format!("f_{{1,{j}}}"), "Hz"),
                    [series(
                        t,
                        Column::mode(Q::Frequency, 0, j - 1),
                        "",
                        solid(2),
                    )],
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
                series(t, Column::of(Q::DeviationX), "Δx", solid(0)),
                series(t, Column::of(Q::DeviationY), "Δy", dashed(1)),
            ],
        ))
        .panel(panel(
            Axis::new("Δφ", "rad"),
            [series(t, Column::of(Q::DeviationPhi), "", solid(2))],
        ));
    ("platform_deviation.svg".to_string(), f)
}
