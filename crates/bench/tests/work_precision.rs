//! Work-precision measurement on a short scene (the paper's machine on the 20 Hz circle for
//! 20 ms): the achieved error falls as the tolerance tightens, the reference agrees with its
//! check and with a third method, the error measure and the equal-error interpolation match
//! closed forms, and the CSV carries every column. On the 30 Hz scene: the mid-point
//! deflection measure against closed forms, the nonlinear model's reference against its
//! check and a tighter run, and models side by side flooring at their model error.

use flexprr_bench::work_precision::builtin;
use flexprr_bench::work_precision::{
    ErrorMeasure, ModelChoice, PACKAGE, Reference, WorkPrecisionConfig, WorkPrecisionRow, csv_text,
    default_reference, markdown_at_error, markdown_models, measure, midpoint_deflections, read_csv,
    time_at_error, work_precision,
};
use flexprr_integrators::{Bdf, Integrator, Options};
use flexprr_scene::Scene;

fn short_scene() -> Scene {
    let text = r#"
[links]
length = 0.2
modes = 3
material = { youngs_modulus = 7.3e10, density = 2770.0 }
section = { kind = "uniform", thickness = 0.002, height = 0.03 }

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 20.0
phi_deg = 45.0

[model]
formulation = "paper"

[integrator]
method = "abm"
rtol = 1e-8
atol = 1e-12

[time]
start = 0.0
end = 0.02
output_step = 1e-3

[output]
requests = ["modes"]
plots = false
"#;
    Scene::from_text("work_precision.toml", "work_precision", text).expect("valid scene")
}

/// The built-in model `name`.
fn model(name: &str) -> ModelChoice {
    ModelChoice::parse(name).unwrap_or_else(|| panic!("{name} is a built-in model"))
}

fn config() -> WorkPrecisionConfig {
    WorkPrecisionConfig {
        tolerances: vec![1e-4, 1e-6, 1e-8],
        warmup: 0,
        repeats: 1,
        ..WorkPrecisionConfig::default()
    }
}

#[test]
fn errors_fall_as_the_tolerance_tightens_and_the_reference_is_confirmed() {
    let scene = short_scene();
    let config = config();
    let result = work_precision(&scene, &config, &mut |_| {}).expect("measurement runs");
    assert!(result.failures.is_empty(), "{:?}", result.failures);
    assert_eq!(
        result.rows.len(),
        config.methods.len() * config.tolerances.len()
    );

    // The reference and its check (a different method family) agree far below the ladder.
    let reference = &result.reference;
    let agreement = reference.agreement.expect("the reference was checked");
    assert!(agreement.max < 1e-9, "agreement {agreement:?}");
    assert_ne!(reference.method, reference.check_method);

    // A third, independent method (implicit BDF at a tight tolerance) agrees with it too.
    let mut system = scene.build_model().expect("system");
    let y0 = system.initial_state();
    let opts = Options::default().rtol(1e-10).atol(reference.atol(1e-10));
    let bdf = Bdf::new(opts)
        .solve(system.as_mut(), 0.0, &y0, &scene.output_times)
        .expect("bdf solves");
    let third = reference.errors(&bdf.states).expect("same shape");
    assert!(
        third.max < 1e-7,
        "bdf at 1e-10 against the reference: {third:?}"
    );

    for method in ["abm", "rk45", "bdf"].map(builtin) {
        let rows: Vec<&WorkPrecisionRow> = result
            .rows
            .iter()
            .filter(|r| r.method == method.name())
            .collect();
        assert_eq!(rows.len(), 3, "{}", method.name());
        for pair in rows.windows(2) {
            let (loose, tight) = (pair[0], pair[1]);
            assert!(tight.rtol < loose.rtol);
            // Two decades of tolerance buy at least one decade of accuracy ...
            assert!(
                tight.max_error < 0.1 * loose.max_error,
                "{}: {:e} at rtol {:e} vs {:e} at rtol {:e}",
                method.name(),
                tight.max_error,
                tight.rtol,
                loose.max_error,
                loose.rtol
            );
            // ... and cost more right-hand-side evaluations.
            assert!(tight.rhs_evaluations > loose.rhs_evaluations);
        }
        for row in &rows {
            // The maximum over the output times includes the end time.
            assert!(row.end_error <= row.max_error);
            assert!(row.time_median_s > 0.0 && row.time_min_s <= row.time_median_s);
            // Tolerance proportionality: the global error stays within a few hundred
            // times the local tolerance on this short, smooth scene.
            assert!(row.max_error < 300.0 * row.rtol, "{row:?}");
        }
    }

    // The exponential methods: errors fall with the tolerance until the reference's own
    // accuracy (about 1e-10 here), and stay proportional to it.
    for method in ["magnus4", "magnus6", "auto"].map(builtin) {
        let rows: Vec<&WorkPrecisionRow> = result
            .rows
            .iter()
            .filter(|r| r.method == method.name())
            .collect();
        assert_eq!(rows.len(), 3, "{}", method.name());
        for pair in rows.windows(2) {
            let (loose, tight) = (pair[0], pair[1]);
            assert!(
                tight.max_error < 0.1 * loose.max_error || tight.max_error < 1e-9,
                "{}: {:e} at rtol {:e} vs {:e} at rtol {:e}",
                method.name(),
                tight.max_error,
                tight.rtol,
                loose.max_error,
                loose.rtol
            );
        }
        for row in &rows {
            assert!(row.end_error <= row.max_error);
            assert!(row.max_error < 300.0 * row.rtol, "{row:?}");
        }
    }
}

