//! The `tracking` and `actuators` tables.

use flexprr_control::{ActuatorSignal, MOTOR_SIGNALS};
use flexprr_dynamics::{Column, MachineSnapshot, NamedQuantity, Quantity as Q, Table};

use crate::samples::Samples;
use flexprr_requirement::Required;

/// `tracking.csv`: per slider `rho_ref - rho` (the commanded inverse kinematics of the
/// samples minus the model's slider), and the platform's commanded minus actual pose. Zero
/// slider errors where the model prescribes the sliders; minus the platform deviation for a
/// model whose platform follows the links.
pub(crate) fn tracking(samples: &Samples, snapshots: &[MachineSnapshot]) -> Table {
    let n = snapshots.len().min(samples.len());
    let mut table = Table::new("tracking", &samples.t[..n]);
    for i in 0..3 {
        let error = (0..n)
            .map(|k| samples.states[k].legs[i].rho - snapshots[k].sliders[i].position)
            .collect();
        table.push(Column::link(Q::SliderError, i), error);
    }
    type Part = fn(&flexprr_kinematics::Pose) -> f64;
    let parts: [(Q, Part); 3] = [
        (Q::PlatformErrorX, |p| p.x),
        (Q::PlatformErrorY, |p| p.y),
        (Q::PlatformErrorPhi, |p| p.phi),
    ];
    for (quantity, part) in parts {
        let error = (0..n)
            .map(|k| part(&samples.motions[k].pose) - part(&snapshots[k].platform.pose))
            .collect();
        table.push(Column::of(quantity), error);
    }
    table
}

/// `actuators.csv` of an actuated model: per slider the force command and the force on the
/// slider, then the actuator's own signals (a motor's torque, speed and saturation, 0/1).
pub(crate) fn actuators_of_model(snapshots: &[MachineSnapshot]) -> Table {
    let t: Vec<f64> = snapshots.iter().map(|s| s.t).collect();
    let mut table = Table::new("actuators", &t);
    for i in 0..3 {
        let state = |s: &MachineSnapshot| s.actuators.map(|a| a[i]).unwrap_or_default();
        table.push(
            Column::link(Q::ForceCommand, i),
            snapshots.iter().map(|s| state(s).command).collect(),
        );
        table.push(
            Column::link(Q::ActuatorForce, i),
            snapshots.iter().map(|s| state(s).output.force).collect(),
        );
        // The actuator's own signals (a motor's torque, speed and saturation), where every
        // snapshot has them.
        let signals = snapshots
            .first()
            .map_or(&[][..], |s| state(s).output.signals);
        for (k, signal) in signals.iter().enumerate() {
            let values: Option<Vec<f64>> = snapshots
                .iter()
                .map(|s| {
                    let output = state(s).output;
                    (output.signals.get(k) == Some(signal)).then_some(output.values[k])
                })
                .collect();
            if let Some(values) = values {
                table.push(Column::link(signal_quantity(signal), i), values);
            }
        }
    }
    table
}

/// The column quantity of an actuator's signal: its own name and units.
fn signal_quantity(signal: &ActuatorSignal) -> Q {
    Q::Named(NamedQuantity::new(
        signal.name,
        signal.header_unit,
        signal.symbol,
        signal.unit,
    ))
}

/// `actuators.csv` of a model whose sliders are prescribed: what the actuators must deliver
/// along the commanded rigid motion (the force is its own command; a motor's torque and
/// speed from [`flexprr_control::Actuator::required`], saturated where the torque is beyond
/// the peak).
pub(crate) fn actuators_required(samples: &Samples, required: &Required) -> Table {
    let mut table = Table::new("actuators", &samples.t);
    for i in 0..3 {
        let force = &required.force[i];
        table.push(Column::link(Q::ForceCommand, i), force.clone());
        table.push(Column::link(Q::ActuatorForce, i), force.clone());
        if let Some((torque, speed)) = &required.motor {
            table.push(
                Column::link(signal_quantity(&MOTOR_SIGNALS[0]), i),
                torque[i].clone(),
            );
            table.push(
                Column::link(signal_quantity(&MOTOR_SIGNALS[1]), i),
                speed[i].clone(),
            );
            let peak = required.peak_torque.unwrap_or(f64::INFINITY);
            let saturated = torque[i]
                .iter()
                .map(|tau| f64::from(u8::from(tau.abs() > peak)))
                .collect();
            table.push(
                Column::link(signal_quantity(&MOTOR_SIGNALS[2]), i),
                saturated,
            );
        }
    }
    table
}
