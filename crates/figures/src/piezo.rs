//! `piezo.svg`: each patch's applied voltage (with the voltage limits and, dashed, the
//! command where it was clipped), its sensor voltage and its actuator power against time.

use flexprr_dynamics::{Column, Quantity as Q, Table};
use flexprr_plot::{Axis, Dash, Figure, Panel, Series, Style};
use flexprr_scene::Scene;

use crate::columns::{
    PATCH_COMMAND_VOLTAGE, PATCH_POWER, PATCH_SENSOR_VOLTAGE, PATCH_VOLTAGE, index_on_link,
};

/// The header of patch `p`'s column of `quantity` (its link and index on the link).
fn header(scene: &Scene, p: usize, quantity: Q) -> String {
    let index = index_on_link(scene, p);
    Column::mode(quantity, scene.patches[p].link, index).header()
}

/// Patch `p`'s legend label: its link and span.
fn label(scene: &Scene, p: usize) -> String {
    let patch = &scene.patches[p];
    format!(
        "link {}, ξ {}–{}",
        patch.link + 1,
        patch.xi_start,
        patch.xi_end
    )
}

/// One series per patch of `quantity`, coloured by patch, labelled when `labelled`.
fn per_patch(scene: &Scene, t: &Table, quantity: Q, labelled: bool) -> Vec<Series> {
    (0..scene.patches.len())
        .filter_map(|p| {
            let y = t.column(&header(scene, p, quantity))?;
            let name = if labelled {
                label(scene, p)
            } else {
                String::new()
            };
            Some(Series::new(name, t.time(), y, Style::nth(p)))
        })
        .collect()
}

/// The figure of the `piezo` table, when the run has it; `saturated`: whether a patch's
/// command was clipped (the commands are drawn then).
pub fn figures(scene: &Scene, piezo: Option<&Table>, saturated: bool) -> Vec<(String, Figure)> {
    let Some(t) = piezo.filter(|t| t.rows() > 1) else {
        return Vec::new();
    };
    let mut voltage = per_patch(scene, t, PATCH_VOLTAGE, true);
    if saturated {
        let commands = (0..scene.patches.len()).filter_map(|p| {
            let y = t.column(&header(scene, p, PATCH_COMMAND_VOLTAGE))?;
            Some(Series::new(
                "",
                t.time(),
                y,
                Style::nth(p).dash(Dash::Dotted),
            ))
        });
        voltage.extend(commands);
    }
    let limit = scene
        .patches
        .iter()
        .fold(0.0_f64, |m, p| m.max(p.voltage_limit));
    let time = t.time();
    let span = [time[0], time[time.len() - 1]];
    let black = Style::nth(5).dash(Dash::Dashed);
    voltage.push(Series::new("voltage limit", &span, &[limit, limit], black));
    voltage.push(Series::new("", &span, &[-limit, -limit], black));
    let title = if saturated {
        "Piezoelectric patches: applied voltage (dotted: the command beyond the limit), \
         sensor voltage, actuator power (negative: energy taken from the link)"
    } else {
        "Piezoelectric patches: applied voltage, sensor voltage, actuator power \
         (negative: energy taken from the link)"
    };
    let figure = Figure::new(Axis::new("t", "s"))
        .title(title)
        .description(format!("flexprr run of scene {}", scene.name))
        .panel(Panel {
            y: Axis::new("V", "V"),
            series: voltage,
        })
        .panel(Panel {
            y: Axis::new("V_{s}", "V"),
            series: per_patch(scene, t, PATCH_SENSOR_VOLTAGE, false),
        })
        .panel(Panel {
            y: Axis::new("P", "W"),
            series: per_patch(scene, t, PATCH_POWER, false),
        });
    vec![("piezo.svg".to_string(), figure)]
}