#[test]
fn the_error_measure_is_relative_to_each_block_size() {
    // Two modes; displacements of size 2, velocities of size 10.
    let t = vec![0.0, 1.0];
    let states = vec![
        0.0, 0.0, 0.0, 0.0, //
        2.0, -1.0, 10.0, 5.0,
    ];
    let reference = Reference::from_states(t, states.clone(), 2).expect("valid");
    assert!((reference.displacement_size - 2.0).abs() < 1e-15);
    assert!((reference.velocity_size - 10.0).abs() < 1e-15);
    assert!((reference.atol(1e-6) - 2e-6).abs() < 1e-21);

    // A displacement off by 1e-3 at t = 0 and a velocity off by 4e-3 at the end.
    let mut perturbed = states;
    perturbed[1] += 1e-3;
    perturbed[7] -= 4e-3;
    let error = reference.errors(&perturbed).expect("same shape");
    assert!((error.max - 5e-4).abs() < 1e-15, "{error:?}");
    assert!((error.end - 4e-4).abs() < 1e-15, "{error:?}");

    // Wrong shapes and zero solutions are rejected with a reason.
    assert!(reference.errors(&[0.0; 3]).is_err());
    assert!(Reference::from_states(vec![0.0], vec![0.0; 4], 2).is_err());
    assert!(Reference::from_states(vec![0.0], vec![1.0; 3], 2).is_err());
}

fn row(method: &str, rtol: f64, time: f64, error: f64) -> WorkPrecisionRow {
    WorkPrecisionRow {
        package: PACKAGE.to_string(),
        method: method.to_string(),
        rtol,
        atol: rtol * 1e-5,
        time_median_s: time,
        time_min_s: time,
        repeats: 1,
        accepted_steps: Some(10),
        rejected_steps: None,
        rhs_evaluations: Some(60),
        jacobian_evaluations: Some(0),
        end_error: error,
        max_error: error,
        model: String::new(),
    }
}

#[test]
fn equal_error_time_is_exact_on_a_power_law() {
    // A method of order 5: time = c * error^(-1/5). Log-log interpolation is exact.
    let time = |e: f64| 1e-3 * e.powf(-0.2);
    let rows: Vec<WorkPrecisionRow> = [1e-3, 1e-5, 1e-7, 1e-9]
        .into_iter()
        .map(|e| row("order5", e, time(e), e))
        .collect();
    let at = time_at_error(&rows, PACKAGE, "order5", 3e-6).expect("reached");
    assert!(
        (at / time(3e-6) - 1.0).abs() < 1e-12,
        "{at} vs {}",
        time(3e-6)
    );
    assert!(time_at_error(&rows, PACKAGE, "order5", 1e-12).is_none());
    assert!(time_at_error(&rows, PACKAGE, "absent", 1e-6).is_none());

    // A second series twice as slow shows as 2.0x in the comparison.
    let mut both = rows.clone();
    both.extend(rows.iter().map(|r| WorkPrecisionRow {
        package: "peer".to_string(),
        time_median_s: 2.0 * r.time_median_s,
        ..r.clone()
    }));
    let md = markdown_at_error(&both, 1e-6);
    assert!(
        md.contains("| peer | order5 |") && md.contains("| 2.0x |"),
        "{md}"
    );
}

