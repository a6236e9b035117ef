//! Work-precision rows of well-known Rust ODE crates on flexprr's modal system.
//!
//! The same `ModalSystem` (the same right-hand side, the same scene, the same output times)
//! is solved by `ode_solvers`' `Dopri5` (Dormand & Prince 5(4), Hairer's DOPRI5) and `Dop853`
//! (Dormand & Prince 8(5,3), Hairer's DOP853) over the tolerance ladder, timed and compared
//! with the reference exactly as `flexprr work-precision` does (`flexprr_bench::work_precision`),
//! and the rows are written in the `work_precision.csv` format for `--peers`.
//!
//! ```text
//! peers <scene.toml> --out <peers.csv> [--reference <reference.csv>] [--write-reference <file>]
//!       [--tolerances 1e-3,1e-4,...] [--repeats 7] [--warmup 2]
//! ```

use std::cell::RefCell;
use std::path::PathBuf;
use std::process::ExitCode;

use flexprr_bench::work_precision::{
    DEFAULT_TOLERANCES, Reference, WorkPrecisionConfig, WorkPrecisionRow, csv_text, time_runs,
};
use flexprr_dynamics::SceneModel;
use flexprr_scene::Scene;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, Dyn, OVector};
use ode_solvers::{Dop853, Dopri5, OutputType, System};

/// The scene's model (the one `flexprr run` builds) behind `ode_solvers`' `&self` interface
/// (the flexprr system keeps work counters, hence `&mut self`).
struct Modal<'a> {
    system: &'a RefCell<Box<dyn SceneModel>>,
}

impl<D: Dim> System<f64, OVector<f64, D>> for Modal<'_>
where
    DefaultAllocator: Allocator<D>,
{
    fn system(&self, t: f64, y: &OVector<f64, D>, dy: &mut OVector<f64, D>) {
        self.system
            .borrow_mut()
            .rhs(t, y.as_slice(), dy.as_mut_slice());
    }
}

/// The two methods of `ode_solvers` that take tolerances.
#[derive(Debug, Clone, Copy)]
enum Peer {
    Dopri5,
    Dop853,
}

impl Peer {
    fn name(self) -> &'static str {
        match self {
            Peer::Dopri5 => "dopri5",
            Peer::Dop853 => "dop853",
        }
    }
}

/// One solve: states at the output times (row by row) and `(rhs, accepted, rejected)`.
type Outcome = (Vec<f64>, (usize, usize, usize));

fn solve<D: Dim>(
    peer: Peer,
    system: &RefCell<Box<dyn SceneModel>>,
    dim: D,
    t_out: &[f64],
    rtol: f64,
    atol: f64,
) -> Result<Outcome, String>
where
    DefaultAllocator: Allocator<D>,
    OVector<f64, D>: std::ops::Mul<f64, Output = OVector<f64, D>>,
{
    let n = dim.value();
    let start = system.borrow().initial_state();
    let y0 = OVector::<f64, D>::from_iterator_generic(dim, Const::<1>, start.into_iter());
    let (t0, t_end) = (t_out[0], t_out[t_out.len() - 1]);
    let dt = t_out[1] - t_out[0];
    let f = Modal { system };
    let (stats, x, y) = match peer {
        Peer::Dopri5 => {
            let mut s = Dopri5::new(f, t0, t_end, dt, y0, rtol, atol);
            let stats = s.integrate().map_err(|e| e.to_string())?;
            (stats, s.x_out().clone(), s.y_out().clone())
        }
        Peer::Dop853 => {
            // Hairer's defaults (safety 0.9, beta 0, step factors 1/3..6, no step limit),
            // but no stiffness test: on this oscillatory system DOP853's test (every 1000
            // steps) reports stiffness and stops the run.
            let mut s = Dop853::from_param(
                f,
                t0,
                t_end,
                dt,
                y0,
                rtol,
                atol,
                0.9,
                0.0,
                0.333,
                6.0,
                t_end - t0,
                0.0,
                10_000_000,
                u32::MAX,
                OutputType::Dense,
            );
            let stats = s.integrate().map_err(|e| e.to_string())?;
            (stats, s.x_out().clone(), s.y_out().clone())
        }
    };
    if x.len() != t_out.len() {
        return Err(format!(
            "{} returned {} output times, the scene has {}",
            peer.name(),
            x.len(),
            t_out.len()
        ));
    }
    if let Some((k, (a, b))) = x
        .iter()
        .zip(t_out)
        .enumerate()
        .find(|(_, (a, b))| (*a - *b).abs() > 1e-9 * dt)
    {
        return Err(format!(
            "{} output {k} at t = {a} s, the scene's is {b} s",
            peer.name()
        ));
    }
    let mut states = Vec::with_capacity(n * y.len());
    for row in &y {
        states.extend_from_slice(row.as_slice());
    }
    Ok((
        states,
        (
            stats.num_eval as usize,
            stats.accepted_steps as usize,
            stats.rejected_steps as usize,
        ),
    ))
}

