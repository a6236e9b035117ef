//! Mutation fuzzing of study files, as `crates/scene/tests/fuzz.rs` does for scenes: the
//! shipped studies in `configs/` and a sweep and a search written for the purpose, edited at
//! random (a deterministic generator: a failure names its mutant) and loaded, never run.
//!
//! Laws checked for every mutant: no panic; an error is one line, in plain words; an error
//! of the study file carries its `file:line:column` whenever the text is TOML or the parser
//! gives a span; an error of the base scene names the base scene (only a missing `base` has no place to point at); a study that loads has at
//! most `MAX_CASES` cases, and none of its plot files leaves the output directory.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use flexprr_studies::study::{MAX_CASES, Study, StudyError};
use flexprr_testkit::fuzz::Lcg;

/// Mutants per seed.
const MUTANTS_PER_SEED: usize = 60;

const VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "0.0",
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
    "2000000",
    "\"../x.svg\"",
    "\"/abs.svg\"",
    "\"results.csv\"",
    "\"study.json\"",
    "\"\"",
    "\"time.end\"",
    "\"machine\"",
    "\"trajectory\"",
    "\"model.formulation\"",
    "\"output.requests\"",
    "\"links.modes\"",
    "\"trajectory.frequency\"",
    "\"collapse\"",
    "\"buckling\"",
    "\"zip\"",
    "\"log\"",
    "[\"deflections\"]",
    "{ start = 1.0, end = 2.0, count = 1 }",
    "{ coupling = \"coupled\" }",
];

const WORDS: &[&str] = &[
    "key",
    "values",
    "range",
    "count",
    "start",
    "end",
    "spacing",
    "combine",
    "quantities",
    "base",
    "scene",
    "set",
    "search",
    "low",
    "high",
    "tolerance",
    "time",
    "revolutions",
    "criterion",
    "plot",
    "file",
    "x",
    "y",
    "series",
    "name",
    "bogus",
];

/// One random edit of `text`.
fn mutate(text: &str, rng: &mut Lcg) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let k = rng.below(lines.len());
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    match rng.below(10) {
        0..=2 => {
            if let Some((key, _)) = lines[k].split_once('=') {
                out[k] = format!("{key}= {}", rng.pick(VALUES));
            }
        }
        3 => {
            out.remove(k);
        }
        4 => out.insert(k, lines[k].to_string()),
        5 => out.insert(k, format!("{} = {}", rng.pick(WORDS), rng.pick(VALUES))),
        6 => {
            let cut = rng.below(text.len());
            let mut cut = cut;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_string();
        }
        7 => {
            let junk = rng.pick(&["[", "]", "{", "=", "\"", "[[", ",", "a.b.c = 1", "#"]);
            let mut at = rng.below(lines[k].len() + 1);
            while !lines[k].is_char_boundary(at) {
                at -= 1;
            }
            out[k] = format!("{}{junk}{}", &lines[k][..at], &lines[k][at..]);
        }
        8 => {
            let table = rng.pick(&[
                "[[axis]]",
                "[set.time]",
                "[set.model]",
                "[[plot]]",
                "[search]",
            ]);
            out.insert(k, format!("{table}\nkey = {}", rng.pick(VALUES)));
        }
        _ => {
            if let Some(start) = lines[k].find('"') {
                out[k] = format!("{}\"{}\"", &lines[k][..start], rng.pick(WORDS));
            }
        }
    }
    out.join("\n") + "\n"
}

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

const SWEEP: &str = r#"name = "fuzz_sweep"
base = "paper_f20.toml"
combine = "product"
quantities = [
    { kind = "frequency_range", link = 1, mode = 1 },
    { kind = "peak_axial_force", link = 2 },
    { kind = "buckling", link = 1 },
]
[set.output]
requests = ["frequencies"]
plots = false
[set.time]
end = 0.01
output_step = 1e-3
[[axis]]
key = "trajectory.frequency"
range = { start = 5.0, end = 30.0, count = 3 }
[[axis]]
key = "model.formulation"
values = ["paper", "consistent"]
[[plot]]
file = "f.svg"
x = "trajectory.frequency"
y = ["f_min_1_1_Hz"]
series = "model.formulation"
"#;

const SEARCH: &str = r#"name = "fuzz_search"
base = "coupled_f20.toml"
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

/// Whether the text is TOML, or else whether the parser gives the error a span.
fn toml_gives_a_place(text: &str) -> bool {
    match toml::from_str::<toml::Table>(text) {
        Ok(_) => true,
        Err(e) => e.span().is_some(),
    }
}

#[test]
fn mutated_studies_load_or_give_located_one_line_errors() {
    let mut seeds: Vec<(String, String)> = [
        "study_speed_sweep.toml",
        "study_thickness_payload.toml",
        "study_speed_limit.toml",
    ]
    .iter()
    .map(|n| {
        (
            n.to_string(),
            std::fs::read_to_string(configs().join(n)).unwrap(),
        )
    })
    .collect();
    seeds.push(("sweep.toml".into(), SWEEP.into()));
    seeds.push(("search.toml".into(), SEARCH.into()));
    seeds.push((
        "study_frequency_map.toml".into(),
        std::fs::read_to_string(configs().join("study_frequency_map.toml")).unwrap(),
    ));
    let mut rng = Lcg(0x5eed_57d1_0028);
    let (mut total, mut rejected) = (0usize, 0usize);
    for (name, original) in &seeds {
        for m in 0..MUTANTS_PER_SEED {
            let text = mutate(original, &mut rng);
            total += 1;
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                Study::from_text(name, "fuzz", &text, &configs())
            }));
            let result = outcome.unwrap_or_else(|_| panic!("{name} mutant {m} panicked:\n{text}"));
            let err = match result {
                Ok(study) => {
                    assert!(study.cases.len() <= MAX_CASES, "{name} mutant {m}");
                    for plot in &study.plots {
                        assert!(
                            !plot.file.contains('/') && !plot.file.starts_with('.'),
                            "{name} mutant {m}: plot file {}",
                            plot.file
                        );
                    }
                    continue;
                }
                Err(e) => e,
            };
            rejected += 1;
            let message = err.to_string();
            assert!(
                !message.contains('\n'),
                "{name} mutant {m}: {message}\n{text}"
            );
            assert!(
                !message.contains("internally tagged") && !message.contains("Config"),
                "{name} mutant {m}: Rust jargon in: {message}"
            );
            match &err {
                StudyError::Input { location, .. } if toml_gives_a_place(&text) => {
                    assert!(
                        location.is_some() || message.contains("base: missing"),
                        "{name} mutant {m}: no location in: {message}\n{text}"
                    );
                }
                StudyError::Scene(_) => {
                    assert!(
                        message.starts_with("base scene: "),
                        "{name} mutant {m}: {message}"
                    );
                }
                _ => {}
            }
        }
    }
    assert!(total >= 250, "only {total} mutants");
    assert!(
        rejected * 3 > total,
        "only {rejected} of {total} mutants were rejected"
    );
    assert!(rejected < total, "no mutant loaded");
}
