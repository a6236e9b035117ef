//! From TOML text to serde values with errors that give `file:line:column`, the dotted key
//! and what was expected in plain words.

use toml::de::{DeTable, DeValue};

use crate::error::ScenarioError;
use crate::locate::line_column;
use crate::schema::SceneFile;

/// Parses scene text into the raw [`SceneFile`]; syntax, unknown keys and wrong types are
/// [`ScenarioError::Input`] with line and column and the dotted key involved.
///
/// The TOML deserializer reports a byte span and a message but not the key path, so the
/// path is recovered from a span-preserving parse of the same text. Where
/// the deserializer only knows the enclosing table (an unknown key or an unknown variant
/// inside a tagged table), the offending key or value is searched for inside that table; a
/// missing key is named after the table that lacks it; a syntax error is named after the
/// key assigned (or the table opened) on its line.
///
/// # Errors
/// As described.
pub fn parse_scene(file: &str, text: &str) -> Result<SceneFile, ScenarioError> {
    parse_toml(file, text)
}

/// Parses any TOML input file (scenes, link files, studies) into `T`, turning serde's errors
/// into [`ScenarioError::Input`] with `file:line:column`, the dotted key and what was expected.
///
/// # Errors
/// As described.
pub fn parse_toml<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
) -> Result<T, ScenarioError> {
    toml::from_str(text).map_err(|e| {
        let message = plain_message(e.message().trim());
        let named = |prefix: &str| {
            message
                .strip_prefix(prefix)
                .and_then(|rest| rest.split('`').next())
                .map(str::to_string)
        };
        let syntax_error = DeTable::parse(text).is_err();
        let mut key = String::new();
        let mut missing_value = false;
        let mut unclosed_at = None;
        let location = e.span().map(|span| {
            let mut offset = span.start.min(text.len());
            if syntax_error {
                if let Some(opened) = unclosed_array_before(text, offset) {
                    // The parser trips over the line after an unclosed `[`; the array's own
                    // key is the one to blame, at its opening bracket.
                    key = key_on_line(text, opened);
                    unclosed_at = Some(line_column(text, opened).0);
                    offset = opened;
                } else {
                    key = key_on_line(text, offset);
                    missing_value = value_is_missing(text, offset);
                }
            } else if let Some(name) = named("unknown field `") {
                if let Some(found) = find_key_within(text, span.clone(), &name)
                    .or_else(|| find_key_from(text, offset, &name))
                {
                    offset = found;
                }
                key = key_path_at(text, offset..offset + 1);
                if !key.ends_with(name.as_str()) {
                    key = join_key(&key, &name);
                }
            } else if let Some(name) = named("missing field `") {
                key = join_key(&key_path_at(text, span.clone()), &name);
            } else {
                if let Some(variant) = named("unknown variant `") {
                    let quoted = [format!("\"{variant}\""), format!("'{variant}'")];
                    if let Some(found) = quoted.iter().find_map(|q| {
                        text.get(span.clone())
                            .and_then(|region| region.find(q.as_str()))
                    }) {
                        offset += found;
                    }
                }
                key = key_path_at(text, offset..offset + 1);
                // Inside a tagged table (trajectory, section, basis) the deserializer only
                // knows the table: find the entry holding the offending value.
                if let Some((found, entry)) = entry_with_value(text, &key, &message) {
                    offset = found;
                    key = join_key(&key, &entry);
                    // An unknown word is shown at the word.
                    if let Some(variant) = named("unknown variant `") {
                        let line_end = text[found..].find('\n').map_or(text.len(), |i| found + i);
                        if let Some(at) = text[found..line_end].find(variant.as_str()) {
                            offset = found + at.saturating_sub(1);
                        }
                    }
                }
            }
            let (line, column) = line_column(text, offset);
            crate::error::Location {
                file: file.to_string(),
                line,
                column,
            }
        });
        if key.is_empty() {
            if let Some(name) = named("missing field `") {
                key = name;
            }
        }
        // Without a span (e.g. nesting too deep) the file alone is the place.
        let message = if location.is_none() {
            format!("{file}: {message}")
        } else {
            message
        };
        let message = if let Some(line) = unclosed_at {
            format!("the array opened on line {line} is not closed with `]` ({message})")
        } else if missing_value {
            format!("expected a value after `=` ({message})")
        } else {
            message
        };
        ScenarioError::Input {
            location,
            key,
            message,
        }
    })
}

fn join_key(parent: &str, name: &str) -> String {
    if parent.is_empty() {
        name.to_string()
    } else {
        format!("{parent}.{name}")
    }
}

