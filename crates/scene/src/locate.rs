//! Finding a dotted key path in TOML source, for error messages with line and column.

use toml::de::{DeTable, DeValue};

use crate::error::Location;

/// Line and column (1-based) of a byte offset.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, column)
}

/// The location of the key path `path` (dot-separated; numeric parts index arrays) in `text`:
/// the deepest part of the path that exists. `None` if the text does not parse.
pub fn locate(file: &str, text: &str, path: &str) -> Option<Location> {
    locate_impl(file, text, path, false)
}

/// As [`locate`], but at the value of the last part of the path when it is there (for an
/// unknown word, the word itself).
pub fn locate_value(file: &str, text: &str, path: &str) -> Option<Location> {
    locate_impl(file, text, path, true)
}

fn locate_impl(file: &str, text: &str, path: &str, at_value: bool) -> Option<Location> {
    let parts: Vec<&str> = path.split('.').filter(|p| !p.is_empty()).collect();
    let root = DeTable::parse(text).ok()?;
    let root_span = root.span();
    let mut current = DeValue::Table(root.into_inner());
    let mut span = root_span;
    let mut found_any = false;
    for (k, part) in parts.iter().copied().enumerate() {
        let next = if let Ok(index) = part.parse::<usize>() {
            current.get(index)
        } else {
            // Key spans point at the key itself, which reads best in a message.
            if let DeValue::Table(table) = &current {
                if let Some((key, _)) = table.iter().find(|(k, _)| k.get_ref().as_ref() == part) {
                    span = key.span();
                }
            }
            current.get(part)
        };
        match next {
            Some(value) => {
                if part.parse::<usize>().is_ok() || (at_value && k + 1 == parts.len()) {
                    span = value.span();
                }
                current = value.get_ref().clone();
                found_any = true;
            }
            None => break,
        }
    }
    if !found_any {
        return None;
    }
    let (line, column) = line_column(text, span.start);
    Some(Location {
        file: file.to_string(),
        line,
        column,
    })
}
