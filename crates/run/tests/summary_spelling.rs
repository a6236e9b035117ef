//! `summary.json` speaks the scene's language: every word a shipped scene file chose is
//! echoed with the scene's own spelling (`"paper"`, never `"Paper"`), and the words of the
//! `formulation` block are ones a scene file accepts back, giving the same formulation.

use std::path::{Path, PathBuf};

use flexprr_run::{RunResult, summary_json};
use flexprr_scene::{InputKind, Scene};
use serde_json::Value;

fn scene_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
    let mut files = Vec::new();
    for dir in [root.clone(), root.join("stress")] {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let text = std::fs::read_to_string(&path).unwrap();
                if InputKind::of(&text) == InputKind::Scene {
                    files.push(path);
                }
            }
        }
    }
    files.sort();
    files
}

/// Every string of the TOML document with its key path, e.g. `model.formulation`.
fn strings(prefix: &str, value: &toml::Value, out: &mut Vec<(String, String)>) {
    match value {
        toml::Value::String(s) => out.push((prefix.to_string(), s.clone())),
        toml::Value::Table(t) => {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                strings(&key, v, out);
            }
        }
        toml::Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                strings(&format!("{prefix}.{i}"), v, out);
            }
        }
        _ => {}
    }
}

fn at<'a>(json: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('.')
        .try_fold(json, |v, key| match key.parse::<usize>() {
            Ok(i) if v.is_array() => v.get(i),
            _ => v.get(key),
        })
}

#[test]
fn summary_echoes_every_word_with_the_scene_spelling() {
    let mut checked = 0;
    for path in scene_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        // (A stress scene may be refused on purpose, e.g. near a singularity.)
        let Ok(scene) = Scene::load(&path) else {
            continue;
        };
        checked += 1;
        let summary = summary_json(&scene, &RunResult::default(), None);
        let document: toml::Value = toml::from_str(&text).unwrap();
        let mut words = Vec::new();
        strings("", &document, &mut words);
        for (key, word) in words {
            let echoed = at(&summary["scene_file"], &key)
                .unwrap_or_else(|| panic!("{}: {key} not echoed", path.display()));
            assert_eq!(echoed, &Value::String(word), "{}: {key}", path.display());
        }

        // The formulation block's words, written back into the scene, are accepted and
        // give the same formulation.
        let f = &summary["formulation"];
        if f["coupling"] == "ked" {
            let mut doc = document.clone();
            let model = doc
                .as_table_mut()
                .unwrap()
                .entry("model")
                .or_insert_with(|| toml::Value::Table(Default::default()))
                .as_table_mut()
                .unwrap();
            for key in ["axial_force", "geometric_stiffness", "coupling"] {
                let word = f[key].as_str().unwrap().to_string();
                assert_eq!(word, word.to_lowercase(), "{}: {key}", path.display());
                model.insert(key.into(), toml::Value::String(word));
            }
            let name = f["name"].as_str().unwrap();
            if name != "custom" {
                model.insert("formulation".into(), toml::Value::String(name.into()));
            }
            let again = Scene::from_text("echo.toml", "echo", &toml::to_string(&doc).unwrap())
                .unwrap_or_else(|e| panic!("{}: echo refused: {e}", path.display()));
            let g = summary_json(&again, &RunResult::default(), None);
            assert_eq!(g["formulation"], *f, "{}", path.display());
        }
    }
    assert!(checked > 10, "only {checked} scenes checked");
}