/// Dotted key path (array elements numbered from 0) of the deepest entry whose key or
/// value span holds all of `span` (byte offsets in `text`); empty when none does or `span`
/// is the root table's.
fn key_path_at(text: &str, span: std::ops::Range<usize>) -> String {
    fn holds(outer: std::ops::Range<usize>, inner: &std::ops::Range<usize>) -> bool {
        outer.start <= inner.start && inner.end <= outer.end.max(outer.start + 1)
    }
    fn search(value: &DeValue<'_>, span: &std::ops::Range<usize>, path: &mut Vec<String>) -> bool {
        match value {
            DeValue::Table(table) => {
                for (key, item) in table.iter() {
                    path.push(key.get_ref().to_string());
                    let covers = holds(key.span(), span) || holds(item.span(), span);
                    if search(item.get_ref(), span, path) || covers {
                        return true;
                    }
                    path.pop();
                }
                false
            }
            DeValue::Array(items) => {
                for (k, item) in items.iter().enumerate() {
                    path.push(k.to_string());
                    if search(item.get_ref(), span, path) || holds(item.span(), span) {
                        return true;
                    }
                    path.pop();
                }
                false
            }
            _ => false,
        }
    }
    let Ok(root) = DeTable::parse(text) else {
        return String::new();
    };
    if root.span() == span {
        // The deserializer names the root table (e.g. for a missing top-level table).
        return String::new();
    }
    let mut path = Vec::new();
    search(&DeValue::Table(root.into_inner()), &span, &mut path);
    path.join(".")
}

/// For an "invalid type" or "invalid value" message that names the offending value
/// (`` boolean `true` ``, `` string "0.1" ``, `` integer `-5` ``, `` floating point `0.5` ``),
/// the one entry of the table at `table_path` holding that value: its offset and name.
/// `None` when `table_path` is not a table, the message names no value, or the value is not
/// found exactly once.
fn entry_with_value(text: &str, table_path: &str, message: &str) -> Option<(usize, String)> {
    let literal = if let Some(rest) = message.strip_prefix("unknown variant `") {
        rest.split('`').next()?
    } else {
        let rest = message
            .strip_prefix("invalid type: ")
            .or_else(|| message.strip_prefix("invalid value: "))?;
        let described = rest.split(", expected").next()?;
        if let Some((_, quoted)) = described.split_once('"') {
            quoted.rsplit_once('"')?.0
        } else {
            described.split('`').nth(1)?
        }
    };
    let root = DeTable::parse(text).ok()?;
    let mut current = DeValue::Table(root.into_inner());
    for part in table_path.split('.').filter(|p| !p.is_empty()) {
        let next = match part.parse::<usize>() {
            Ok(index) => current.get(index),
            Err(_) => current.get(part),
        }?;
        current = next.get_ref().clone();
    }
    let DeValue::Table(table) = &current else {
        return None;
    };
    let same = |source: &str| {
        let source = source.trim();
        let unquoted = source.trim_matches(['"', '\'']);
        let as_number = |s: &str| s.replace('_', "").parse::<f64>().ok().map(f64::to_bits);
        unquoted == literal
            || (as_number(source).is_some() && as_number(source) == as_number(literal))
    };
    let mut hits = table.iter().filter(|(_, value)| {
        !matches!(value.get_ref(), DeValue::Table(_) | DeValue::Array(_))
            && text.get(value.span()).is_some_and(same)
    });
    let (key, _) = hits.next()?;
    if hits.next().is_some() {
        return None;
    }
    Some((key.span().start, key.get_ref().to_string()))
}

/// Byte offset of the `[` of an array value that is still open at `offset` and was opened on
/// an earlier line, if there is one (the outermost such array).
///
/// A small scanner over TOML's lexical rules: table headers and keys at line starts, basic
/// and literal strings (single- and triple-quoted), comments, and the brackets and braces of
/// values. It only has to be right up to the parser's error, which it is because everything
/// before that point parsed.
fn unclosed_array_before(text: &str, offset: usize) -> Option<usize> {
    let bytes = text.as_bytes();
    let end = offset.min(bytes.len());
    // Open `[` and `{` of values, innermost last.
    let mut open: Vec<(u8, usize)> = Vec::new();
    let mut at_line_start = true;
    let mut in_value = false;
    let mut i = 0;
    while i < end {
        let c = bytes[i];
        match c {
            b'\n' => {
                at_line_start = open.is_empty();
                if open.is_empty() {
                    in_value = false;
                }
                i += 1;
                continue;
            }
            b' ' | b'\t' | b'\r' => {
                i += 1;
                continue;
            }
            b'#' => {
                i = text[i..].find('\n').map_or(end, |n| i + n);
                continue;
            }
            b'"' | b'\'' => {
                let triple = bytes
                    .get(i..i + 3)
                    .is_some_and(|t| t.iter().all(|&b| b == c));
                let step = if triple { 3 } else { 1 };
                let mut j = i + step;
                loop {
                    if j >= bytes.len() {
                        return None;
                    }
                    if c == b'"' && bytes[j] == b'\\' {
                        j += 2;
                        continue;
                    }
                    if bytes[j] == c
                        && (!triple
                            || bytes
                                .get(j..j + 3)
                                .is_some_and(|t| t.iter().all(|&b| b == c)))
                    {
                        j += step;
                        break;
                    }
                    if !triple && bytes[j] == b'\n' {
                        break;
                    }
                    j += 1;
                }
                i = j;
                at_line_start = false;
                continue;
            }
            _ => {}
        }
        if at_line_start && c == b'[' && !in_value {
            // A table header: skip to the end of its line.
            i = text[i..].find('\n').map_or(end, |n| i + n);
            continue;
        }
        at_line_start = false;
        match c {
            b'=' if open.is_empty() || open.last().is_some_and(|(b, _)| *b == b'{') => {
                in_value = true;
            }
            b'[' | b'{' if in_value => open.push((c, i)),
            b']' | b'}' if in_value => {
                open.pop();
            }
            b',' if open.last().is_some_and(|(b, _)| *b == b'{') => in_value = false,
            _ => {}
        }
        i += 1;
    }
    let error_line_start = text[..end].rfind('\n').map_or(0, |n| n + 1);
    open.iter()
        .find(|(b, at)| *b == b'[' && *at < error_line_start)
        .map(|(_, at)| *at)
}

