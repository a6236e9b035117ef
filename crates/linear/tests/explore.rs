use std::sync::Arc;
use flexprr_control::{Actuator, IdealForce, Pid};
use flexprr_dynamics::{Actuation, CoupledOptions, CoupledSystem, ModalDamping, NonlinearOptions, NonlinearSystem, SceneModel, paper};
use flexprr_kinematics::{Line, Pose, Trajectory};
use flexprr_linear::{linearize, modes, Output};
use nalgebra::Vector3;

#[test]
fn explore() {
    for (x, y, phi) in [(0.0, 0.0, 45.0), (-0.1, 0.0, 45.0)] {
        let pose = Pose::new(x, y, f64::to_radians(phi));
        let traj: Arc<dyn Trajectory + Send + Sync> = Arc::new(Line::new(pose, Vector3::zeros(), 0.0).unwrap());
        for servo in [false, true] {
            for r in [3usize, 6] {
            let machine = Arc::new(paper::machine(r, paper::YOUNGS_MODULUS).unwrap());
            let mut m: Box<dyn SceneModel> = {
                let c = CoupledSystem::new(machine.clone(), traj.clone(), ModalDamping::none(), CoupledOptions::full()).unwrap();
                if servo {
                    let f: Arc<dyn Actuator> = Arc::new(IdealForce);
                    Box::new(c.with_actuation(Actuation { controller: Arc::new(Pid::pd(2e5, 0.0, true, 0.0).unwrap()), actuators: [f.clone(), f.clone(), f] }, 0.0).unwrap())
                } else { Box::new(c) }
            };
            let y0 = m.initial_state();
            let outs = vec![Output::Deflection { link: 0, xi: 0.5 }];
            let t0 = std::time::Instant::now();
            let lin = linearize(m.as_mut(), 0.0, &y0, &[], &outs).unwrap();
            let ms = modes(&lin).unwrap();
            let f: Vec<String> = ms.iter().take(12).map(|m| format!("{:.3}", m.frequency_hz)).collect();
            println!("pose ({x},{y},{phi}) servo {servo} r {r}: {:?} in {:?}", f, t0.elapsed());
            }
        }
        for servo in [false, true] {
        for ne in [16usize, 32] {
            let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
            let options = NonlinearOptions { elements: ne, ..NonlinearOptions::paper(paper::YOUNGS_MODULUS) };
            let mut nl = NonlinearSystem::new(machine, traj.clone(), options).unwrap();
            nl.start_at(0.0).unwrap();
            let mut m: Box<dyn SceneModel> = if servo {
                let f: Arc<dyn Actuator> = Arc::new(IdealForce);
                Box::new(nl.with_actuation(Actuation { controller: Arc::new(Pid::pd(2e5, 0.0, true, 0.0).unwrap()), actuators: [f.clone(), f.clone(), f] }, 0.0).unwrap())
            } else { Box::new(nl) };
            let y0 = m.initial_state();
            let t0 = std::time::Instant::now();
            let lin = linearize(m.as_mut(), 0.0, &y0, &[], &[Output::Deflection { link: 0, xi: 0.5 }]).unwrap();
            let ms = modes(&lin).unwrap();
            let f: Vec<String> = ms.iter().take(14).map(|m| format!("{:.3}", m.frequency_hz)).collect();
            println!("pose ({x},{y},{phi}) nonlinear {ne} servo {servo}: {:?} in {:?}", f, t0.elapsed());
        }
        }
    }
}
