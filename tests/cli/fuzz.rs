//! Mutation fuzzing of `flexprr study` (sweeps and speed searches), `merge` and
//! `work-precision` through the built binary, with the laws of the scene fuzz test and the
//! output-directory policy: no panic; exit 0, 1 or 2 with one error line; a study the library
//! refuses is refused by the command before any work (exit 2, no output directory), and one it
//! loads runs to the end (exit 0: failed cases are rows, not errors); no non-finite number in
//! any output; nothing written outside the output directory, no input changed. Mutants are
//! drawn by a deterministic generator (a failure names its mutant) and kept cheap: a study
//! that loads is run only when its cases are few and short.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Output;

use crate::common::{TINY, flexprr, tree};

use flexprr_studies::search::Window;
use flexprr_studies::study::Study;
use flexprr_testkit::fuzz::Lcg;

fn flexprr_in(dir: &Path, args: &[&str]) -> Output {
    flexprr().current_dir(dir).args(args).output().unwrap()
}

/// The laws every command obeys; `out` is the output directory (relative to `dir`) and
/// `what` names the mutant in messages.
fn check_laws(
    what: &str,
    dir: &Path,
    out: &str,
    before: &BTreeMap<String, Vec<u8>>,
    output: &Output,
) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    let code = output.status.code();
    assert!(
        matches!(code, Some(0..=2)),
        "{what}: exit {code:?}: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    let errors = stderr.lines().filter(|l| l.starts_with("error")).count();
    if code != Some(0) {
        assert_eq!(errors, 1, "{what}: {stderr}");
    }
    let after = tree(dir);
    let inside = |name: &str| name == format!("{out}/") || name.starts_with(&format!("{out}/"));
    for (name, content) in before {
        if !inside(name) {
            assert!(
                after.get(name) == Some(content),
                "{what}: changed or removed {name}"
            );
        }
    }
    for name in after.keys().filter(|n| !before.contains_key(*n)) {
        assert!(inside(name), "{what}: wrote {name} outside {out}");
    }
    for (name, content) in after.iter().filter(|(n, _)| inside(n)) {
        let text = String::from_utf8_lossy(content);
        let bad = if name.ends_with(".csv") {
            csv_non_finite(&text)
        } else if name.ends_with(".json") {
            let value: serde_json::Value = serde_json::from_str(&text)
                .unwrap_or_else(|e| panic!("{what}: {name} is not JSON: {e}"));
            json_non_finite(&value)
        } else if name.ends_with(".md") {
            text.lines()
                .filter(|l| l.starts_with('|'))
                .flat_map(|l| l.split('|'))
                .find(|c| non_finite(c))
                .map(String::from)
        } else {
            None
        };
        assert!(bad.is_none(), "{what}: {bad:?} in {name}");
    }
}

/// Whether a cell is a non-finite number (`NaN`, `inf`, `-Infinity`, ...).
fn non_finite(cell: &str) -> bool {
    cell.trim()
        .trim_matches('"')
        .parse::<f64>()
        .is_ok_and(|v| !v.is_finite())
}

/// The cells of one CSV line (quotes and doubled quotes handled).
fn csv_cells(line: &str) -> Vec<String> {
    let (mut cells, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cell.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cell)),
            _ => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}

/// A non-finite cell of a CSV table outside its `error` column (a message may quote the
/// bad input it refused).
fn csv_non_finite(text: &str) -> Option<String> {
    let mut lines = text.lines();
    let header = csv_cells(lines.next()?);
    lines.flat_map(csv_cells_owned).find_map(|(k, cell)| {
        (header.get(k).map(String::as_str) != Some("error") && non_finite(&cell)).then_some(cell)
    })
}

fn csv_cells_owned(line: &str) -> Vec<(usize, String)> {
    csv_cells(line).into_iter().enumerate().collect()
}

/// A non-finite number (as a string) in a JSON value, outside `error` and `message`.
fn json_non_finite(value: &serde_json::Value) -> Option<String> {
    match value {
        serde_json::Value::String(s) if non_finite(s) => Some(s.clone()),
        serde_json::Value::Array(a) => a.iter().find_map(json_non_finite),
        serde_json::Value::Object(o) => o
            .iter()
            .filter(|(k, _)| !["error", "message"].contains(&k.as_str()))
            .find_map(|(_, v)| json_non_finite(v)),
        _ => None,
    }
}