#[test]
fn the_csv_has_every_column_and_reads_back() {
    let rows = vec![row("abm", 1e-6, 2e-3, 3e-6), row("rk45", 1e-6, 4e-3, 5e-6)];
    let text = csv_text(&rows).expect("serialises");
    let header = text.lines().next().expect("header");
    let expected = [
        "package",
        "method",
        "rtol",
        "atol",
        "time_median_s",
        "time_min_s",
        "repeats",
        "accepted_steps",
        "rejected_steps",
        "rhs_evaluations",
        "jacobian_evaluations",
        "end_error",
        "max_error",
        "model",
    ];
    assert_eq!(header.split(',').collect::<Vec<_>>(), expected);
    // A count a package does not report is an empty field.
    assert!(text.lines().nth(1).expect("row").contains(",10,,60,"));

    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("peers.csv");
    std::fs::write(&path, &text).expect("write");
    assert_eq!(read_csv(&path).expect("reads"), rows);

    // A row with a negative error is rejected, naming the file's line (the header is
    // line 1).
    let broken = text
        .replace("3e-6", "-3e-6")
        .replace("0.000003", "-0.000003");
    std::fs::write(&path, &broken).expect("write");
    let err = read_csv(&path).expect_err("negative error").to_string();
    assert!(err.contains("line 2") && err.contains("peers.csv"), "{err}");
    // A file without rows, or with a tolerance that is no tolerance, is refused: one line
    // naming the file and what is wrong.
    let header_only = format!("{}\n", text.lines().next().expect("header"));
    let row = text.lines().nth(1).expect("row");
    let nan_rtol = format!("{header_only}{}\n", row.replacen(",1e-6,", ",NaN,", 1));
    assert!(nan_rtol.contains(",NaN,"), "{nan_rtol}");
    for (contents, words) in [
        ("", "holds no rows"),
        (header_only.as_str(), "holds no rows"),
        (nan_rtol.as_str(), "rtol = NaN"),
    ] {
        std::fs::write(&path, contents).expect("write");
        let err = read_csv(&path).expect_err(words).to_string();
        assert!(
            err.contains(words) && err.contains("peers.csv") && err.lines().count() == 1,
            "{err}"
        );
    }
}

/// The paper scene at 30 Hz over `end` seconds, consistent formulation (every model can be
/// built from it), with `model` as its `[model]` table body.
fn scene_f30(model: &str, end: f64) -> Scene {
    let text = format!(
        r#"
[links]
length = 0.2
modes = 3
material = {{ youngs_modulus = 7.3e10, density = 2770.0 }}
section = {{ kind = "uniform", thickness = 0.002, height = 0.03 }}
basis = {{ kind = "sine" }}

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 30.0
phi_deg = 45.0

[model]
formulation = "consistent"
{model}

[integrator]
method = "abm"
rtol = 1e-8
atol = 1e-12

[time]
start = 0.0
end = {end}
output_step = 2e-4

[output]
requests = ["deflections"]
plots = false
"#
    );
    Scene::from_text("f30.toml", "f30", &text).expect("valid scene")
}

