//! Changing one dotted key of a scene's TOML table, checked at once against the scene schema.
//!
//! Programs that edit scenes key by key (the Python `Scene.set`, a study's `[set]` table)
//! want a misspelt key or a value of the wrong type refused where it is written, not later
//! at a line of a regenerated file. The check reuses the schema itself ([`SceneFile`] through
//! serde, and the [`Registry`]'s basis keys): the edited top-level table is put into a
//! minimal complete scene and parsed, so the rules live once. Completeness (a key still
//! missing) and ranges are left to [`crate::Scene`]'s validation, because an edit made in
//! several steps is incomplete in between.

use crate::error::ScenarioError;
use crate::parse::parse_toml;
use crate::registry::{BasisParams, Registry, TableParams};
use crate::schema::SceneFile;

/// Sets the dotted `key` (table keys and array indices from 0, e.g.
/// `machine.legs.0.branch`) of a scene table to `value`, creating missing tables on the way.
/// An integer written where the table holds a float becomes a float. Nothing is checked
/// against the schema (see [`set_checked`]).
///
/// # Errors
/// A message when a segment is empty, an index is not a number or out of range, or a
/// segment goes through a value that is neither a table nor an array; the table is then
/// unchanged.
pub fn set_key(table: &mut toml::Table, key: &str, value: &toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(format!("key \"{key}\" has an empty segment"));
    }
    // Check the path before changing anything, so that a refused key leaves no new tables.
    let mut probe = table.clone();
    set_in_table(&mut probe, &parts, key, value)?;
    *table = probe;
    Ok(())
}