const SWEEP: &str = r#"name = "sweep"
base = "scene.toml"
quantities = [
    { kind = "frequency_range", link = 1, mode = 1 },
    { kind = "peak_deflection", link = 2 },
    { kind = "buckling", link = 1 },
]
[set.time]
end = 0.01
output_step = 1e-3
[[axis]]
key = "trajectory.frequency"
range = { start = 5.0, end = 30.0, count = 3 }
[[axis]]
key = "links.section"
values = [{ kind = "uniform", thickness = 0.002, height = 0.03 }, { kind = "uniform", thickness = 0.001, height = 0.03 }]
[[plot]]
file = "f.svg"
x = "trajectory.frequency"
y = ["f_min_1_1_Hz"]
series = "links.section"
"#;

const SEARCH: &str = r#"name = "search"
base = "coupled.toml"
[set.output]
requests = ["frequencies"]
[set.time]
output_step = 1e-3
[[axis]]
key = "model.coupling"
values = ["ked", "coupled"]
[search]
key = "trajectory.frequency"
low = 20.0
high = 34.0
tolerance = 4.0
time = 0.05
"#;

const VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "0.5",
    "1e300",
    "1e-300",
    "nan",
    "inf",
    "\"x\"",
    "true",
    "[]",
    "{}",
    "[1, 2]",
    "1000000000000",
    "\"../x.svg\"",
    "\"/tmp/x.svg\"",
    "\"results.csv\"",
    "\"study.json\"",
    "\"\"",
    "\"time.end\"",
    "\"time\"",
    "\"machine\"",
    "\"trajectory\"",
    "\"model.formulation\"",
    "\"output.requests\"",
    "\"links.modes\"",
    "\"machine.platform_mass\"",
    "\"collapse\"",
    "\"buckling\"",
    "\"zip\"",
    "\"log\"",
    "[\"deflections\"]",
    "[\"frequencies\"]",
    "0.001",
    "0.04",
    "35.0",
    "{ start = 1.0, end = 2.0, count = 1 }",
    "{ start = 5.0, end = 30.0, count = 2 }",
];

const WORDS: &[&str] = &[
    "key",
    "values",
    "range",
    "count",
    "quantities",
    "base",
    "set",
    "low",
    "high",
    "tolerance",
    "time",
    "revolutions",
    "criterion",
    "file",
    "x",
    "y",
    "series",
    "name",
    "bogus",
];

fn mutate(text: &str, rng: &mut Lcg) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let k = rng.below(lines.len());
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    match rng.below(8) {
        0..=3 => {
            if let Some((key, _)) = lines[k].split_once('=') {
                out[k] = format!("{key}= {}", rng.pick(VALUES));
            }
        }
        4 => {
            out.remove(k);
        }
        5 => out.insert(k, lines[k].to_string()),
        6 => out.insert(k, format!("{} = {}", rng.pick(WORDS), rng.pick(VALUES))),
        _ => {
            let table = rng.pick(&["[[axis]]", "[set.model]", "[set.integrator]", "[[plot]]"]);
            out.insert(k, format!("{table}\nkey = {}", rng.pick(VALUES)));
        }
    }
    out.join("\n") + "\n"
}

/// Whether a study that loads is cheap enough to run here: few, short cases with few output
/// times, no nonlinear model, few probes.
fn cheap(study: &Study) -> bool {
    match &study.search {
        None => {
            study.cases.len() <= 12
                && study.cases.iter().all(|c| {
                    study.case_scene(c).map_or(true, |scene| {
                        let t = &scene.output_times;
                        t.len() <= 2001
                            && t.last().zip(t.first()).is_some_and(|(l, f)| l - f <= 0.05)
                            && scene.coupling.name() != "nonlinear"
                    })
                })
        }
        Some(search) => {
            let window = match search.window {
                Window::Time(t) => t,
                Window::Revolutions(n) => n / search.low,
            };
            let probes = 2.0
                + ((search.high - search.low) / search.tolerance)
                    .log2()
                    .ceil();
            let step = study
                .base
                .get("time")
                .and_then(|t| t.get("output_step"))
                .and_then(|v| v.as_float());
            let samples = step.map_or(1000.0, |s| window / s);
            let nonlinear = study.cases.iter().any(|c| {
                study.case_table(c).map_or(true, |t| {
                    t.get("model")
                        .and_then(|m| m.get("coupling"))
                        .and_then(|v| v.as_str())
                        == Some("nonlinear")
                })
            });
            study.cases.len() <= 3
                && window <= 0.05
                && probes <= 10.0
                && samples <= 2000.0
                && !nonlinear
        }
    }
}

