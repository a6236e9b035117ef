//! The names of a linear model's states: for readers (`rate of the position of slider 1`)
//! and as identifiers (`rho_1_rate`) that python-control and MATLAB take as signal names.

use flexprr_dynamics::SceneModel;

use crate::linearize::StateName;
use crate::relax::Relaxation;

/// The added coordinates' names: the platform's deviation, then the links' axial
/// coordinates of the relaxed chords (`per_link` each).
fn added(k: usize, per_link: usize) -> (String, String) {
    match k {
        0..=2 => {
            let axis = ["x", "y", "phi"][k];
            (
                format!("platform deviation {axis} on the elastic chords"),
                format!("platform_dev_{axis}"),
            )
        }
        k => {
            let per_link = per_link.max(1);
            let (link, mode) = ((k - 3) / per_link, (k - 3) % per_link);
            (
                format!("axial coordinate {} of link {}", mode + 1, link + 1),
                format!("axial_{}_{}", link + 1, mode + 1),
            )
        }
    }
}

/// The names of every component of the relaxed state of `model` (`layout`): coordinates
/// (the model's, then the added ones), their rates, then a continuous law's states.
pub(crate) fn state_names(model: &dyn SceneModel, layout: &Relaxation<'_>) -> Vec<StateName> {
    let (own, total) = (layout.own, layout.total);
    let per_link = layout.added().saturating_sub(3) / 3;
    let coordinate = |k: usize| -> (String, String) {
        if k < own {
            model.coordinate_label(k)
        } else {
            added(k - own, per_link)
        }
    };
    let law = model
        .actuation()
        .map_or_else(|| "control".to_string(), |a| a.controller.name());
    // The actuators' own states come last, slider by slider.
    let actuator_states: Vec<(String, String)> = model.actuation().map_or_else(Vec::new, |a| {
        a.actuators
            .iter()
            .enumerate()
            .flat_map(|(i, actuator)| {
                actuator.state_names().iter().map(move |s| {
                    (
                        format!(
                            "{} of actuator {} ({})",
                            s.name.replace('_', " "),
                            i + 1,
                            s.unit
                        ),
                        format!("{}_{}", s.name, i + 1),
                    )
                })
            })
            .collect()
    });
    let first_actuator_state = layout.dim() - actuator_states.len();
    (0..layout.dim())
        .map(|k| {
            let (name, signal) = if k < total {
                coordinate(k)
            } else if k < 2 * total {
                let (name, signal) = coordinate(k - total);
                (format!("rate of the {name}"), format!("{signal}_rate"))
            } else if k >= first_actuator_state {
                actuator_states[k - first_actuator_state].clone()
            } else {
                let i = k - 2 * total + 1;
                (format!("state {i} of the {law} law"), format!("law_{i}"))
            };
            StateName { name, signal }
        })
        .collect()
}