/// Whether the line holding `offset` is `key =` with nothing (or only a comment) after it.
fn value_is_missing(text: &str, offset: usize) -> bool {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next().unwrap_or("");
    match line.split_once('=') {
        Some((assigned, value)) => {
            !assigned.trim().is_empty()
                && !assigned.contains(['{', '[', '"'])
                && value.split('#').next().unwrap_or("").trim().is_empty()
        }
        None => false,
    }
}

/// For a syntax error at `offset`: the key assigned on that line (`key = ...`) or the table
/// opened there (`[table`), prefixed with the last table header above it.
fn key_on_line(text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    // An error at the end of a line belongs to that line.
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[line_start..]
        .find('\n')
        .map_or(text.len(), |i| line_start + i);
    let line = text[line_start..line_end].trim();
    let header_name = |l: &str| {
        l.trim_start_matches('[')
            .split([']', '#'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string()
    };
    if line.starts_with('[') {
        return header_name(line);
    }
    let assigned = line.split('=').next().unwrap_or("").trim();
    let table = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(header_name)
        .unwrap_or_default();
    if line.contains('=') {
        join_key(&table, assigned)
    } else {
        table
    }
}

/// Byte offset of `key =` inside `span` of `text` (e.g. in an inline table), if there.
fn find_key_within(text: &str, span: std::ops::Range<usize>, key: &str) -> Option<usize> {
    let end = span.end.min(text.len());
    let start = span.start.min(end);
    let region = text.get(start..end)?;
    let is_ident = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
    region.match_indices(key).find_map(|(at, _)| {
        let before_ok = region[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !is_ident(c));
        let after = &region[at + key.len()..];
        let after_ok = after.trim_start_matches([' ', '\t']).starts_with('=');
        (before_ok && after_ok).then_some(start + at)
    })
}

/// Byte offset of the first line at or after `from` that assigns `key`.
fn find_key_from(text: &str, from: usize, key: &str) -> Option<usize> {
    let line_start = text[..from.min(text.len())]
        .rfind('\n')
        .map_or(0, |i| i + 1);
    let mut offset = line_start;
    for line in text[line_start..].split_inclusive('\n') {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix(key) {
            if rest.trim_start().starts_with('=') {
                return Some(offset + (line.len() - trimmed.len()));
            }
        }
        offset += line.len();
    }
    None
}

/// Serde's wording made plain: one line, no Rust type names.
fn plain_message(message: &str) -> String {
    let one_line = message.split_whitespace().collect::<Vec<_>>().join(" ");
    if one_line.contains("recursion limit") {
        return "keys or tables nested too deeply (the parser's recursion limit); scene files \
                need at most a few levels"
            .to_string();
    }
    let mut out = one_line.replace(
        ", there are no fields",
        ": this table takes no keys besides its kind",
    );
    for (rust, plain) in [
        (
            "internally tagged enum TrajectoryConfig",
            "a trajectory table with kind one of circle, line, point-to-point, waypoints",
        ),
        (
            "internally tagged enum SectionConfig",
            "a section table with kind one of uniform, tapered, stepped",
        ),
    ] {
        out = out.replace(rust, plain);
    }
    // Any other Rust type name after "struct " or "enum ".
    for word in ["struct ", "enum "] {
        while let Some(at) = out.find(word) {
            let rest = &out[at + word.len()..];
            let end = rest
                .find(|c: char| !c.is_ascii_alphanumeric() && c != '_')
                .unwrap_or(rest.len());
            let name = &rest[..end];
            let plain = name
                .strip_suffix("Config")
                .or_else(|| name.strip_suffix("Choice"))
                .or_else(|| name.strip_suffix("Table"))
                .unwrap_or(name)
                .to_lowercase();
            out = format!("{}a {plain} table{}", &out[..at], &rest[end..]);
        }
    }
    out
}
