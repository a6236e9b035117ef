//! Workspace maps (`[map]`, docs/studies.md) and the `lowest_frequency` quantity: against
//! the pinned-pinned closed form where the machine is the locked coupled model (rigid
//! chords, no axial load at rest: every link a pinned-pinned beam at every pose), marked
//! poses (out of reach, type-II singular home pose of the radial layout), the files, and
//! every load error located in the study file.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use flexprr_studies::map::MapProgress;
use flexprr_studies::study::{Study, StudyError, StudyOptions};
use flexprr_studies::{run_map_study, run_study};

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

fn study(text: &str) -> Result<Study, StudyError> {
    Study::from_text("map.toml", "map", text, &configs())
}

/// The first pinned-pinned frequency of the paper's link (E = 7.3e10 Pa, 2770 kg/m^3,
/// l = 0.2 m) of thickness `t`: `(pi / 2 l^2) t sqrt(E / 12 rho)`.
fn pinned_pinned(t: f64) -> f64 {
    PI / (2.0 * 0.2 * 0.2) * t * (7.3e10_f64 / (12.0 * 2770.0)).sqrt()
}

/// The rows of `map.csv` as `(x, y, status, frequency)`.
fn rows(dir: &Path) -> Vec<(f64, f64, String, Option<f64>)> {
    let text = std::fs::read_to_string(dir.join("map.csv")).unwrap();
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[0].parse().unwrap(),
                r[1].parse().unwrap(),
                r[3].to_string(),
                r[4].parse().ok(),
            )
        })
        .collect()
}

#[test]
fn the_locked_coupled_map_is_the_pinned_pinned_frequency_and_marks_what_it_cannot_hold() {
    // phi = 0: the radial layout's home pose (0, 0) is type-II singular; the corners of
    // the grid are out of reach.
    let s = study(
        r#"
base = "coupled_f20.toml"
[set.model]
chords = "rigid"              # the pinned-pinned idealisation: the closed form exactly
[map]
x = { start = -0.2, end = 0.2, count = 9 }
y = { start = -0.2, end = 0.2, count = 9 }
phi_deg = 0.0
"#,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    let seen = std::sync::Mutex::new(Vec::new());
    let (summary, outcome) = run_map_study(
        &s,
        &out,
        &StudyOptions {
            threads: Some(2),
            ..StudyOptions::default()
        },
        &|p: &MapProgress| seen.lock().unwrap().push(p.done),
    )
    .unwrap();
    let mut seen = seen.into_inner().unwrap();
    seen.sort_unstable();
    assert_eq!(
        seen,
        (1..=81).collect::<Vec<_>>(),
        "every pose reported once"
    );
    assert_eq!(summary.progress.total, 81);
    let rows = rows(&out);
    assert_eq!(rows.len(), 81);
    let exact = pinned_pinned(0.002);
    let mut ok = 0;
    for (x, y, status, f) in &rows {
        match status.as_str() {
            "ok" => {
                let f = f.unwrap();
                assert!(((f - exact) / exact).abs() < 1e-6, "({x}, {y}): {f}");
                ok += 1;
            }
            "unreachable" | "singular" => assert!(f.is_none()),
            other => panic!("({x}, {y}): {other}"),
        }
    }
    assert!(ok > 20, "{ok} poses held");
    let at = |x: f64, y: f64| {
        rows.iter()
            .find(|r| (r.0 - x).abs() < 1e-12 && (r.1 - y).abs() < 1e-12)
            .unwrap()
            .2
            .clone()
    };
    assert_eq!(at(0.0, 0.0), "singular");
    assert_eq!(at(-0.2, -0.2), "unreachable");
    assert_eq!(
        outcome.progress.unreachable + outcome.progress.singular + ok,
        81
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("map.json")).unwrap()).unwrap();
    assert_eq!(json["poses"]["ok"], ok);
    assert_eq!(json["grid"]["x_m"]["count"], 9);
    assert_eq!(json["quantity"], "lowest_frequency");
    let svg = std::fs::read_to_string(out.join("map.svg")).unwrap();
    assert!(svg.contains("reachable-set boundary") && svg.contains("singular ("));
    // run_study dispatches a map study too; it writes the same table.
    let again = dir.path().join("again");
    run_study(&s, &again, &StudyOptions::default(), &|_, _| {}).unwrap();
    assert_eq!(
        std::fs::read_to_string(again.join("map.csv")).unwrap(),
        std::fs::read_to_string(out.join("map.csv")).unwrap()
    );
}