struct Args {
    scene: PathBuf,
    out: PathBuf,
    reference: Option<PathBuf>,
    write_reference: Option<PathBuf>,
    tolerances: Vec<f64>,
    repeats: usize,
    warmup: usize,
}

fn parse_args() -> Result<Args, String> {
    let mut args = std::env::args().skip(1);
    let mut scene = None;
    let mut out = None;
    let mut reference = None;
    let mut write_reference = None;
    let mut tolerances = DEFAULT_TOLERANCES.to_vec();
    let mut repeats = 7;
    let mut warmup = 2;
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--out" => out = Some(PathBuf::from(value("--out")?)),
            "--reference" => reference = Some(PathBuf::from(value("--reference")?)),
            "--write-reference" => {
                write_reference = Some(PathBuf::from(value("--write-reference")?));
            }
            "--tolerances" => {
                tolerances = value("--tolerances")?
                    .split(',')
                    .map(|s| {
                        s.trim()
                            .parse::<f64>()
                            .map_err(|_| format!("--tolerances: {s:?} is not a number"))
                    })
                    .collect::<Result<_, _>>()?;
            }
            "--repeats" => {
                let v = value("--repeats")?;
                repeats = v
                    .parse()
                    .map_err(|_| format!("--repeats: {v:?} is not a count"))?;
            }
            "--warmup" => {
                let v = value("--warmup")?;
                warmup = v
                    .parse()
                    .map_err(|_| format!("--warmup: {v:?} is not a count"))?;
            }
            other if other.starts_with("--") => return Err(format!("unknown option {other}")),
            other => scene = Some(PathBuf::from(other)),
        }
    }
    Ok(Args {
        scene: scene.ok_or("missing <scene.toml>")?,
        out: out.ok_or("missing --out <peers.csv>")?,
        reference,
        write_reference,
        tolerances,
        repeats,
        warmup,
    })
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    let scene = Scene::load(&args.scene).map_err(|e| e.to_string())?;
    let config = WorkPrecisionConfig {
        tolerances: args.tolerances.clone(),
        repeats: args.repeats,
        warmup: args.warmup,
        ..WorkPrecisionConfig::default()
    };
    config.validate().map_err(|e| e.to_string())?;
    let reference = match &args.reference {
        Some(path) => Reference::read_csv(path).map_err(|e| e.to_string())?,
        None => Reference::compute(&scene, &config).map_err(|e| e.to_string())?,
    };
    if let Some(path) = &args.write_reference {
        reference.write_csv(path).map_err(|e| e.to_string())?;
    }
    let system = RefCell::new(scene.build_model().map_err(|e| e.to_string())?);
    let dim = system.borrow().dim();
    let t_out = &scene.output_times;
    if t_out.len() < 2 || reference.t.len() != t_out.len() {
        return Err(format!(
            "the reference has {} output times, the scene {}",
            reference.t.len(),
            t_out.len()
        ));
    }
    let mut rows = Vec::new();
    for peer in [Peer::Dopri5, Peer::Dop853] {
        for &rtol in &config.tolerances {
            let atol = reference.atol(rtol);
            // A fixed-size state (stack vectors) for the paper's 3 x 3 modes, the crate's
            // fastest form; any other size runs on heap vectors.
            let timed = time_runs(config.warmup, config.repeats, || match dim {
                18 => solve(peer, &system, Const::<18>, t_out, rtol, atol),
                _ => solve(peer, &system, Dyn(dim), t_out, rtol, atol),
            });
            let ((states, (rhs, accepted, rejected)), timing) = match timed {
                Ok(ok) => ok,
                Err(e) => {
                    eprintln!("ode_solvers {} at rtol {rtol:e} failed: {e}", peer.name());
                    continue;
                }
            };
            let error = reference.errors(&states).map_err(|e| e.to_string())?;
            let row = WorkPrecisionRow {
                package: "ode_solvers".to_string(),
                method: peer.name().to_string(),
                rtol,
                atol,
                time_median_s: timing.median_s,
                time_min_s: timing.min_s,
                repeats: timing.repeats,
                accepted_steps: Some(accepted),
                rejected_steps: Some(rejected),
                rhs_evaluations: Some(rhs),
                jacobian_evaluations: Some(0),
                end_error: error.end,
                max_error: error.max,
                model: String::new(),
            };
            println!(
                "ode_solvers {:<7} {:>7.0e} {:>10.3} ms {:>8} steps {:>9} rhs {:>10.2e} {:>10.2e}",
                row.method,
                rtol,
                1e3 * row.time_median_s,
                accepted,
                rhs,
                row.end_error,
                row.max_error
            );
            let slow = row.time_median_s > 0.5;
            rows.push(row);
            if slow {
                // Tighter tolerances would take minutes (DOP853 here): stop this method.
                eprintln!(
                    "ode_solvers {}: stopping the ladder after rtol {rtol:e}",
                    peer.name()
                );
                break;
            }
        }
    }
    let text = csv_text(&rows).map_err(|e| e.to_string())?;
    std::fs::write(&args.out, text).map_err(|e| format!("{}: {e}", args.out.display()))?;
    println!("{} rows written to {}", rows.len(), args.out.display());
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