#[test]
fn the_deflection_error_of_a_run_is_zero_against_itself_and_the_perturbation_against_a_copy() {
    // A KED run: with three sine modes psi_j = sin(j pi xi), the mid-point deflection is
    // eta_1 - eta_3 (psi_2(1/2) = 0), a closed form independent of the model's own sum.
    let scene = scene_f30("", 0.004);
    let mut system = scene.build_model().expect("KED model");
    let y0 = system.initial_state();
    let options = Options::default().rtol(1e-9).atol(1e-13);
    let solution = builtin("abm")
        .solve(options, &mut system.as_mut(), &y0, &scene.output_times)
        .expect("solves");
    let w = midpoint_deflections(system.as_mut(), &solution).expect("deflections");
    assert_eq!(w.len(), 3 * solution.t.len());
    for k in 0..solution.t.len() {
        let y = solution.y(k);
        for i in 0..3 {
            let eta = &y[system.link_range(i)];
            let closed = eta[0] - eta[2];
            assert!(
                (w[3 * k + i] - closed).abs() <= 1e-12 * closed.abs().max(1e-9),
                "link {i} at t = {}: {} vs eta_1 - eta_3 = {closed}",
                solution.t[k],
                w[3 * k + i]
            );
        }
    }

    let reference = Reference::from_deflections(solution.t.clone(), w.clone()).expect("valid");
    assert_eq!(reference.measure, ErrorMeasure::Deflection);
    let size = w.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!((reference.displacement_size - size).abs() < 1e-18);
    let itself = reference
        .errors_of(system.as_mut(), &solution)
        .expect("same shape");
    assert!(
        itself.max.abs() < 1e-300 && itself.end.abs() < 1e-300,
        "{itself:?}"
    );

    // Perturb link 2 at the middle time by delta and link 3 at the end by delta / 4: the
    // maximum error is delta / size, the end error delta / (4 size).
    let delta = 1e-3 * size;
    let mut perturbed = w.clone();
    let middle = solution.t.len() / 2;
    perturbed[3 * middle + 1] += delta;
    let last = solution.t.len() - 1;
    perturbed[3 * last + 2] -= 0.25 * delta;
    let error = reference.deflection_errors(&perturbed).expect("same shape");
    assert!((error.max - 1e-3).abs() < 1e-15, "{error:?}");
    assert!((error.end - 0.25e-3).abs() < 1e-15, "{error:?}");

    // The state measure refuses a deflection reference and the other way round, and wrong
    // shapes are refused naming what they hold.
    assert!(reference.errors(&solution.states).is_err());
    let err = reference.deflection_errors(&w[..3]).expect_err("short");
    assert!(err.to_string().contains("3 links"), "{err}");
    let mut nan = w;
    nan[4] = f64::NAN;
    let err = reference.deflection_errors(&nan).expect_err("NaN");
    assert!(err.to_string().contains("link 2"), "{err}");
}

#[test]
fn a_deflection_reference_reads_back_from_its_csv() {
    let t = vec![0.0, 1e-3, 2e-3];
    let w = vec![0.0, 0.0, 0.0, 1e-3, -2e-3, 5e-4, 2e-3, -4e-3, 1e-3];
    let reference = Reference::from_deflections(t, w).expect("valid");
    assert!((reference.displacement_size - 4e-3).abs() < 1e-18);
    assert!((reference.atol(1e-6) - 4e-9).abs() < 1e-22);
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("reference.csv");
    reference.write_csv(&path).expect("writes");
    let text = std::fs::read_to_string(&path).expect("read");
    assert!(
        text.starts_with("t_s,w_1_xi0.5_m,w_2_xi0.5_m,w_3_xi0.5_m\n"),
        "{text}"
    );
    let back = Reference::read_csv(&path).expect("reads");
    assert_eq!(back.measure, ErrorMeasure::Deflection);
    let error = back
        .deflection_errors(&reference.deflections)
        .expect("same");
    assert!(error.max.abs() < 1e-300, "{error:?}");
    assert!(Reference::from_deflections(vec![0.0], vec![0.0; 3]).is_err());
    assert!(Reference::from_deflections(vec![0.0], vec![1.0; 2]).is_err());
}

#[test]
fn the_nonlinear_reference_agrees_with_its_check_and_with_a_tighter_third_run() {
    // Four elements per link over 2 ms: a few thousand steps.
    let scene = scene_f30("coupling = \"nonlinear\"\nelements = 4", 0.002);
    let config = WorkPrecisionConfig {
        tolerances: vec![1e-4, 1e-6],
        methods: vec![builtin("abm")],
        warmup: 0,
        repeats: 1,
        ..WorkPrecisionConfig::default()
    };
    assert_eq!(
        config.error_measure(&scene).expect("measure"),
        ErrorMeasure::Deflection
    );
    let plan = config.reference_plan(&scene).expect("plan");
    assert_eq!(plan, default_reference(scene.coupling.capabilities()));
    let reference = Reference::compute(&scene, &config).expect("reference");
    assert_eq!(reference.model, "nonlinear:4");
    assert_ne!(reference.method, reference.check_method);
    let agreement = reference.agreement.expect("checked");
    assert!(
        agreement.max < plan.agreement_limit && agreement.end <= agreement.max,
        "{agreement:?} against the limit {:e}",
        plan.agreement_limit
    );

    // A third run, ABM ten times tighter than the reference, agrees to the same limit: the
    // reference is accurate, not only reproducible.
    let mut system = scene.build_model().expect("nonlinear model");
    let y0 = system.initial_state();
    let tight = 0.1 * plan.rtol;
    let options = Options::default()
        .rtol(tight)
        .atol(tight * reference.displacement_size);
    let third = builtin("abm")
        .solve(options, &mut system.as_mut(), &y0, &scene.output_times)
        .expect("solves");
    let error = reference
        .errors_of(system.as_mut(), &third)
        .expect("same shape");
    assert!(error.max < plan.agreement_limit, "{error:?}");

    // The measurement gives rows whose error falls with the tolerance down to the
    // reference's agreement.
    let (rows, failures) = measure(&scene, &reference, &config, &mut |_| {}).expect("measures");
    assert!(failures.is_empty(), "{failures:?}");
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r.model.is_empty()));
    assert!(
        rows[1].max_error < rows[0].max_error || rows[1].max_error < 10.0 * agreement.max,
        "{rows:?}"
    );
}