fn sandbox() -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("scene.toml"), TINY).unwrap();
    let coupled = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/coupled_f20.toml");
    std::fs::copy(coupled, tmp.path().join("coupled.toml")).unwrap();
    tmp
}

/// Runs `mutants` mutants of `seed` through `flexprr study`; returns (refused, ran).
fn fuzz_study(seed: &str, mutants: usize, rng: &mut Lcg) -> (usize, usize) {
    let tmp = sandbox();
    let dir = tmp.path();
    let (mut refused, mut ran) = (0, 0);
    for m in 0..mutants {
        let text = mutate(seed, rng);
        let what = format!("mutant {m}:\n{text}");
        let loaded = Study::from_text("s.toml", "s", &text, dir);
        if loaded.as_ref().is_ok_and(|s| !cheap(s)) {
            continue;
        }
        std::fs::write(dir.join("s.toml"), &text).unwrap();
        let _ = std::fs::remove_dir_all(dir.join("o"));
        let before = tree(dir);
        let output = flexprr_in(
            dir,
            &["study", "s.toml", "--out", "o", "--quiet", "--threads", "1"],
        );
        check_laws(&what, dir, "o", &before, &output);
        let stderr = String::from_utf8_lossy(&output.stderr);
        match loaded {
            Err(e) => {
                assert_eq!(output.status.code(), Some(2), "{what}\n{e}\n{stderr}");
                assert!(
                    !dir.join("o").exists(),
                    "{what}: work done before the refusal"
                );
                refused += 1;
            }
            Ok(_) => {
                assert_eq!(output.status.code(), Some(0), "{what}\n{stderr}");
                assert!(dir.join("o/results.csv").is_file(), "{what}");
                ran += 1;
            }
        }
    }
    (refused, ran)
}

#[test]
fn mutated_sweeps_are_refused_at_once_or_run_to_the_end() {
    let (refused, ran) = fuzz_study(SWEEP, 120, &mut Lcg(0x28_0001));
    assert!(refused >= 30 && ran >= 20, "refused {refused}, ran {ran}");
}

#[test]
fn mutated_searches_are_refused_at_once_or_run_to_the_end() {
    let (refused, ran) = fuzz_study(SEARCH, 100, &mut Lcg(0x28_0002));
    assert!(refused >= 20 && ran >= 15, "refused {refused}, ran {ran}");
}

/// Shard directories with a damaged file are merged or refused, never half-merged.
#[test]
fn merges_of_damaged_shards_are_refused_or_complete() {
    let tmp = sandbox();
    let dir = tmp.path();
    std::fs::write(dir.join("s.toml"), SWEEP).unwrap();
    for k in ["1", "2"] {
        let (out, shard) = (format!("s{k}"), format!("{k}/2"));
        let made = flexprr_in(
            dir,
            &[
                "study", "s.toml", "--out", &out, "--shard", &shard, "--quiet",
            ],
        );
        assert!(made.status.success());
    }
    let pristine: BTreeMap<String, Vec<u8>> = tree(dir);
    let files: Vec<String> = pristine
        .keys()
        .filter(|n| n.starts_with('s') && n.ends_with(".json") && n.contains('/'))
        .cloned()
        .collect();
    let edits = [
        "\"NaN\"",
        "\"inf\"",
        "1e999",
        "null",
        "\"\"",
        "-1",
        "\"ok\"",
        "\"failed\"",
        "{}",
        "[]",
    ];
    let mut rng = Lcg(0x28_0003);
    let (mut refused, mut merged) = (0, 0);
    for m in 0..60 {
        // Restore the shards, then damage one file.
        for (name, content) in &pristine {
            if !name.ends_with('/') {
                std::fs::write(dir.join(name), content).unwrap();
            }
        }
        let _ = std::fs::remove_dir_all(dir.join("m"));
        let file = &files[rng.below(files.len())];
        let text = String::from_utf8_lossy(&pristine[file]).into_owned();
        let damaged = match rng.below(4) {
            0 => text[..rng.below(text.len())].to_string(),
            1 => {
                // Replace one value.
                let lines: Vec<&str> = text.lines().collect();
                let k = rng.below(lines.len());
                let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
                if let Some((key, _)) = lines[k].split_once(':') {
                    let comma = if lines[k].trim_end().ends_with(',') {
                        ","
                    } else {
                        ""
                    };
                    out[k] = format!("{key}: {}{comma}", rng.pick(&edits));
                }
                out.join("\n")
            }
            2 => text.replacen("\"ok\"", "\"failed\"", 1),
            _ => String::new(),
        };
        std::fs::write(dir.join(file), &damaged).unwrap();
        let what = format!("merge mutant {m} ({file}):\n{damaged}");
        let before = tree(dir);
        let output = flexprr_in(dir, &["merge", "s1", "s2", "--out", "m"]);
        check_laws(&what, dir, "m", &before, &output);
        if output.status.success() {
            merged += 1;
            let table = std::fs::read_to_string(dir.join("m/results.csv")).unwrap();
            assert_eq!(table.lines().count(), 1 + 6, "{what}");
        } else {
            refused += 1;
            assert!(!dir.join("m/results.csv").exists(), "{what}: a half merge");
        }
    }
    assert!(refused >= 20, "refused {refused}, merged {merged}");
}

