//! The machine under control in a run (docs/control.md): the `tracking` and `actuators`
//! tables, the feasibility of the commanded motion for the scene's motors, the servo
//! summary of an actuated run, their warnings, `summary.json` sections and figures.
//!
//! Everything here reads the run's shared samples (the commanded motion, its inverse
//! kinematics and rigid inverse dynamics) and the model's [`MachineSnapshot`]s; nothing asks
//! which model ran. A snapshot with [`MachineSnapshot::actuators`] is an actuated model's; a
//! snapshot without is a model whose sliders are prescribed.

mod servo;
mod tables;

use flexprr_dynamics::{DynamicsError, MachineSnapshot};
use flexprr_scene::{OutputKind, Scene};
use serde_json::Value;

pub use flexprr_requirement::Peak;
pub use flexprr_requirement::{Feasibility, LegRequirement, SCAN_TOLERANCE};
pub use servo::{PlatformSummary, ServoSummary, SliderSummary};

use crate::samples::Samples;
use crate::table::RunResult;

/// What a run found about its actuators and control: the feasibility of the commanded
/// motion for the scene's motors, and the servo summary of an actuated run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ControlReport {
    /// The commanded rigid motion against the motors' ratings, when the scene names a
    /// motor (`[actuators] kind = "motor_ballscrew"`), for every model.
    pub feasibility: Option<Feasibility>,
    /// Tracking errors and actuator loads of a run whose sliders are actuated.
    pub servo: Option<ServoSummary>,
}

/// Whether a run of `scene` needs the shared samples for control outputs or checks.
pub(crate) fn needs_samples(scene: &Scene) -> bool {
    scene.outputs.contains(&OutputKind::Tracking)
        || scene.outputs.contains(&OutputKind::Actuators)
        || scene.actuator.is_some()
}

/// Whether a run of `scene` needs the model's snapshots for control outputs or checks.
pub(crate) fn needs_snapshots(scene: &Scene) -> bool {
    scene.outputs.contains(&OutputKind::Tracking)
        || scene.outputs.contains(&OutputKind::Actuators)
        || scene.controller.is_some()
}

/// The control outputs of a run into `result`: the `tracking` and `actuators` tables when
/// requested, the feasibility check when the scene names a motor, the servo summary when
/// the model's sliders are actuated, and their warnings. `snapshots` are the integrated
/// model's at the samples' times, when it was integrated.
///
/// # Errors
/// A singular rigid inverse dynamics at an output time (the commanded motion's).
pub(crate) fn produce(
    scene: &Scene,
    samples: &mut Samples,
    snapshots: Option<&[MachineSnapshot]>,
    result: &mut RunResult,
) -> Result<(), DynamicsError> {
    let actuated = snapshots.filter(|s| s.first().is_some_and(|p| p.actuators.is_some()));
    let motor = scene.actuator.as_deref().filter(|a| a.ratings().is_some());
    let motor_required = match motor {
        Some(m) => Some(required(m, samples, scene)?),
        None => None,
    };
    if scene.outputs.contains(&OutputKind::Tracking) {
        if let Some(snapshots) = snapshots {
            result.tables.push(tables::tracking(samples, snapshots));
        }
    }
    if scene.outputs.contains(&OutputKind::Actuators) {
        let table = match (actuated, &motor_required) {
            (Some(snapshots), _) => tables::actuators_of_model(snapshots),
            (None, Some(required)) => tables::actuators_required(samples, required),
            (None, None) => {
                let ideal = flexprr_control::IdealForce;
                let actuator = scene.actuator.as_deref().unwrap_or(&ideal);
                let required = required(actuator, samples, scene)?;
                tables::actuators_required(samples, &required)
            }
        };
        result.tables.push(table);
    }
    let mut report = ControlReport::default();
    if let Some(motor) = motor {
        // The commanded motion is known over the whole span, between the samples and
        // beyond a failure: check all of it.
        report.feasibility = Feasibility::scan(scene, motor)?;
    }
    if let Some(snapshots) = actuated {
        report.servo = Some(ServoSummary::of(scene, samples, snapshots));
    }
    if report.feasibility.is_some() || report.servo.is_some() {
        result.add_report(report);
    }
    Ok(())
}

/// What `actuator` must deliver along the commanded motion at the samples' times.
///
/// # Errors
/// A singular rigid inverse dynamics at an output time.
fn required(
    actuator: &dyn flexprr_control::Actuator,
    samples: &mut Samples,
    scene: &Scene,
) -> Result<flexprr_requirement::Required, DynamicsError> {
    let reactions = samples.with_reactions(&scene.machine)?.to_vec();
    Ok(flexprr_requirement::required(
        actuator,
        &samples.states,
        &reactions,
    ))
}

impl crate::report::Report for ControlReport {
    fn name(&self) -> &'static str {
        "control"
    }

    /// `control` (the servo summary) and `feasibility`, `null` where the run has none.
    fn sections(&self) -> Vec<(&'static str, Value)> {
        vec![
            (
                "control",
                self.servo
                    .as_ref()
                    .map_or(Value::Null, ServoSummary::to_json),
            ),
            (
                "feasibility",
                self.feasibility
                    .as_ref()
                    .map_or(Value::Null, Feasibility::to_json),
            ),
        ]
    }

    /// The feasibility's warnings, then the servo's.
    fn warnings(&self) -> Vec<String> {
        let mut w = self
            .feasibility
            .as_ref()
            .map(Feasibility::warnings)
            .unwrap_or_default();
        w.extend(
            self.servo
                .as_ref()
                .map(ServoSummary::warnings)
                .unwrap_or_default(),
        );
        w
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

/// The control report of `result`: the empty one (no feasibility, no servo summary) when
/// the run made none.
pub fn report_of(result: &RunResult) -> &ControlReport {
    static NONE: ControlReport = ControlReport {
        feasibility: None,
        servo: None,
    };
    result.report::<ControlReport>().unwrap_or(&NONE)
}

pub use flexprr_figures::columns::{MOTOR_SATURATED, MOTOR_SPEED, MOTOR_TORQUE};

#[cfg(test)]
mod tests {
    use super::{MOTOR_SATURATED, MOTOR_SPEED, MOTOR_TORQUE};
    use crate::column::Column;

    #[test]
    fn motor_headers_follow_the_documented_pattern() {
        assert_eq!(Column::link(MOTOR_TORQUE, 2).header(), "motor_torque_3_N_m");
        assert_eq!(Column::link(MOTOR_SPEED, 1).header(), "motor_speed_2_rev_s");
        assert_eq!(
            Column::link(MOTOR_SATURATED, 0).header(),
            "motor_saturated_1_flag"
        );
    }
}