/// The value at the dotted `key` of a scene table, if it is there.
pub fn get_key<'a>(table: &'a toml::Table, key: &str) -> Option<&'a toml::Value> {
    let mut parts = key.split('.');
    let mut node = table.get(parts.next()?)?;
    for part in parts {
        node = match node {
            toml::Value::Table(t) => t.get(part)?,
            toml::Value::Array(a) => a.get(part.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(node)
}

/// As [`set_key`], then checks the key and the value's type against the scene schema (with
/// the built-in parts, [`Registry::default`]); on an error the table is left unchanged.
///
/// # Errors
/// [`ScenarioError::Input`] (without a location: the value was not written in a file) whose
/// key is `key` and whose message says what the schema expects there.
pub fn set_checked(
    table: &mut toml::Table,
    key: &str,
    value: &toml::Value,
) -> Result<(), ScenarioError> {
    set_checked_with(&Registry::default(), table, key, value)
}

/// As [`set_checked`], with the parts of `registry`.
///
/// # Errors
/// As [`set_checked`].
pub fn set_checked_with(
    registry: &Registry,
    table: &mut toml::Table,
    key: &str,
    value: &toml::Value,
) -> Result<(), ScenarioError> {
    let error = |message: String| ScenarioError::Input {
        location: None,
        key: key.to_string(),
        message,
    };
    // TOML tells integers and floats apart, a user does not: an integer goes in as a float
    // where the schema takes one, an integral float as an integer where it wants that.
    let alternative = match value {
        toml::Value::Integer(i) => Some(toml::Value::Float(*i as f64)),
        toml::Value::Float(x) if x.fract() == 0.0 && x.abs() < 9.0e15 => {
            Some(toml::Value::Integer(*x as i64))
        }
        _ => None,
    };
    let attempt = |v: &toml::Value| -> Result<toml::Table, ScenarioError> {
        let mut after = table.clone();
        set_key(&mut after, key, v).map_err(error)?;
        check_change(registry, table, &after, key)?;
        Ok(after)
    };
    let after = match (value, &alternative) {
        (toml::Value::Integer(_), Some(float)) => attempt(float).or_else(|_| attempt(value))?,
        (_, Some(integer)) => {
            attempt(value).or_else(|first| attempt(integer).map_err(|_| first))?
        }
        _ => attempt(value)?,
    };
    *table = after;
    Ok(())
}

/// Whether changing `key` turns `before` into `after` without a new schema error: an unknown
/// key or a value of the wrong type at or because of `key`. An error already in `before`,
/// and a key still missing, are not the change's (validation reports them).
///
/// # Errors
/// [`ScenarioError::Input`] at `key`, naming the schema's key if that is another one.
pub fn check_change(
    registry: &Registry,
    before: &toml::Table,
    after: &toml::Table,
    key: &str,
) -> Result<(), ScenarioError> {
    let top = key.split('.').next().unwrap_or_default();
    let Some(found) = schema_error(registry, after, top, key) else {
        return Ok(());
    };
    let (found_key, message) = match &found {
        ScenarioError::Input { key, message, .. } => (key.clone(), message.clone()),
        other => (String::new(), other.to_string()),
    };
    if message.starts_with("missing field") {
        return Ok(());
    }
    let same_before = schema_error(registry, before, top, key).is_some_and(|e| {
        matches!(e, ScenarioError::Input { key: k, message: m, .. } if k == found_key && m == message)
    });
    if same_before {
        return Ok(());
    }
    let inside = found_key == key || found_key.starts_with(&format!("{key}."));
    let message = if inside || found_key.is_empty() {
        if found_key.is_empty() || found_key == key {
            message
        } else {
            format!("{found_key}: {message}")
        }
    } else {
        let parent = found_key.rsplit_once('.').map_or(top, |(p, _)| p);
        format!(
            "setting it makes {found_key} wrong: {message}; to change several keys of a table \
             together, set the whole table (\"{parent}\" to a dict of its keys)"
        )
    };
    Err(ScenarioError::Input {
        location: None,
        key: key.to_string(),
        message,
    })
}

/// The first schema error of the top-level entry `top` of `table`, put into an otherwise
/// minimal complete scene; for the links, the control law and the vibration control law,
/// also the registered part's own keys (the basis kind's, the control law's, the vibration
/// law's against the scene's patches; reported only at or under `key`, since other errors
/// of the part may depend on keys set later).
fn schema_error(
    registry: &Registry,
    table: &toml::Table,
    top: &str,
    key: &str,
) -> Option<ScenarioError> {
    let mut probe = minimal_scene();
    match table.get(top) {
        Some(v) => {
            probe.insert(top.to_string(), v.clone());
        }
        None => {
            if !probe.contains_key(top) {
                return None;
            }
        }
    }
    // A vibration control law reads its keys against the patches, on the machine's links.
    if top == "vibration_control" {
        for part in ["links", "machine"] {
            if let Some(v) = table.get(part) {
                probe.insert(part.to_string(), v.clone());
            }
        }
    }
    let text = toml::to_string(&probe).ok()?;
    let file = "<set>";
    let parsed: SceneFile = match parse_toml(file, &text) {
        Ok(f) => f,
        Err(e) => return Some(e),
    };
    // The registered parts read their own keys: the basis of the links, the control law.
    let built = match top {
        "links" => {
            let links = &parsed.links;
            let params = BasisParams::new(file, &text, "links.basis", &links.basis.params);
            registry
                .build_basis(&params, &links.basis.kind, "links.modes", links.modes)
                .map(|_| ())
        }
        "control" => {
            let control = parsed.control.as_ref()?;
            let params = TableParams::new(file, &text, "control", &control.params);
            registry
                .build_controller(&params, &control.kind)
                .map(|_| ())
        }
        "actuators" => {
            let actuators = parsed.actuators.as_ref()?;
            let params = TableParams::new(file, &text, "actuators", &actuators.params);
            registry
                .build_actuator(&params, &actuators.kind)
                .map(|_| ())
        }
        "vibration_control" => {
            let c = crate::scene::Checker { file, text: &text };
            crate::scene::build_patches(&c, registry, &parsed)
        }
        _ => return None,
    };
    match built {
        Err(ScenarioError::Input {
            key: found,
            message,
            ..
        }) if found == key || found.starts_with(&format!("{key}.")) => Some(ScenarioError::Input {
            location: None,
            key: found,
            message,
        }),
        _ => None,
    }
}

/// The smallest complete scene: the two required tables, everything else by default.
fn minimal_scene() -> toml::Table {
    let mut trajectory = toml::Table::new();
    trajectory.insert("kind".into(), "circle".into());
    trajectory.insert("frequency".into(), 1.0.into());
    let mut time = toml::Table::new();
    time.insert("end".into(), 1.0.into());
    let mut scene = toml::Table::new();
    scene.insert("trajectory".into(), trajectory.into());
    scene.insert("time".into(), time.into());
    scene
}

fn coerce(old: Option<&toml::Value>, value: &toml::Value) -> toml::Value {
    match (old, value) {
        (Some(toml::Value::Float(_)), toml::Value::Integer(i)) => toml::Value::Float(*i as f64),
        _ => value.clone(),
    }
}

fn set_in_table(
    table: &mut toml::Table,
    parts: &[&str],
    key: &str,
    value: &toml::Value,
) -> Result<(), String> {
    let Some((first, rest)) = parts.split_first() else {
        return Err(format!("key \"{key}\" is empty"));
    };
    if rest.is_empty() {
        let new = coerce(table.get(*first), value);
        table.insert((*first).to_string(), new);
        return Ok(());
    }
    if !table.contains_key(*first) && rest.first().is_some_and(|p| p.parse::<usize>().is_ok()) {
        return Err(format!(
            "\"{key}\": there is no array `{first}` whose element could be set; give the whole \
             array first (in a study: in the base scene or in [set]) to vary one element"
        ));
    }
    let child = table
        .entry((*first).to_string())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    set_in_value(child, rest, key, value)
}

fn set_in_value(
    node: &mut toml::Value,
    parts: &[&str],
    key: &str,
    value: &toml::Value,
) -> Result<(), String> {
    match node {
        toml::Value::Table(t) => set_in_table(t, parts, key, value),
        toml::Value::Array(a) => {
            let Some((first, rest)) = parts.split_first() else {
                return Err(format!("key \"{key}\" is empty"));
            };
            let index: usize = first
                .parse()
                .map_err(|_| format!("\"{first}\" in \"{key}\" is not an array index"))?;
            let len = a.len();
            let slot = a.get_mut(index).ok_or_else(|| {
                format!("index {index} in \"{key}\" is out of range (length {len})")
            })?;
            if rest.is_empty() {
                *slot = coerce(Some(&*slot), value);
                Ok(())
            } else {
                set_in_value(slot, rest, key, value)
            }
        }
        _ => Err(format!(
            "\"{key}\": \"{}\" is not inside a table or an array",
            parts.first().copied().unwrap_or_default()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> toml::Table {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../configs/paper_f20.toml"
        ))
        .unwrap();
        text.parse().unwrap()
    }

    fn refused(key: &str, value: toml::Value) -> (String, String) {
        let mut table = paper();
        let before = table.clone();
        match set_checked(&mut table, key, &value) {
            Err(ScenarioError::Input {
                key,
                message,
                location,
            }) => {
                assert!(location.is_none());
                assert_eq!(table, before, "a refused set changed the table");
                (key, message)
            }
            other => panic!("{key} = {value:?} accepted: {other:?}"),
        }
    }

    /// `Scene.set` accepted unknown `vibration_control` keys (issue 34): the law's own keys
    /// are now checked at once, against the scene's patches, as validation checks them.
    #[test]
    fn vibration_control_keys_and_types_are_checked_at_once() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../configs/piezo_f20.toml"
        ))
        .unwrap();
        let piezo: toml::Table = text.parse().unwrap();
        let mut table = piezo.clone();
        let e = set_checked(&mut table, "vibration_control.gian", &0.01.into()).unwrap_err();
        assert!(
            matches!(&e, ScenarioError::Input { key, message, .. }
                if key == "vibration_control.gian" && message.contains("unknown field `gian`")),
            "{e}"
        );
        assert_eq!(table, piezo, "a refused set changed the table");
        let e = set_checked(&mut table, "vibration_control.gain", &"high".into()).unwrap_err();
        assert!(
            matches!(&e, ScenarioError::Input { key, .. } if key == "vibration_control.gain"),
            "{e}"
        );
        set_checked(&mut table, "vibration_control.gain", &0.01.into()).unwrap();
        set_checked(&mut table, "vibration_control.period", &1e-4.into()).unwrap();
    }

    #[test]
    fn unknown_keys_are_refused_at_once() {
        let (key, message) = refused("links.nope", 1.0.into());
        assert_eq!(key, "links.nope");
        assert!(message.contains("unknown field `nope`"), "{message}");
        let (key, message) = refused("nope", 1.0.into());
        assert_eq!(key, "nope");
        assert!(message.contains("unknown field"), "{message}");
        let (key, _) = refused("links.section.width", 1.0.into());
        assert_eq!(key, "links.section.width");
        let (key, message) = refused("links.basis.nope", 1.into());
        assert_eq!(key, "links.basis.nope");
        assert!(message.contains("nope"), "{message}");
    }

    #[test]
    fn wrong_types_are_refused_at_once() {
        let (key, message) = refused("links.length", "abc".into());
        assert_eq!(key, "links.length");
        assert!(message.contains("string \"abc\""), "{message}");
        let (_, message) = refused("output.plots", 1.0.into());
        assert!(message.contains("bool"), "{message}");
        let (key, _) = refused(
            "output.requests",
            toml::Value::Array(vec!["nothing".into()]),
        );
        assert_eq!(key, "output.requests");
        let (key, message) = refused("trajectory.kind", "line".into());
        assert_eq!(key, "trajectory.kind");
        assert!(message.contains("set the whole table"), "{message}");
    }

    #[test]
    fn good_values_are_set_and_ints_become_floats() {
        let mut table = paper();
        set_checked(&mut table, "links.section.thickness", &3.into()).unwrap();
        assert_eq!(
            get_key(&table, "links.section.thickness"),
            Some(&toml::Value::Float(3.0))
        );
        // absent from the file: the schema says float
        set_checked(&mut table, "machine.platform_inertia", &1.into()).unwrap();
        assert_eq!(
            get_key(&table, "machine.platform_inertia"),
            Some(&toml::Value::Float(1.0))
        );
        // ranges are validation's: a negative thickness is a float
        set_checked(&mut table, "links.section.thickness", &(-1.0).into()).unwrap();
        set_checked(&mut table, "integrator.max_steps", &50.into()).unwrap();
        assert_eq!(
            get_key(&table, "integrator.max_steps"),
            Some(&toml::Value::Integer(50))
        );
        // and an integral float where the schema wants an integer
        set_checked(&mut table, "integrator.max_steps", &1e6.into()).unwrap();
        assert_eq!(
            get_key(&table, "integrator.max_steps"),
            Some(&toml::Value::Integer(1_000_000))
        );
        let (key, _) = refused("integrator.max_steps", 2.5.into());
        assert_eq!(key, "integrator.max_steps");
    }

    #[test]
    fn errors_already_there_do_not_block_other_keys() {
        let mut table = paper();
        set_key(&mut table, "links.nope", &1.0.into()).unwrap();
        // the existing unknown key is not this change's fault
        set_checked(&mut table, "links.length", &0.25.into()).unwrap();
        // a scene built key by key is incomplete in between
        let mut empty = toml::Table::new();
        set_checked(&mut empty, "time.start", &0.0.into()).unwrap();
        set_checked(&mut empty, "trajectory.kind", &"line".into()).unwrap();
    }

    #[test]
    fn bad_paths_leave_the_table_unchanged() {
        let mut table = paper();
        let before = table.clone();
        assert!(set_key(&mut table, "name.first.x", &1.into()).is_err());
        assert!(set_key(&mut table, "links..x", &1.into()).is_err());
        assert!(set_key(&mut table, "machine.alpha_deg.7", &1.into()).is_err());
        // An element of an array that is not there: no table named `legs` with a key `0`.
        let missing = set_key(&mut table, "machine.legs.0.branch", &"elbow".into()).unwrap_err();
        assert!(missing.contains("no array `legs`"), "{missing}");
        assert_eq!(table, before);
    }
}
