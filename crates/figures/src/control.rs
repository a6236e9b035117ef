//! The figures of the control outputs: `tracking.svg` (slider and platform tracking errors
//! against time) and `actuators.svg` (force on each slider; where a motor is modelled its
//! torque with the peak and continuous ratings, and its speed with the largest speed).

use flexprr_dynamics::{Column, Quantity as Q, Table};
use flexprr_plot::{Axis, Dash, Figure, Panel, Series, Style};
use flexprr_scene::Scene;

use crate::columns::{MOTOR_SPEED, MOTOR_TORQUE};

/// One series per slider of `quantity`, labelled `slider i` when `labelled` (the legend
/// once per figure: the colours are the same in every panel).
fn per_slider(table: &Table, quantity: Q, labelled: bool) -> Vec<Series> {
    (1..=3)
        .filter_map(|i| {
            let y = table.column(&Column::link(quantity, i - 1).header())?;
            let label = if labelled {
                format!("slider {i}")
            } else {
                String::new()
            };
            Some(Series::new(label, table.time(), y, Style::nth(i - 1)))
        })
        .collect()
}

/// Horizontal lines at `+value` and `-value` across the table's time span, in `style`,
/// with one legend entry `label`.
fn rating_lines(table: &Table, value: f64, label: &str, style: Style) -> [Series; 2] {
    let t = table.time();
    let span = [t[0], t[t.len() - 1]];
    [
        Series::new(label, &span, &[value, value], style),
        Series::new("", &span, &[-value, -value], style),
    ]
}

fn panel(y: Axis, series: impl IntoIterator<Item = Series>) -> Panel {
    Panel {
        y,
        series: series.into_iter().collect(),
    }
}

/// The control figures of the `tracking` and `actuators` tables a run has.
pub fn figures(
    scene: &Scene,
    tracking: Option<&Table>,
    actuators: Option<&Table>,
) -> Vec<(String, Figure)> {
    let about = format!("flexprr run of scene {}", scene.name);
    let figure = |title: &str| {
        Figure::new(Axis::new("t", "s"))
            .title(title)
            .description(&about)
    };
    let mut out = Vec::new();
    if let Some(t) = tracking.filter(|t| t.rows() > 1) {
        let errors = [(Q::PlatformErrorX, "x"), (Q::PlatformErrorY, "y")];
        let platform = errors.iter().enumerate().filter_map(|(k, (q, c))| {
            let y = t.column(&Column::of(*q).header())?;
            let style = Style::nth(k + 3).dash(if k == 0 { Dash::Solid } else { Dash::Dashed });
            Some(Series::new(format!("e_{{{c}}}"), t.time(), y, style))
        });
        let orientation = t
            .column(&Column::of(Q::PlatformErrorPhi).header())
            .map(|y| Series::new("", t.time(), y, Style::nth(5)));
        let f = figure("Tracking errors (commanded minus actual)")
            .panel(panel(
                Axis::new("ρ_{ref} − ρ", "m"),
                per_slider(t, Q::SliderError, true),
            ))
            .panel(panel(Axis::new("platform e_{x}, e_{y}", "m"), platform))
            .panel(panel(Axis::new("platform e_{φ}", "rad"), orientation));
        out.push(("tracking.svg".to_string(), f));
    }
    if let Some(t) = actuators.filter(|t| t.rows() > 1) {
        let ratings = scene.actuator.as_ref().and_then(|a| a.ratings());
        let mut f = figure("Actuator force on each slider").panel(panel(
            Axis::new("F", "N"),
            per_slider(t, Q::ActuatorForce, true),
        ));
        let torque = per_slider(t, MOTOR_TORQUE, false);
        if !torque.is_empty() {
            let mut series = torque;
            if let Some(r) = ratings {
                let black = Style::nth(5);
                series.extend(rating_lines(
                    t,
                    r.peak_torque,
                    "peak torque",
                    black.dash(Dash::Dashed),
                ));
                series.extend(rating_lines(
                    t,
                    r.continuous_torque,
                    "continuous torque",
                    black.dash(Dash::Dotted),
                ));
            }
            f = f.panel(panel(Axis::new("τ", "N·m"), series));
            // The slider entries again: a lone "max speed" entry would get no legend.
            let mut speed = per_slider(t, MOTOR_SPEED, true);
            if let Some(r) = ratings {
                speed.extend(rating_lines(
                    t,
                    r.max_speed,
                    "max speed",
                    Style::nth(5).dash(Dash::Dashed),
                ));
            }
            f = f.panel(panel(Axis::new("n", "rev/s"), speed));
        }
        if f.panels.len() > 1 {
            f.title = Some("Actuators: force, motor torque and speed".to_string());
        }
        out.push(("actuators.svg".to_string(), f));
    }
    out
}
