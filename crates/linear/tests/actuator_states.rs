//! The actuators' own states in the linear models (docs/linear.md): the models' `A` is
//! formed by differencing the right-hand side over the whole state, so an actuator's states
//! come in with their own rows and names. Checked with a force that follows its command with
//! a first-order lag, `F' = (F_c - F) / T` under a PD law `F_c = kp (rho_ref - rho) + kd
//! (rho_ref' - rho')`: the lag's row of `A` is `-1/T` on itself, `-kp/T` on its slider's
//! position and `-kd/T` on its rate, and nothing else.

use std::sync::Arc;

use flexprr_control::{Actuator, ActuatorOutput, ActuatorSignal, Pid};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, ModalDamping, NonlinearOptions, NonlinearSystem,
    SceneModel, paper,
};
use flexprr_kinematics::{Line, Pose, Trajectory};
use flexprr_linear::{Output, linearize};
use nalgebra::Vector3;

const LAGGED: [ActuatorSignal; 1] = [ActuatorSignal {
    name: "lagged_force",
    header_unit: "N",
    symbol: "F",
    unit: "N",
}];

/// A force following its command with a first-order lag of time constant `T` (s).
#[derive(Debug)]
struct Lagged(f64);

impl Actuator for Lagged {
    fn apply(&self, command: f64, _velocity: f64) -> ActuatorOutput {
        ActuatorOutput {
            force: command,
            ..ActuatorOutput::default()
        }
    }
    fn name(&self) -> &'static str {
        "lagged"
    }
    fn states(&self) -> usize {
        1
    }
    fn state_names(&self) -> &'static [ActuatorSignal] {
        &LAGGED
    }
    fn apply_with_states(
        &self,
        command: f64,
        _velocity: f64,
        _friction_velocity: Option<f64>,
        states: &[f64],
        rates: &mut [f64],
    ) -> ActuatorOutput {
        rates[0] = (command - states[0]) / self.0;
        ActuatorOutput {
            force: states[0],
            ..ActuatorOutput::default()
        }
    }
}

#[test]
fn an_actuators_lag_has_its_closed_form_row_in_a() {
    let (kp, kd, lag) = (2.0e5, 400.0, 1e-3);
    let actuator: Arc<dyn Actuator> = Arc::new(Lagged(lag));
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(kp, kd, false, 0.0).unwrap()),
        actuators: [actuator.clone(), actuator.clone(), actuator],
    };
    let rest: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(0.0, 0.0, 45f64.to_radians()),
            Vector3::zeros(),
            0.0,
        )
        .unwrap(),
    );
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let models: [Box<dyn SceneModel>; 2] = [
        Box::new(
            CoupledSystem::new(
                machine.clone(),
                rest.clone(),
                ModalDamping::none(),
                CoupledOptions::full(),
            )
            .unwrap()
            .with_actuation(actuation.clone(), 0.0)
            .unwrap(),
        ),
        Box::new(
            NonlinearSystem::new(
                machine,
                rest,
                NonlinearOptions {
                    elements: 4,
                    ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
                },
            )
            .unwrap()
            .with_actuation(actuation, 0.0)
            .unwrap(),
        ),
    ];
    for mut model in models {
        let y0 = model.initial_state();
        let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
        let index = |signal: &str| {
            lin.states
                .iter()
                .position(|s| s.signal == signal)
                .unwrap_or_else(|| panic!("{}: no state {signal}", model.kind()))
        };
        let n = lin.a.nrows();
        for i in 1..=3 {
            let row = index(&format!("lagged_force_{i}"));
            assert_eq!(
                lin.states[row].name,
                format!("lagged force of actuator {i} (N)")
            );
            let expected = [
                (row, -1.0 / lag),
                (index(&format!("rho_{i}")), -kp / lag),
                (index(&format!("rho_{i}_rate")), -kd / lag),
            ];
            for col in 0..n {
                let want = expected
                    .iter()
                    .find(|(c, _)| *c == col)
                    .map_or(0.0, |(_, v)| *v);
                let got = lin.a[(row, col)];
                assert!(
                    (got - want).abs() <= 1e-6 * want.abs().max(1.0 / lag),
                    "{}: A[{}, {}] = {got}, closed form {want}",
                    model.kind(),
                    lin.states[row].signal,
                    lin.states[col].signal
                );
            }
        }
    }
}