#[test]
fn models_side_by_side_share_one_reference_and_floor_at_their_model_error() {
    let scene = scene_f30("coupling = \"nonlinear\"\nelements = 4", 0.002);
    let config = WorkPrecisionConfig {
        tolerances: vec![1e-5, 1e-7],
        methods: vec![builtin("abm")],
        models: vec![model("ked"), model("nonlinear:4")],
        warmup: 0,
        repeats: 1,
        ..WorkPrecisionConfig::default()
    };
    assert_eq!(config.reference_model(&scene), model("nonlinear:4"));
    let reference = Reference::compute(&scene, &config).expect("reference");
    let (rows, failures) = measure(&scene, &reference, &config, &mut |_| {}).expect("measures");
    assert!(failures.is_empty(), "{failures:?}");
    let labels: Vec<String> = rows.iter().map(WorkPrecisionRow::series_label).collect();
    assert_eq!(
        labels,
        [
            "ked (consistent) abm",
            "ked (consistent) abm",
            "nonlinear:4 abm",
            "nonlinear:4 abm"
        ]
    );

    // The KED rows floor at KED's model error: the difference of a KED reference (computed
    // on its own, RK45 at 1e-14 checked by ABM) from the nonlinear one, found directly.
    let ked_config = WorkPrecisionConfig {
        models: vec![model("ked")],
        error: Some(ErrorMeasure::Deflection),
        ..config.clone()
    };
    let ked = Reference::compute(&scene, &ked_config).expect("KED reference");
    assert_eq!(ked.model, "ked (consistent)");
    let model_error = reference
        .deflection_errors(&ked.deflections)
        .expect("same times");
    assert!(model_error.max > 1e-3, "{model_error:?}");
    let tight = &rows[1];
    assert!(
        (tight.max_error / model_error.max - 1.0).abs() < 1e-3,
        "{} vs {}",
        tight.max_error,
        model_error.max
    );
    // The nonlinear rows go far below it.
    assert!(rows[3].max_error < 1e-3 * model_error.max, "{rows:?}");
    let md = markdown_models(&rows);
    assert!(md.contains("| flexprr | nonlinear:4 abm |"), "{md}");
}

#[test]
fn choices_that_do_not_apply_are_refused_with_the_setting() {
    let scene = scene_f30("coupling = \"nonlinear\"\nelements = 4", 0.002);
    let state = WorkPrecisionConfig {
        error: Some(ErrorMeasure::State),
        ..WorkPrecisionConfig::default()
    };
    let err = state.error_measure(&scene).expect_err("state on nonlinear");
    let text = err.to_string();
    assert!(
        text.contains("error") && text.contains("nonlinear:4"),
        "{text}"
    );
    assert!(!text.contains('\n'), "{text}");

    // The paper formulation cannot carry the coupled model.
    let paper = short_scene();
    let err = model("coupled").apply(&paper).expect_err("paper + coupled");
    assert!(err.to_string().contains("consistent"), "{err}");

    // A reference tolerance not below the ladder is refused naming it.
    let loose = WorkPrecisionConfig {
        tolerances: vec![1e-4, 1e-11],
        ..WorkPrecisionConfig::default()
    };
    let err = loose.reference_plan(&scene).expect_err("1e-10 above 1e-11");
    assert!(err.to_string().contains("reference_rtol"), "{err}");

    // Each accepted name reads back as itself, on its registered kind; the rest are refused.
    for (name, kind) in [
        ("ked", Some("ked")),
        ("coupled", Some("coupled")),
        ("nonlinear", Some("nonlinear")),
        ("nonlinear:16", Some("nonlinear")),
        ("nonlinear:15", None),
        ("nonlinear:0", None),
        ("nonlinear:1024", None),
        ("coupled:4", None),
        ("linear", None),
    ] {
        let parsed = ModelChoice::parse(name);
        assert_eq!(parsed.as_ref().map(|m| m.kind().name()), kind, "{name}");
        if let Some(parsed) = parsed {
            assert_eq!(parsed.name(), name);
        }
    }
    assert_eq!(
        ModelChoice::names(&flexprr_scene::Registry::default()),
        "ked, coupled, nonlinear, nonlinear:N (N even, 2 to 512)"
    );
    assert_eq!(model("nonlinear").label(&scene), "nonlinear:4");
}

