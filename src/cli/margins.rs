//! `flexprr margins <scene.toml> [--pose X_M,Y_M,PHI_DEG] [--json]`: each slider loop broken
//! at its actuator (`actuator_command:I` in, `slider_command:I` out, the other two loops
//! closed), its gain and phase margins, crossover frequencies and sensitivity peak, on the
//! discrete model where the law is sampled (docs/control.md, "Loop margins").

use std::path::PathBuf;

use flexprr_linear::{Input, LoopMargins, Output, linearize, loop_margins};
use flexprr_linear_tools::linear::{OperatingPoint, operating_point};
use flexprr_linear_tools::machine_modes::start_pose;
use flexprr_scene::Scene;
use serde_json::json;

use super::Failure;

/// Arguments of `flexprr margins`.
#[derive(Debug, clap::Args)]
pub struct MarginsArgs {
    /// Scene file (TOML) with `[control]`.
    pub scene: PathBuf,
    /// The platform at rest at this pose: x (m), y (m), phi (deg). Default: the scene's
    /// start pose.
    #[arg(long, value_name = "X_M,Y_M,PHI_DEG", allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Print `{"loops": [...]}` (JSON) on standard output instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// A number for JSON: `null` when not finite (no crossing).
fn finite(x: f64) -> serde_json::Value {
    if x.is_finite() { json!(x) } else { json!(null) }
}

/// Runs `flexprr margins`.
///
/// # Errors
/// Bad input (exit 2): the scene, the pose, a scene without `[control]`; a failed analysis
/// (exit 1).
pub fn run(args: MarginsArgs) -> Result<(), Failure> {
    let scene = Scene::load_for_analysis(&args.scene).map_err(Failure::bad_input)?;
    if scene.controller.is_none() {
        return Err(Failure::bad_input(format!(
            "{}: margins need a control loop: the scene has no [control] table",
            args.scene.display()
        )));
    }
    let pose = match &args.pose {
        Some(p) => super::modes::parse_pose(p)?,
        None => start_pose(&scene),
    };
    let mut loops: Vec<(LoopMargins, f64)> = Vec::new();
    for i in 0..3 {
        let mut at = operating_point(&scene, OperatingPoint::Rest(pose))
            .map_err(|e| Failure::bad_input(format!("{}: {e}", args.scene.display())))?;
        let lin = linearize(
            at.model.as_mut(),
            at.t,
            &at.state,
            &[Input::ActuatorCommand(i)],
            &[Output::SliderCommand(i)],
        )
        .map_err(|e| Failure::run(format!("margins: slider {}: {e}", i + 1)))?;
        let m = loop_margins(&lin)
            .map_err(|e| Failure::run(format!("margins: slider {}: {e}", i + 1)))?;
        loops.push((m, lin.dt));
    }
    if args.json {
        let rows: Vec<_> = loops
            .iter()
            .enumerate()
            .map(|(i, (m, dt))| {
                json!({
                    "slider": i + 1,
                    "dt_s": dt,
                    "gain_margin": finite(m.gain_margin),
                    "gain_margin_db": finite(20.0 * m.gain_margin.log10()),
                    "phase_margin_deg": finite(m.phase_margin_deg),
                    "gain_crossover_hz": finite(m.gain_crossover_hz),
                    "phase_crossover_hz": finite(m.phase_crossover_hz),
                    "sensitivity_peak": m.sensitivity_peak,
                    "sensitivity_peak_hz": m.sensitivity_peak_hz,
                })
            })
            .collect();
        println!("{}", json!({ "loops": rows }));
        return Ok(());
    }
    let dt = loops[0].1;
    println!(
        "{}: each slider loop broken at its actuator, at ({:.4} m, {:.4} m, {:.2} deg), {}",
        args.scene.display(),
        pose.x,
        pose.y,
        pose.phi.to_degrees(),
        if dt > 0.0 {
            format!("discrete (period {dt} s)")
        } else {
            "continuous".to_string()
        }
    );
    println!(
        "slider  gain margin (dB)  phase crossover (Hz)  phase margin (deg)  gain crossover (Hz)  sensitivity peak  at (Hz)"
    );
    let show = |x: f64, digits: usize| {
        if x.is_finite() {
            format!("{x:.digits$}")
        } else {
            "none".to_string()
        }
    };
    for (i, (m, _)) in loops.iter().enumerate() {
        println!(
            "{:>6}  {:>16}  {:>20}  {:>18}  {:>19}  {:>16.3}  {:>7.1}",
            i + 1,
            show(20.0 * m.gain_margin.log10(), 2),
            show(m.phase_crossover_hz, 1),
            show(m.phase_margin_deg, 2),
            show(m.gain_crossover_hz, 1),
            m.sensitivity_peak,
            m.sensitivity_peak_hz
        );
    }
    Ok(())
}
