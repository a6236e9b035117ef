//! Mutation fuzzing of the shipped input files: every scene in `configs/` and
//! `configs/stress/`, and the link file, edited at random (a deterministic generator, so a
//! failure is reproducible from the printed mutant number) and only parsed and validated,
//! never run.
//!
//! Laws checked for every mutant: no panic; an error is one line; an error of bad input
//! carries a `file:line:column` location whenever the TOML parser gives a span (every
//! syntax error) or the file is valid TOML (every key the validator names is in the text,
//! or it names the table that holds the problem).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use flexprr_scene::link::{MaterialConfig, SectionConfig, check_link};
use flexprr_scene::{
    BasisParams, BasisTable, ModeCount, Registry, ScenarioError, Scene, parse_toml,
};
use flexprr_testkit::fuzz::Lcg;

/// Mutants per input file (about 20 files: well over 500 in all).
const MUTANTS_PER_FILE: usize = 24;

const VALUES: &[&str] = &[
    "0",
    "-1",
    "0.0",
    "-0.0",
    "1e300",
    "1e-300",
    "nan",
    "inf",
    "-inf",
    "\"x\"",
    "true",
    "[]",
    "{}",
    "[1, 2]",
    "817.0",
    "1e9",
    "99999999999999999999",
    "\"../../x\"",
    "\"\"",
    "'a b'",
];

const WORDS: &[&str] = &[
    "kind",
    "ends",
    "elements",
    "modes",
    "name",
    "stops",
    "rtol",
    "atol",
    "output_step",
    "thickness",
    "height",
    "method",
    "layout",
    "branch",
    "profile",
    "axial_force",
    "coupling",
    "requests",
    "formulation",
    "geometric_stiffness",
    "bogus",
];

/// One random edit of `text`.
fn mutate(text: &str, rng: &mut Lcg) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let k = rng.below(lines.len());
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    match rng.below(9) {
        // Replace the value of an assignment.
        0 | 1 => {
            if let Some((key, _)) = lines[k].split_once('=') {
                out[k] = format!("{key}= {}", rng.pick(VALUES));
            }
        }
        // Delete a line.
        2 => {
            out.remove(k);
        }
        // Duplicate a line (duplicate keys, duplicate tables).
        3 => out.insert(k, lines[k].to_string()),
        // Add a key, known somewhere or unknown.
        4 => out.insert(k, format!("{} = {}", rng.pick(WORDS), rng.pick(VALUES))),
        // Replace a word inside a string value.
        5 => {
            if let Some(start) = lines[k].find('"') {
                out[k] = format!("{}\"{}\"", &lines[k][..start], rng.pick(WORDS));
            }
        }
        // Truncate the file.
        6 => {
            let cut = rng.below(text.len());
            let mut cut = cut;
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_string();
        }
        // Break the syntax of a line.
        7 => {
            let junk = rng.pick(&["[", "]", "{", "=", "\"", "[[", ",", "a.b.c = 1", "#"]);
            let at = rng.below(lines[k].len() + 1);
            let mut at = at;
            while !lines[k].is_char_boundary(at) {
                at -= 1;
            }
            out[k] = format!("{}{junk}{}", &lines[k][..at], &lines[k][at..]);
        }
        // A deeply dotted key.
        _ => out.insert(k, format!("{} = 1", vec!["a"; 200].join("."))),
    }
    out.join("\n") + "\n"
}

fn configs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs")
}

fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("configs directory")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

/// Whether the text is TOML, or else whether the parser gives the error a span.
fn toml_gives_a_place(text: &str) -> bool {
    match toml::from_str::<toml::Table>(text) {
        Ok(_) => true,
        Err(e) => e.span().is_some(),
    }
}

/// A single-link file, as `flexprr beam` reads it (mirrored from the CLI with the crate's
/// public tables).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct LinkFile {
    length: f64,
    modes: usize,
    #[serde(default)]
    coupling: Option<String>,
    material: MaterialConfig,
    section: SectionConfig,
    basis: BasisTable,
    #[serde(default)]
    load: Option<toml::Table>,
}

fn check_link_file(registry: &Registry, file: &str, text: &str) -> Result<(), ScenarioError> {
    let link: LinkFile = parse_toml(file, text)?;
    let located = |key: &str, message: String| ScenarioError::Input {
        location: flexprr_scene::locate(file, text, key),
        key: key.to_string(),
        message,
    };
    check_link(&link.material, &link.section, link.length).map_err(|(k, m)| located(&k, m))?;
    let params = BasisParams::new(file, text, "basis", &link.basis.params);
    let sized = registry
        .basis(&link.basis.kind)
        .is_none_or(|f| f.mode_count() == ModeCount::FromModes);
    registry.build_basis(
        &params,
        &link.basis.kind,
        "modes",
        sized.then_some(link.modes),
    )?;
    Ok(())
}

#[test]
fn mutated_inputs_give_located_one_line_errors_and_never_panic() {
    let registry = Registry::default();
    let mut files = toml_files(&configs());
    files.extend(toml_files(&configs().join("stress")));
    let mut rng = Lcg(0x5eed_f1e4_0001);
    let (mut total, mut rejected) = (0usize, 0usize);
    for path in &files {
        let original = std::fs::read_to_string(path).expect("readable config");
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("?");
        let is_link = name.starts_with("link");
        let is_study = name.starts_with("study");
        if is_study {
            continue;
        }
        for m in 0..MUTANTS_PER_FILE {
            let text = mutate(&original, &mut rng);
            total += 1;
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                if is_link {
                    check_link_file(&registry, name, &text)
                } else {
                    Scene::from_text(name, "fuzz", &text).map(|_| ())
                }
            }));
            let result = outcome.unwrap_or_else(|_| panic!("{name} mutant {m} panicked:\n{text}"));
            let Err(err) = result else { continue };
            rejected += 1;
            let message = err.to_string();
            assert!(
                !message.contains('\n'),
                "{name} mutant {m}: a multi-line error: {message}\n{text}"
            );
            assert!(
                !message.contains("internally tagged") && !message.contains("Config"),
                "{name} mutant {m}: Rust jargon in: {message}"
            );
            if let ScenarioError::Input { location, .. } = &err {
                if toml_gives_a_place(&text) {
                    assert!(
                        location.is_some(),
                        "{name} mutant {m}: no location in: {message}\n{text}"
                    );
                }
            }
        }
    }
    assert!(total >= 500, "only {total} mutants");
    // The generator must produce bad input most of the time, or it tests little.
    assert!(
        rejected * 2 > total,
        "only {rejected} of {total} mutants were rejected"
    );
}