/// A shipped stress scene (`configs/stress/`).
fn stress_scene(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/stress")
        .join(format!("{name}.toml"));
    Scene::load(&path).expect("stress scene loads")
}

#[test]
fn a_diverged_reference_is_refused_where_the_run_layer_sees_the_divergence() {
    // At 40 Hz link 3 buckles and the small-deflection model runs away (`flexprr run`
    // reports "diverged"). The reference's pilot run (ABM at 1e-8 with the scene's atol) is
    // refused, naming the scene, the model, the reason and the time the run layer's own
    // integration of the same model and options stops at.
    let scene = stress_scene("high_speed_f40");
    let config = WorkPrecisionConfig {
        warmup: 0,
        repeats: 1,
        ..WorkPrecisionConfig::default()
    };
    let err = Reference::compute(&scene, &config).expect_err("diverged reference refused");
    let text = err.to_string();
    assert!(
        matches!(
            err,
            flexprr_bench::work_precision::WorkPrecisionError::Reference(ref failed)
                if failed.role == "pilot run"
        ),
        "{text}"
    );
    assert!(!text.contains('\n'), "{text}");

    let mut model = scene.build_model().expect("model");
    let integrator = flexprr_scene::Registry::default()
        .method("abm")
        .expect("abm")
        .integrator(scene.options.clone().rtol(1e-8));
    let run =
        flexprr_run::integrate_model(&scene, integrator.as_ref(), model.as_mut(), &mut |_| {});
    let failure = run.failure.expect("the run layer sees the divergence");
    assert_eq!(failure.kind(), "diverged");
    let t_ms = 1e3 * failure.time().expect("a time");
    assert!((15.0..17.0).contains(&t_ms), "diverged at {t_ms} ms");
    for part in [
        "high_speed_f40",
        "ked (consistent)",
        "pilot run",
        &failure.to_string(),
        "not measured against",
    ] {
        assert!(text.contains(part), "{part:?} not in {text}");
    }
}

#[test]
fn a_point_that_diverges_is_a_failed_point_and_the_others_are_measured() {
    // The loose-tolerance stress scene: its reference (1e-14) is sound, but ABM at rtol 1e-1
    // runs away. That point is listed as failed ("diverged", as the run layer's guard sees
    // it), never as a row with a huge error; the point at 1e-4 is measured.
    let scene = stress_scene("tolerance_loose");
    let config = WorkPrecisionConfig {
        tolerances: vec![1e-1, 1e-4],
        methods: vec![builtin("abm")],
        warmup: 0,
        repeats: 1,
        ..WorkPrecisionConfig::default()
    };
    let result = work_precision(&scene, &config, &mut |_| {}).expect("measured");
    assert_eq!(result.rows.len(), 1, "{:?}", result.rows);
    assert!(result.rows[0].rtol < 1e-3 && result.rows[0].max_error < 1e-2);
    assert_eq!(result.failures.len(), 1, "{:?}", result.failures);
    assert!(
        result.failures[0].starts_with("abm at rtol 1e-1: diverged: link"),
        "{:?}",
        result.failures
    );

    // The run layer's own guarded integration with the same method and options diverges.
    let mut model = scene.build_model().expect("model");
    let integrator = flexprr_scene::Registry::default()
        .method("abm")
        .expect("abm")
        .integrator(
            Options::default()
                .rtol(1e-1)
                .atol(result.reference.atol(1e-1)),
        );
    let run =
        flexprr_run::integrate_model(&scene, integrator.as_ref(), model.as_mut(), &mut |_| {});
    assert_eq!(run.failure.map(|f| f.kind()), Some("diverged"));
}