#[test]
fn a_map_is_not_sharded_or_resumed() {
    let s = study(
        "base = \"coupled_f20.toml\"\n[map]\nx = { start = -0.05, end = 0.05, count = 2 }\ny = { start = -0.05, end = 0.05, count = 2 }\n",
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for options in [
        StudyOptions {
            resume: true,
            ..StudyOptions::default()
        },
        StudyOptions {
            shard: Some("1/2".parse().unwrap()),
            ..StudyOptions::default()
        },
    ] {
        let e = run_map_study(&s, &dir.path().join("m"), &options, &|_| {}).unwrap_err();
        assert!(e.is_input(), "{e}");
        assert!(
            e.to_string().contains("cannot be sharded or resumed"),
            "{e}"
        );
    }
    assert!(!dir.path().join("m").exists(), "nothing written");
}

/// `lowest_frequency` in a sweep: the locked coupled machine at rest at each case's start
/// pose is the pinned-pinned frequency of that case's link thickness (linear in it).
#[test]
fn the_lowest_frequency_quantity_follows_the_link_thickness() {
    let s = study(
        r#"
base = "coupled_f20.toml"
quantities = [{ kind = "lowest_frequency" }]
[set.model]
chords = "rigid"
[set.output]
requests = ["machine"]
[[axis]]
key = "links.section.thickness"
values = [0.002, 0.003, 0.004]
"#,
    )
    .unwrap();
    assert_eq!(
        s.columns(),
        [
            "case",
            "links.section.thickness",
            "f_machine_lowest_Hz",
            "zeta_machine_lowest",
            "status",
            "error"
        ]
    );
    for case in &s.cases {
        let (record, _) = s.run_case(case);
        assert_eq!(record.status.name(), "ok", "{}", record.error);
        let t: f64 = record.parameters[0].parse().unwrap();
        let f: f64 = record.quantities[0].parse().unwrap();
        assert!(
            ((f - pinned_pinned(t)) / pinned_pinned(t)).abs() < 1e-6,
            "{t}: {f}"
        );
        let zeta: f64 = record.quantities[1].parse().unwrap();
        assert!(zeta.abs() < 1e-6);
    }
}

/// `bad.toml`-style location of the `needle` in `text`: `map.toml:<line>:<column>: `.
fn located(text: &str, needle: &str) -> String {
    let offset = text.find(needle).unwrap_or_else(|| panic!("{needle}"));
    let line = text[..offset].matches('\n').count() + 1;
    let column = offset - text[..offset].rfind('\n').map_or(0, |i| i + 1) + 1;
    format!("map.toml:{line}:{column}: ")
}

fn refused(text: &str, needle: &str, key: &str, what: &str) {
    let e = study(text).unwrap_err();
    let message = e.to_string();
    assert!(e.is_input(), "{message}");
    let prefix = format!("{}{key}: ", located(text, needle));
    assert!(
        message.starts_with(&prefix),
        "expected {prefix}..., got {message}"
    );
    assert!(message.contains(what), "{message}");
    assert!(!message.contains('\n'));
}

#[test]
fn bad_maps_are_refused_where_they_are_written() {
    let grid = "x = { start = -0.05, end = 0.05, count = 5 }\ny = { start = -0.05, end = 0.05, count = 5 }\n";
    let coupled = "base = \"coupled_f20.toml\"\n";
    refused(
        &format!("base = \"paper_f20.toml\"\n[map]\n{grid}"),
        "map]",
        "map",
        "model.coupling is \"ked\"",
    );
    refused(
        &format!(
            "{coupled}[map]\nx = {{ start = 0.1, end = -0.1, count = 5 }}\ny = {{ start = -0.05, end = 0.05, count = 5 }}\n"
        ),
        "x = { start = 0.1",
        "map.x",
        "start < end",
    );
    refused(
        &format!(
            "{coupled}[map]\nx = {{ start = -0.1, end = 0.1, count = 1 }}\ny = {{ start = -0.05, end = 0.05, count = 5 }}\n"
        ),
        "count = 1",
        "map.x.count",
        "2 to 1000",
    );
    refused(
        &format!(
            "{coupled}[map]\nx = {{ start = -0.1, end = 0.1, count = 5 }}\ny = {{ start = -0.05, end = 0.05, count = 5000 }}\n"
        ),
        "count = 5000",
        "map.y.count",
        "2 to 1000",
    );
    refused(
        &format!(
            "{coupled}[map]\nx = {{ start = 0.01, end = 0.1, count = 5, spacing = \"log\" }}\ny = {{ start = -0.05, end = 0.05, count = 5 }}\n"
        ),
        "spacing = \"log\"",
        "map.x.spacing",
        "linear",
    );
    refused(
        &format!("{coupled}[map]\n{grid}phi_deg = nan\n"),
        "phi_deg = nan",
        "map.phi_deg",
        "finite",
    );
    refused(
        &format!("{coupled}[map]\n{grid}quantity = \"highest_frequency\"\n"),
        "\"highest_frequency\"",
        "map.quantity",
        "lowest_frequency",
    );
    refused(
        &format!(
            "{coupled}[map]\nx = {{ start = 1.0, end = 2.0, count = 5 }}\ny = {{ start = 1.0, end = 2.0, count = 5 }}\n"
        ),
        "map]",
        "map",
        "the reachable set spans about",
    );
    refused(
        &format!(
            "{coupled}[map]\n{grid}[[axis]]\nkey = \"machine.platform_mass\"\nvalues = [0.2]\n"
        ),
        "[[axis]]",
        "axis.0",
        "no sweep axes",
    );
    refused(
        &format!("{coupled}quantities = [{{ kind = \"collapse\" }}]\n[map]\n{grid}"),
        "quantities",
        "quantities",
        "map.quantity",
    );
    refused(
        &format!(
            "{coupled}[search]\nkey = \"trajectory.frequency\"\nlow = 1.0\nhigh = 2.0\ntolerance = 0.5\ntime = 0.01\n[map]\n{grid}"
        ),
        "search]",
        "search",
        "not both",
    );
    // The base scene's own errors stay located in it, through [set].
    refused(
        &format!("{coupled}[set.links]\nlength = -1.0\n[map]\n{grid}"),
        "length",
        "set.links.length",
        "positive",
    );
}

#[test]
fn the_quantity_is_refused_for_a_ked_sweep() {
    let text = "base = \"paper_f20.toml\"\nquantities = [{ kind = \"lowest_frequency\" }]\n";
    refused(text, "{ kind", "quantities.0", "whole machine");
}
