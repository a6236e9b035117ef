//! The stress suite (`configs/stress/`, `docs/stability.md`) on short horizons: every stiff
//! or extreme scene is run by every integrator (the general ones, `abm`, `rk45` and `bdf`,
//! and, since every stress scene is a KED scene, the exponential `magnus4`, `magnus6` and
//! the automatic choice `auto`) and the outcome (solved with error X, solved but slow, failed
//! with a clear error) is asserted.
//!
//! Errors are measured against the same scene integrated by a *different* method at a much
//! tighter tolerance (rtol 1e-11); the buckling checks use Euler's load and the periodicity
//! of the motion. Explicit methods run under a `max_steps` cap so that a stiff scene makes
//! them stop quickly with a too-many-steps error instead of grinding on.
//!
//! The full-length runs are `flexprr run configs/stress/<scene>.toml`; the table of all
//! cases is printed by `cargo test --release --test stress -- --ignored --nocapture`.

use flexprr_bench::classify::{Attempt, Failure, Outcome, attempt};
use flexprr_bench::work_precision::builtin;
use flexprr_run::guard::DIVERGENCE_FRACTION;
use flexprr_run::{RunError, run};
use flexprr_scene::{
    FormulationChoice, MethodHandle, OutputKind, ScenarioError, Scene, SceneFile, parse_scene,
};

/// Every stress scene that is integrated (all but `near_singular_type2`, refused at load).
const INTEGRATED_SCENES: [&str; 12] = [
    "many_modes_r12",
    "many_modes_r12_damped",
    "many_modes_r20",
    "many_modes_r20_damped",
    "high_speed_f30",
    "high_speed_f35",
    "high_speed_f40",
    "long_horizon_f20",
    "tolerance_tight",
    "tolerance_loose",
    "max_step_tiny",
    "max_step_huge",
];

/// The general methods (any model).
const GENERAL: [&str; 3] = ["abm", "rk45", "bdf"];
/// The exponential methods and the automatic choice (`magnus6` on a KED model): models that
/// are linear in their state only.
const EXPONENTIAL: [&str; 3] = ["magnus4", "magnus6", "auto"];

fn is_exponential(method: &MethodHandle) -> bool {
    EXPONENTIAL.contains(&method.name())
}

/// The methods run on `s`: the general ones, and the exponential ones where the scene's
/// model is linear in its state (the KED model: every stress scene).
fn methods(s: &Scene) -> Vec<MethodHandle> {
    let mut model = s
        .build_model()
        .unwrap_or_else(|e| panic!("{}: {e}", s.name));
    let linear = model.linear_form().is_some();
    GENERAL
        .into_iter()
        .chain(EXPONENTIAL.into_iter().filter(|_| linear))
        .map(builtin)
        .collect()
}

/// Loads `configs/stress/<name>.toml`, applies `edit` (short horizon, caps) and validates it.
fn load(name: &str, edit: impl FnOnce(&mut SceneFile)) -> Result<Scene, ScenarioError> {
    let path = format!("{}/configs/stress/{name}.toml", WORKSPACE);
    let text = std::fs::read_to_string(&path).map_err(|source| ScenarioError::Io {
        path: path.clone(),
        source,
    })?;
    let mut raw = parse_scene(&path, &text)?;
    edit(&mut raw);
    Scene::from_file(&path, &text, raw, name)
}