#[test]
fn a_method_model_or_tolerance_named_twice_is_refused() {
    for (config, key, named) in [
        (
            WorkPrecisionConfig {
                methods: ["abm", "rk45", "abm"].map(builtin).to_vec(),
                ..config()
            },
            "methods",
            "abm",
        ),
        (
            WorkPrecisionConfig {
                models: vec![model("ked"), model("ked")],
                ..config()
            },
            "models",
            "ked",
        ),
        (
            WorkPrecisionConfig {
                tolerances: vec![1e-4, 1e-6, 1e-6],
                ..config()
            },
            "tolerances",
            "1e-6",
        ),
    ] {
        let err = config.validate().expect_err("repeat refused");
        assert_eq!(err.to_string(), format!("{key}: {named} is named twice"));
    }
    // The same nonlinear model under two names: refused when measured on the scene.
    let f30 = scene_f30("coupling = \"nonlinear\"\nelements = 4", 0.002);
    let twice = WorkPrecisionConfig {
        models: vec![model("nonlinear"), model("nonlinear:4")],
        error: Some(ErrorMeasure::Deflection),
        ..config()
    };
    let reference = Reference::from_deflections(vec![0.0, 1.0], vec![1.0; 6]).expect("ref");
    let err = measure(&f30, &reference, &twice, &mut |_| {}).expect_err("refused");
    assert!(
        err.to_string()
            .contains("models: nonlinear:4 is named twice"),
        "{err}"
    );
}

/// The KED modal equations under a kind registered by a program, declared not linear in its
/// state (as in `examples/custom_model.rs`).
struct GeneralKed;

impl flexprr_scene::ModelKind for GeneralKed {
    fn capabilities(&self) -> flexprr_scene::ModelCapabilities {
        flexprr_scene::ModelCapabilities {
            assumed_modes: true,
            ..flexprr_scene::ModelCapabilities::default()
        }
    }

    fn build(
        &self,
        scene: &Scene,
    ) -> Result<Box<dyn flexprr_dynamics::SceneModel>, flexprr_dynamics::DynamicsError> {
        Ok(Box::new(scene.build_ked(false)?))
    }
}

#[test]
fn a_registered_model_kind_is_measured_by_name_beside_the_builtin_one() {
    let mut registry = flexprr_scene::Registry::default();
    registry.register_model_kind("ked-general", std::sync::Arc::new(GeneralKed));
    assert!(ModelChoice::parse("ked-general").is_none(), "not built in");
    assert!(ModelChoice::parse_in(&registry, "ked-general:4").is_none());
    assert!(
        ModelChoice::names(&registry).starts_with("ked, coupled, ked-general, nonlinear"),
        "{}",
        ModelChoice::names(&registry)
    );
    let general = ModelChoice::parse_in(&registry, "ked-general").expect("registered");
    let scene = short_scene();
    assert_eq!(general.label(&scene), "ked-general (paper)");
    let config = WorkPrecisionConfig {
        tolerances: vec![1e-5, 1e-7],
        methods: vec![builtin("abm")],
        models: vec![model("ked"), general.clone()],
        warmup: 0,
        repeats: 1,
        ..WorkPrecisionConfig::default()
    };
    config
        .validate()
        .expect("a registered kind is a valid choice");
    // Not linear in its state: the more faithful by its capabilities, so the reference, and
    // measured in deflections (the state measure is KED's).
    assert_eq!(config.reference_model(&scene), general);
    assert_eq!(
        config.error_measure(&scene).expect("measure"),
        ErrorMeasure::Deflection
    );
    let reference = Reference::compute(&scene, &config).expect("reference");
    assert_eq!(reference.model, "ked-general (paper)");
    let (rows, failures) = measure(&scene, &reference, &config, &mut |_| {}).expect("measures");
    assert!(failures.is_empty(), "{failures:?}");
    let labels: Vec<String> = rows.iter().map(WorkPrecisionRow::series_label).collect();
    assert_eq!(
        labels,
        [
            "ked (paper) abm",
            "ked (paper) abm",
            "ked-general (paper) abm",
            "ked-general (paper) abm"
        ]
    );
    // The same equations under two names, integrated by the same method at the same
    // tolerance: the same error, and one that falls as the tolerance tightens.
    for (ked, other) in rows[..2].iter().zip(&rows[2..]) {
        assert!(
            (ked.max_error - other.max_error).abs() <= 1e-9 * ked.max_error,
            "{ked:?} vs {other:?}"
        );
    }
    assert!(rows[1].max_error < rows[0].max_error, "{rows:?}");
}
