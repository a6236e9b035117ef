//! Work-precision measurement on a short scene (the paper's machine on the 20 Hz circle for
//! 20 ms): the achieved error falls as the tolerance tightens, the reference agrees with its
//! check and with a third method, the error measure and the equal-error interpolation match
//! closed forms, and the CSV carries every column.

use flexprr_bench::work_precision::{
    PACKAGE, Reference, WorkPrecisionConfig, WorkPrecisionRow, csv_text, markdown_at_error,
    read_csv, time_at_error, work_precision,
};
use flexprr_integrators::{Bdf, Integrator, Options};
use flexprr_scene::Method;
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

    for method in [Method::Abm, Method::Rk45, Method::Bdf] {
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
    for method in [Method::Magnus4, Method::Magnus6, Method::Auto] {
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
    ];
    assert_eq!(header.split(',').collect::<Vec<_>>(), expected);
    // A count a package does not report is an empty field.
    assert!(text.lines().nth(1).expect("row").contains(",10,,60,"));

    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("peers.csv");
    std::fs::write(&path, &text).expect("write");
    assert_eq!(read_csv(&path).expect("reads"), rows);

    // A row with a negative error is rejected, naming the row.
    let broken = text
        .replace("3e-6", "-3e-6")
        .replace("0.000003", "-0.000003");
    std::fs::write(&path, broken).expect("write");
    let err = read_csv(&path).expect_err("negative error").to_string();
    assert!(err.contains("row 1"), "{err}");
}