fn scene(name: &str, edit: impl FnOnce(&mut SceneFile)) -> Scene {
    load(name, edit).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The method whose tight solution is the reference for `method`.
fn reference_method(method: &MethodHandle) -> MethodHandle {
    match method.name() {
        "abm" => builtin("rk45"),
        _ => builtin("abm"),
    }
}

/// The reference for `method`: the same scene integrated by another method (RK45 for ABM,
/// ABM for RK45 and BDF) at rtol 1e-11, atol 1e-15.
fn reference(name: &str, method: &MethodHandle, edit: impl Fn(&mut SceneFile)) -> Attempt {
    let other = reference_method(method);
    let tight = scene(name, |f| {
        edit(f);
        f.integrator.rtol = 1e-11;
        f.integrator.atol = 1e-15;
        f.integrator.max_steps = 50_000_000;
    });
    let a = attempt(&tight, &other);
    assert!(a.result.is_ok(), "{name}: reference failed: {:?}", a.result);
    a
}

fn describe(name: &str, a: &Attempt, outcome: &Outcome) -> String {
    let detail = match outcome {
        Outcome::Failed { reason } => reason.to_string(),
        other => match other.error() {
            Some(e) => format!(
                "error {e:.2e}, peak deflection {:.3e} m",
                a.max_deflection_m
            ),
            None => format!("peak deflection {:.3e} m", a.max_deflection_m),
        },
    };
    let method = if a.resolved == a.method.name() {
        a.method.name().to_string()
    } else {
        format!("{} ({})", a.method.name(), a.resolved)
    };
    let unit = if is_exponential(&a.method) {
        "coefficient evaluations"
    } else {
        "rhs"
    };
    format!(
        "{name} {method}: {} ({} steps, {} rejected, {} {unit}, stiffness at {:?}): {detail}",
        outcome.label(),
        a.stats.accepted_steps,
        a.stats.rejected_steps,
        a.stats.rhs_evaluations,
        a.stats.stiffness_detected_at,
    )
}

/// Runs every method on the scene and classifies each against its reference, with a work
/// budget of `slow_factor` times the cheapest successful method of the same kind (the
/// general methods count right-hand sides, the exponential ones coefficient evaluations: not
/// the same unit, so they are not compared with each other; docs/performance.md compares
/// them by wall time).
fn classify_all(
    name: &str,
    edit: impl Fn(&mut SceneFile) + Copy,
    slow_factor: usize,
) -> Vec<(Attempt, Outcome)> {
    let s = scene(name, edit);
    let attempts: Vec<Attempt> = methods(&s).iter().map(|m| attempt(&s, m)).collect();
    let cheapest = |exponential: bool| {
        attempts
            .iter()
            .filter(|a| a.result.is_ok() && is_exponential(&a.method) == exponential)
            .map(Attempt::rhs_evaluations)
            .min()
    };
    let cheapest = [cheapest(false), cheapest(true)];
    // One reference per other method, computed only when needed.
    let mut references: Vec<(MethodHandle, Attempt)> = Vec::new();
    attempts
        .into_iter()
        .map(|a| {
            let outcome = if a.result.is_ok() {
                let other = reference_method(&a.method);
                if !references.iter().any(|(m, _)| *m == other) {
                    references.push((other.clone(), reference(name, &a.method, edit)));
                }
                let r = &references
                    .iter()
                    .find(|(m, _)| *m == other)
                    .expect("added")
                    .1;
                let budget = cheapest[usize::from(is_exponential(&a.method))]
                    .map(|c| c.saturating_mul(slow_factor));
                a.classify(r.result.as_ref().ok(), budget)
            } else {
                a.classify(None, None)
            };
            println!("{}", describe(name, &a, &outcome));
            (a, outcome)
        })
        .collect()
}

/// Every integrated stress scene is a KED scene, so the suite runs the exponential methods
/// and `auto` on all of them, and a scene naming `auto` runs `magnus6`, the registry's choice
/// for a model linear in its state.
#[test]
fn every_stress_scene_runs_the_exponential_methods() {
    for name in INTEGRATED_SCENES {
        let s = scene(name, |f| f.integrator.method = "auto".to_string());
        assert_eq!(s.method.name(), "magnus6", "{name}");
        let model = s.build_model().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(model.kind(), "ked", "{name}");
        let all = methods(&s);
        let names: Vec<&str> = all.iter().map(MethodHandle::name).collect();
        assert_eq!(names, [GENERAL, EXPONENTIAL].concat(), "{name}");
    }
}

/// The classification resolves a method for the scene's model as a scene does: on the
/// coupled model (nonlinear in its state) `auto` runs `abm` and solves, and `magnus6` fails
/// with the scene's own refusal, naming what to use instead.
#[test]
fn classification_resolves_methods_like_a_scene() {
    let coupled = scene("max_step_huge", |f| {
        f.model.coupling = "coupled".to_string();
        f.time.end = 0.002;
    });
    let a = attempt(&coupled, &builtin("auto"));
    assert_eq!(a.resolved, "abm");
    assert!(a.result.is_ok(), "{:?}", a.result);
    let m = attempt(&coupled, &builtin("magnus6"));
    assert_eq!(m.resolved, "magnus6");
    match &m.result {
        Err(failure @ Failure::Method { .. }) => {
            let message = failure.to_string();
            assert!(
                message.contains("needs a linear (KED) model") && message.contains("use abm"),
                "{message}"
            );
        }
        other => panic!("magnus6 on the coupled model: {other:?}"),
    }
    let ked = scene("max_step_huge", |f| f.time.end = 0.002);
    assert_eq!(attempt(&ked, &builtin("auto")).resolved, "magnus6");
}

/// Many modes (r = 12 and 20 per link): an explicit method solves the scene accurately or
/// reports stiffness or stops at its step cap; nothing else. The exponential methods solve
/// it, within the budget of their kind, to the same accuracy, in fewer steps than ABM (their
/// step is set by how fast the coefficients vary, not by the highest mode).
#[test]
fn many_modes_explicit_methods_solve_or_report_stiffness() {
    for name in [
        "many_modes_r12",
        "many_modes_r12_damped",
        "many_modes_r20",
        "many_modes_r20_damped",
    ] {
        let short = |f: &mut SceneFile| {
            f.time.end = 0.01;
            f.integrator.max_steps = 60_000;
        };
        let results = classify_all(name, short, 3);
        let abm_steps = results
            .iter()
            .find(|(a, _)| a.method.name() == "abm")
            .map(|(a, _)| a.stats.accepted_steps)
            .expect("abm ran");
        for (a, outcome) in results {
            if a.method.name() == "bdf" {
                continue;
            }
            if is_exponential(&a.method) {
                let Outcome::Solved { error, .. } = outcome else {
                    panic!("{name} {}: {outcome:?}", a.method.name());
                };
                let error = error.expect("a reference");
                assert!(
                    error < 1e-3,
                    "{name} {}: error {error:e} at rtol 1e-6",
                    a.method.name()
                );
                assert!(
                    a.stats.accepted_steps < abm_steps,
                    "{name} {}: {} steps, abm {abm_steps}",
                    a.method.name(),
                    a.stats.accepted_steps
                );
                continue;
            }
            match &outcome {
                Outcome::Solved { error, .. } | Outcome::SolvedSlow { error, .. } => {
                    let error = error.expect("a reference");
                    assert!(
                        error < 1e-3,
                        "{name} {}: error {error:e} at rtol 1e-6",
                        a.method.name()
                    );
                }
                Outcome::Failed { reason } => assert!(
                    matches!(
                        reason,
                        Failure::Integrator {
                            error: flexprr_integrators::IntegratorError::TooManySteps { .. }
                                | flexprr_integrators::IntegratorError::Stiff { .. },
                            ..
                        }
                    ) || a.stats.stiffness_detected_at.is_some(),
                    "{name} {}: unexpected failure {reason}",
                    a.method.name()
                ),
            }
        }
    }
}

/// With modal damping the high modes die out and the problem is stiff: BDF solves it
/// accurately with fewer right-hand-side evaluations than either explicit method (the
/// exponential methods, which count coefficient evaluations, are checked for accuracy).
#[test]
fn many_modes_damped_bdf_is_efficient() {
    for name in ["many_modes_r12_damped", "many_modes_r20_damped"] {
        let short = |f: &mut SceneFile| {
            f.time.end = 0.02;
            f.integrator.atol = 1e-9;
            f.integrator.max_steps = 200_000;
        };
        let results = classify_all(name, short, 2);
        let bdf = results
            .iter()
            .find(|(a, _)| a.method.name() == "bdf")
            .expect("bdf ran");
        for (a, outcome) in results
            .iter()
            .filter(|(a, _)| a.method.name() == "bdf" || is_exponential(&a.method))
        {
            match outcome {
                Outcome::Solved { error, .. } => {
                    let error = error.expect("a reference");
                    assert!(error < 1e-3, "{name} {}: error {error:e}", a.method.name());
                }
                other => panic!("{name} {}: {other:?}", a.method.name()),
            }
        }
        for (a, _) in results
            .iter()
            .filter(|(a, _)| matches!(a.method.name(), "abm" | "rk45"))
        {
            assert!(
                bdf.0.rhs_evaluations() < a.rhs_evaluations(),
                "{name}: bdf used {} rhs evaluations, {} used {}",
                bdf.0.rhs_evaluations(),
                a.method.name(),
                a.rhs_evaluations()
            );
        }
    }
}

/// Euler's load of the stress scenes' links, `pi^2 EI / l^2` (E = 7.3e10 Pa, 2 mm x 30 mm).
fn euler_load() -> f64 {
    let (e, t, h, l) = (7.3e10, 0.002, 0.03, 0.2);
    std::f64::consts::PI.powi(2) * e * (h * t * t * t / 12.0) / (l * l)
}

/// High speed, frequencies only over 0.2 s with the paper's formulation (no softening): every
/// sample at which a link's lowest `omega^2` is non-positive has a compression above Euler's
/// load at one end (for sine modes `kf_11 = P_cr g_11` and `P(x)` is concave, so a link
/// whose compression stays below `P_cr` everywhere cannot buckle); the intervals repeat with
/// the period of the motion; 30 Hz does not buckle, 35 and 40 Hz do.
#[test]
fn high_speed_buckling_intervals_follow_euler_load_and_period() {
    let p_cr = euler_load();
    for (f, expect_buckling) in [(30, false), (35, true), (40, true)] {
        let s = scene(&format!("high_speed_f{f}"), |file| {
            file.model.formulation = FormulationChoice::Paper;
            file.output.requests = vec![OutputKind::Frequencies];
        });
        let result = run(&s, &mut |_| {}).expect("frequencies only");
        let hist = result.frequencies.expect("requested");
        assert_eq!(!hist.buckling.is_empty(), expect_buckling, "f = {f} Hz");
        for link in 0..3 {
            for k in 0..hist.t.len() {
                let lowest = hist.omega_squared[link]
                    .iter()
                    .map(|series| series[k])
                    .fold(f64::INFINITY, f64::min);
                let (pb, pc) = hist.end_forces[link][k];
                if lowest <= 0.0 {
                    assert!(
                        -pb.min(pc) > p_cr,
                        "f = {f} Hz link {} t = {}: buckled with compression {} N < P_cr = {p_cr} N",
                        link + 1,
                        hist.t[k],
                        -pb.min(pc)
                    );
                }
            }
            let intervals: Vec<_> = hist.buckling.iter().filter(|b| b.link == link).collect();
            let period = 1.0 / f64::from(f);
            for pair in intervals.windows(2) {
                // Both ends interior to the sampled span: starts one period apart.
                if pair[0].t_start > 0.0 && pair[1].t_end < 0.2 {
                    let gap = pair[1].t_start - pair[0].t_start;
                    assert!(
                        (gap - period).abs() < 2e-4,
                        "f = {f} Hz link {}: intervals {gap} s apart, period {period} s",
                        link + 1
                    );
                }
            }
        }
    }
}

/// High speed, integrated: the growth is bounded by the small-deflection limit or the run
/// stops with a clear divergence error; every method (general and exponential) agrees on
/// when (to 1 %).
#[test]
fn high_speed_integration_is_bounded_or_diverges_clearly() {
    for f in [30, 35, 40] {
        let name = format!("high_speed_f{f}");
        let s = scene(&name, |file| {
            file.time.end = 0.03;
            file.integrator.max_steps = 200_000;
        });
        let limit = DIVERGENCE_FRACTION * 0.2;
        let mut diverged_at = Vec::new();
        let all = methods(&s);
        for m in &all {
            let a = attempt(&s, m);
            println!("{}", describe(&name, &a, &a.classify(None, None)));
            match &a.result {
                Ok(sol) => {
                    assert!(a.max_deflection_m <= limit);
                    assert!(sol.states.iter().all(|v| v.is_finite()));
                }
                Err(Failure::Diverged {
                    t,
                    deflection_m,
                    limit_m,
                    ..
                }) => {
                    assert!(deflection_m.abs() > *limit_m && deflection_m.is_finite());
                    diverged_at.push(*t);
                }
                Err(other) => panic!("{name} {}: unclear failure {other}", m.name()),
            }
        }
        if let (Some(lo), Some(hi)) = (
            diverged_at.iter().copied().reduce(f64::min),
            diverged_at.iter().copied().reduce(f64::max),
        ) {
            assert_eq!(diverged_at.len(), all.len(), "{name}: the methods disagree");
            assert!(
                (hi - lo) / lo < 0.01,
                "{name}: divergence times {diverged_at:?}"
            );
        }
    }
}

/// High speed over the full 0.2 s with a loose limit (half the link length, far outside the
/// linear model's range, to tell bounded from unbounded growth): at 30 Hz, where no link
/// buckles, the deflection stays bounded (about 50 mm) and every method (general and
/// exponential) agrees on its peak to 1 %; at 35 and 40 Hz every method stops with a
/// divergence error, and not before
/// the first buckling interval found by the frequency analysis starts (a linear
/// time-varying system can only grow exponentially where its stiffness is indefinite): the
/// link that diverges is one that has started buckling.
#[test]
fn high_speed_growth_bounded_without_buckling_divergent_with_it() {
    for f in [30, 35, 40] {
        let name = format!("high_speed_f{f}");
        let s = scene(&name, |file| file.integrator.max_steps = 200_000);
        let frequencies = scene(&name, |file| {
            file.output.requests = vec![OutputKind::Frequencies];
        });
        let hist = run(&frequencies, &mut |_| {})
            .expect("frequencies only")
            .frequencies
            .expect("requested");
        let first_buckling = hist.buckling.iter().map(|b| b.t_start).reduce(f64::min);
        let mut peaks = Vec::new();
        for m in methods(&s) {
            let a = attempt(&s, &m);
            println!("{}", describe(&name, &a, &a.classify(None, None)));
            match (&a.result, first_buckling) {
                (Ok(sol), None) => {
                    assert!(sol.states.iter().all(|v| v.is_finite()));
                    peaks.push(a.max_deflection_m);
                }
                (Err(Failure::Diverged { t, link, .. }), Some(_)) => assert!(
                    hist.buckling
                        .iter()
                        .any(|b| b.link == *link && b.t_start <= *t),
                    "{name} {}: link {} diverged at {t} s before it buckles",
                    m.name(),
                    link + 1
                ),
                (other, onset) => panic!(
                    "{name} {}: {other:?} with first buckling at {onset:?}",
                    m.name()
                ),
            }
        }
        if let (Some(lo), Some(hi)) = (
            peaks.iter().copied().reduce(f64::min),
            peaks.iter().copied().reduce(f64::max),
        ) {
            assert!(hi < 0.1 && (hi - lo) / lo < 0.01, "{name}: peaks {peaks:?}");
        }
    }
}

/// Inside a buckling interval (the lowest `omega^2` of a link negative, where the exponential
/// methods switch to cosh/sinh): at 35 and 40 Hz, integrated up to just before the
/// divergence, every method agrees with a reference by a different method at rtol 1e-11 to
/// 1e-4 relative, and the link that grows is one the frequency analysis finds buckled.
#[test]
fn buckling_intervals_are_integrated_accurately_by_every_method() {
    // (scene, end of the span: inside the first buckling interval, before the 50 % limit)
    for (name, end) in [("high_speed_f35", 0.025), ("high_speed_f40", 0.0155)] {
        let span = |file: &mut SceneFile| {
            file.time.end = end;
            file.integrator.max_steps = 200_000;
        };
        let frequencies = scene(name, |file| {
            span(file);
            file.output.requests = vec![OutputKind::Frequencies];
        });
        let hist = run(&frequencies, &mut |_| {})
            .expect("frequencies only")
            .frequencies
            .expect("requested");
        let results = classify_all(name, span, usize::MAX);
        for (a, outcome) in &results {
            let error = outcome
                .error()
                .unwrap_or_else(|| panic!("{name} {}: {outcome:?}", a.method.name()));
            assert!(error < 1e-4, "{name} {}: error {error:e}", a.method.name());
        }
        // The growth happens on a buckled link: the link deflected most at the end of the
        // span (far beyond the 20 Hz response, about 3 mm) has been buckled for at least
        // 2 ms by then.
        let (a, _) = results
            .iter()
            .find(|(a, _)| a.method.name() == "magnus6")
            .expect("magnus6 ran");
        assert!(
            a.max_deflection_m > 0.01,
            "{name}: peak {}",
            a.max_deflection_m
        );
        let sol = a.result.as_ref().expect("solved");
        let y = sol.y(sol.len() - 1);
        let model = frequencies.build_model().expect("model");
        let t_end = sol.t[sol.len() - 1];
        let w: Vec<f64> = (0..3)
            .map(|l| {
                model
                    .deflection(t_end, l, 0.5, y)
                    .expect("deflection")
                    .abs()
            })
            .collect();
        let largest = (0..3)
            .max_by(|&i, &j| w[i].total_cmp(&w[j]))
            .expect("three links");
        assert!(
            hist.buckling
                .iter()
                .any(|b| b.link == largest && b.t_start < end - 2e-3),
            "{name}: link {} deflected most ({w:?} m) but is not buckled: {:?}",
            largest + 1,
            hist.buckling
        );
    }
}

/// A run and the stress classification share one stepping loop and one divergence guard:
/// at 40 Hz `flexprr run` stops with the divergence of the same link at the same accepted
/// step as `attempt`, keeping its outputs up to there; the bounded 30 Hz run passes both.
#[test]
fn run_and_classification_share_the_divergence_guard() {
    let check = |name: &str| {
        let s = scene(name, |_| {});
        (run(&s, &mut |_| {}), attempt(&s, &s.method))
    };
    let (run_40, stepwise) = check("high_speed_f40");
    let Err(Failure::Diverged {
        link, t: t_step, ..
    }) = &stepwise.result
    else {
        panic!("40 Hz stepwise: {:?}", stepwise.result);
    };
    let failure = run_40.expect_err("40 Hz must diverge");
    let RunError::Diverged { link: l, t, .. } = failure.error else {
        panic!("40 Hz run: {}", failure.error);
    };
    assert_eq!(l, *link);
    assert!((t - t_step).abs() <= 1e-12, "{t} vs {t_step}");
    // The outputs are kept up to the last output time before the divergence.
    let deflections = failure.partial.table("deflections").expect("kept");
    let last = *deflections.time().last().expect("rows");
    assert!(
        last <= t && last > t - 2e-4,
        "last kept {last} vs divergence {t}"
    );
    let (run_30, stepwise) = check("high_speed_f30");
    assert!(
        run_30.is_ok() && stepwise.result.is_ok(),
        "{:?}",
        run_30.err().map(|f| f.to_string())
    );
}

/// A move into the home pose (platform at the origin, phi = 0: the three link lines meet at
/// the platform centre, a type-II singularity) is refused when the scene is loaded, before
/// anything is integrated, with the time and the measure.
#[test]
fn near_singular_trajectory_is_refused_before_integrating() {
    let err = load("near_singular_type2", |_| {}).expect_err("must be refused");
    let message = err.to_string();
    println!("{message}");
    assert!(err.is_input(), "{message}");
    assert!(message.contains("type-II"), "{message}");
    assert!(message.contains("measure"), "{message}");
    // The reported time lies inside the move (0 to 0.1 s) and before its end, where the pose
    // is exactly singular.
    let t: f64 = message
        .split("at t = ")
        .nth(1)
        .and_then(|rest| rest.split(" s").next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no time in: {message}"));
    assert!(t > 0.0 && t < 0.1, "{message}");
}

/// Relative difference of the peak mid-link deflections of link 1 over the last revolution.
fn last_revolution_amplitude_drift(a: &Attempt, r: &Attempt, period: f64) -> f64 {
    let (sol, reference) = (
        a.result.as_ref().expect("solved"),
        r.result.as_ref().expect("solved"),
    );
    let t_end = sol.t[sol.len() - 1];
    let peak = |s: &flexprr_integrators::Solution| {
        (0..s.len())
            .filter(|&k| s.t[k] >= t_end - period)
            .map(|k| {
                // Sine basis: w(1/2) = eta_1 - eta_3 (+ ...), mode j at sin(j pi / 2).
                let y = s.y(k);
                (0..3)
                    .map(|j| y[j] * ((j + 1) as f64 * std::f64::consts::FRAC_PI_2).sin())
                    .sum::<f64>()
                    .abs()
            })
            .fold(0.0, f64::max)
    };
    peak(sol) / peak(reference) - 1.0
}

/// Long horizon (1 s = 20 revolutions here; 10 s in the full scene): every method stays
/// within its tolerance of the reference; amplitude drift over the last revolution is small.
#[test]
fn long_horizon_drift_is_small() {
    let short = |f: &mut SceneFile| {
        f.time.end = 1.0;
        f.time.output_step = Some(2e-4);
    };
    let s = scene("long_horizon_f20", short);
    for m in methods(&s) {
        let a = attempt(&s, &m);
        let r = reference("long_horizon_f20", &m, short);
        let outcome = a.classify(r.result.as_ref().ok(), None);
        println!("{}", describe("long_horizon_f20", &a, &outcome));
        let error = outcome.error().expect("solved with a reference");
        let drift = last_revolution_amplitude_drift(&a, &r, 0.05);
        println!("  amplitude drift over the last revolution {drift:.2e}");
        assert!(error < 1e-4, "{}: error {error:e}", m.name());
        assert!(drift.abs() < 1e-4, "{}: drift {drift:e}", m.name());
    }
}

/// rtol = 1e-14 (the tightest a scene accepts): every method solves, agreeing with the
/// reference to 1e-8; rtol = 1e-1: no NaN, no hang: solved or a clear divergence error.
#[test]
fn tolerance_extremes_finish_without_nan() {
    let short = |f: &mut SceneFile| f.time.end = 0.01;
    for (a, outcome) in classify_all("tolerance_tight", short, usize::MAX) {
        let error = outcome
            .error()
            .unwrap_or_else(|| panic!("{}: {outcome:?}", a.method.name()));
        assert!(error < 1e-8, "{}: error {error:e}", a.method.name());
    }
    let s = scene("tolerance_loose", |_| {});
    for m in methods(&s) {
        let a = attempt(&s, &m);
        println!(
            "{}",
            describe("tolerance_loose", &a, &a.classify(None, None))
        );
        match &a.result {
            Ok(sol) => assert!(sol.states.iter().all(|v| v.is_finite())),
            Err(Failure::Diverged { deflection_m, .. }) => assert!(deflection_m.is_finite()),
            Err(other) => panic!("tolerance_loose {}: {other}", m.name()),
        }
    }
}

/// A tiny max_step stops every method at its step cap with a clear error (no hang); a huge
/// max_step changes nothing: the error control alone limits the step.
#[test]
fn max_step_extremes() {
    let s = scene("max_step_tiny", |f| f.integrator.max_steps = 20_000);
    for m in methods(&s) {
        let a = attempt(&s, &m);
        match &a.result {
            Err(Failure::Integrator {
                error: flexprr_integrators::IntegratorError::TooManySteps { t, max_steps },
                ..
            }) => {
                assert_eq!(*max_steps, 20_000);
                // 20 000 steps of at most 1e-8 s.
                assert!(*t <= 20_000.0 * 1e-8 * (1.0 + 1e-9), "t = {t}");
            }
            other => panic!("max_step_tiny {}: {other:?}", m.name()),
        }
    }
    let short = |f: &mut SceneFile| f.time.end = 0.02;
    for (a, outcome) in classify_all("max_step_huge", short, usize::MAX) {
        let error = outcome
            .error()
            .unwrap_or_else(|| panic!("{}: {outcome:?}", a.method.name()));
        assert!(error < 1e-3, "{}: error {error:e}", a.method.name());
    }
}

/// The table of docs/stability.md: every stress scene at full length, every method.
/// `cargo test --release --test stress -- --ignored --nocapture` (a few minutes).
#[test]
#[ignore = "full-length survey for docs/stability.md"]
fn survey_full_length() {
    for name in INTEGRATED_SCENES {
        // STRESS_SCENES=name,name,... runs only those.
        if let Ok(only) = std::env::var("STRESS_SCENES") {
            if !only.split(',').any(|n| n == name) {
                continue;
            }
        }
        classify_all(name, |_| {}, 3);
    }
}

/// The workspace root: the tests read its configs and validation data.
const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