/// `work-precision` with options drawn from valid and invalid values, and damaged reference
/// files: refused at once (exit 2) or measured, with the laws above.
#[test]
fn work_precision_with_random_options_obeys_the_laws() {
    let tmp = sandbox();
    let dir = tmp.path();
    let fast = [
        "work-precision",
        "scene.toml",
        "--warmup",
        "0",
        "--out",
        "w0",
    ];
    let made = flexprr_in(
        dir,
        &[
            &fast[..],
            &["--repeats", "1", "--methods", "abm", "--tolerances", "1e-4"],
        ]
        .concat(),
    );
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let reference = std::fs::read_to_string(dir.join("w0/reference.csv")).unwrap();
    std::fs::write(dir.join("ref.csv"), &reference).unwrap();
    std::fs::write(dir.join("cut.csv"), &reference[..reference.len() / 3]).unwrap();
    std::fs::write(dir.join("nan.csv"), reference.replacen("e-", "NaNe-", 3)).unwrap();
    let options: [(&str, &[&str]); 9] = [
        (
            "--tolerances",
            &["1e-4", "1e-4,1e-6", "nan", "0", "2", "-1", "1e-20", "x"],
        ),
        (
            "--methods",
            &["abm", "rk45,abm", "magnus6", "bogus", "abm,abm", ""],
        ),
        (
            "--models",
            &["ked", "coupled", "ked,coupled", "bogus", "nonlinear:3"],
        ),
        ("--error", &["state", "deflection", "bogus"]),
        ("--repeats", &["1", "0", "-1"]),
        ("--reference-rtol", &["1e-10", "0", "nan", "1"]),
        ("--target-error", &["1e-6", "0", "-1", "inf"]),
        (
            "--reference",
            &[
                "ref.csv",
                "cut.csv",
                "nan.csv",
                "/dev/zero",
                "w0/reference.csv",
                ".",
            ],
        ),
        ("--peers", &["ref.csv", "/dev/zero", "scene.toml"]),
    ];
    let mut rng = Lcg(0x28_0004);
    let mut codes = [0usize; 3];
    for m in 0..30 {
        let mut args: Vec<String> = fast.iter().map(|s| s.to_string()).collect();
        args[5] = "w".into();
        let mut named = vec!["--repeats=1".to_string(), "--methods=abm".to_string()];
        for _ in 0..1 + rng.below(3) {
            let (option, values) = options[rng.below(options.len())];
            named.retain(|a| !a.starts_with(&format!("{option}=")));
            named.push(format!("{option}={}", rng.pick(values)));
        }
        args.extend(named);
        let _ = std::fs::remove_dir_all(dir.join("w"));
        let before = tree(dir);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let output = flexprr_in(dir, &refs);
        let what = format!("work-precision mutant {m}: {args:?}");
        check_laws(&what, dir, "w", &before, &output);
        codes[output.status.code().unwrap_or(0) as usize] += 1;
    }
    assert!(codes[0] >= 3 && codes[2] >= 5, "exit codes {codes:?}");
}

/// The seeds themselves load and are cheap: the mutants start from working files.
#[test]
fn the_seeds_load_and_are_cheap() {
    let tmp = sandbox();
    for seed in [SWEEP, SEARCH] {
        let study = Study::from_text("s.toml", "s", seed, tmp.path()).unwrap();
        assert!(cheap(&study));
    }
}
