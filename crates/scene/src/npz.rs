//! Reading NumPy's `.npz` files (a ZIP archive of `.npy` arrays, as `numpy.savez` writes
//! them) without a dependency: the ZIP's central directory (PKWARE APPNOTE 6.3, sections
//! 4.3.7, 4.3.12, 4.3.16) and the `.npy` format version 1-3 (NumPy's `format` module
//! documentation). Stored (uncompressed) members only: `numpy.savez_compressed` is refused
//! with that advice.

use std::collections::BTreeMap;

/// One array: its shape and its entries in row-major (C) order, as `f64`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Array {
    pub(crate) shape: Vec<usize>,
    pub(crate) data: Vec<f64>,
}

fn u16_at(b: &[u8], at: usize) -> Result<usize, String> {
    b.get(at..at + 2)
        .map(|s| usize::from(u16::from_le_bytes([s[0], s[1]])))
        .ok_or_else(|| "truncated".to_string())
}

fn u32_at(b: &[u8], at: usize) -> Result<usize, String> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize)
        .ok_or_else(|| "truncated".to_string())
}

/// The arrays of an `.npz` file's bytes, by name (without `.npy`).
///
/// # Errors
/// A message saying why the bytes are not an `.npz` of numeric arrays.
pub(crate) fn read(bytes: &[u8]) -> Result<BTreeMap<String, Array>, String> {
    const END: [u8; 4] = [0x50, 0x4b, 0x05, 0x06];
    if bytes.len() < 22 || !bytes.starts_with(b"PK") {
        return Err("not an .npz file (not a ZIP archive, as numpy.savez writes)".into());
    }
    // The end of central directory record: the last signature within the comment's reach.
    let from = bytes.len().saturating_sub(22 + 65535);
    let end = (from..=bytes.len() - 22)
        .rev()
        .find(|&i| bytes[i..i + 4] == END)
        .ok_or("not an .npz file (no ZIP directory)")?;
    let count = u16_at(bytes, end + 10)?;
    let mut at = u32_at(bytes, end + 16)?;
    let mut arrays = BTreeMap::new();
    for _ in 0..count {
        if bytes.get(at..at + 4) != Some(&[0x50, 0x4b, 0x01, 0x02][..]) {
            return Err("a damaged ZIP directory".into());
        }
        let method = u16_at(bytes, at + 10)?;
        let size = u32_at(bytes, at + 20)?;
        let (name_len, extra, comment) = (
            u16_at(bytes, at + 28)?,
            u16_at(bytes, at + 30)?,
            u16_at(bytes, at + 32)?,
        );
        let local = u32_at(bytes, at + 42)?;
        let name = String::from_utf8_lossy(
            bytes
                .get(at + 46..at + 46 + name_len)
                .ok_or("a damaged ZIP directory")?,
        )
        .into_owned();
        at += 46 + name_len + extra + comment;
        let Some(stem) = name.strip_suffix(".npy") else {
            continue;
        };
        if method != 0 {
            return Err(format!(
                "array {stem} is compressed (numpy.savez_compressed): save the law with numpy.savez"
            ));
        }
        if size == 0xffff_ffff {
            return Err(format!("array {stem} is too large (ZIP64)"));
        }
        let start = local + 30 + u16_at(bytes, local + 26)? + u16_at(bytes, local + 28)?;
        let member = bytes
            .get(start..start + size)
            .ok_or_else(|| format!("array {stem} is truncated"))?;
        let array = npy(member).map_err(|e| format!("array {stem}: {e}"))?;
        arrays.insert(stem.to_string(), array);
    }
    Ok(arrays)
}

/// One `.npy` member.
fn npy(b: &[u8]) -> Result<Array, String> {
    if !b.starts_with(b"\x93NUMPY") || b.len() < 10 {
        return Err("not a .npy array".into());
    }
    let (len, start) = match b[6] {
        1 => (u16_at(b, 8)?, 10),
        2 | 3 => (u32_at(b, 8)?, 12),
        v => return Err(format!(".npy version {v} is not known")),
    };
    let header = std::str::from_utf8(b.get(start..start + len).ok_or("truncated header")?)
        .map_err(|_| "a header that is not text")?;
    let field = |key: &str| -> Result<&str, String> {
        let at = header
            .find(&format!("'{key}'"))
            .ok_or_else(|| format!("no {key} in the header"))?;
        let rest = header[at + key.len() + 2..].trim_start();
        Ok(rest.strip_prefix(':').unwrap_or(rest).trim_start())
    };
    let descr = field("descr")?;
    let descr = descr
        .strip_prefix('\'')
        .and_then(|d| d.split('\'').next())
        .ok_or("a malformed descr")?;
    if field("fortran_order")?.starts_with("True") {
        return Err("Fortran order: save a C-ordered array (numpy.ascontiguousarray)".into());
    }
    let shape = field("shape")?;
    let shape = shape
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or("a malformed shape")?;
    let shape: Vec<usize> = shape
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| "a malformed shape".to_string())
        })
        .collect::<Result<_, _>>()?;
    let count: usize = shape.iter().product();
    let body = &b[start + len..];
    let (width, little) = match descr.get(1..) {
        Some("f8" | "i8" | "u8") => (8, descr.starts_with('<') || descr.starts_with('|')),
        Some("f4" | "i4" | "u4") => (4, descr.starts_with('<') || descr.starts_with('|')),
        _ => {
            return Err(format!(
                "dtype {descr} is not numeric: save float64 arrays (numpy.asarray(x, dtype=float))"
            ));
        }
    };
    if !little {
        return Err(format!(
            "dtype {descr} is big-endian: save little-endian float64"
        ));
    }
    if body.len() < count * width {
        return Err("truncated data".into());
    }
    let kind = &descr[1..2];
    let data = body
        .chunks_exact(width)
        .take(count)
        .map(|c| match (kind, width) {
            ("f", 8) => f64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
            ("i", 8) => i64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f64,
            ("u", 8) => u64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f64,
            ("f", _) => f64::from(f32::from_le_bytes(c.try_into().unwrap_or([0; 4]))),
            ("i", _) => f64::from(i32::from_le_bytes(c.try_into().unwrap_or([0; 4]))),
            _ => f64::from(u32::from_le_bytes(c.try_into().unwrap_or([0; 4]))),
        })
        .collect();
    Ok(Array { shape, data })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stored ZIP of `.npy` members, built here (local headers, directory, end record).
    fn zip(members: &[(&str, Vec<u8>)]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut directory = Vec::new();
        for (name, data) in members {
            let offset = out.len() as u32;
            let n = name.len() as u16;
            let size = data.len() as u32;
            out.extend_from_slice(&[0x50, 0x4b, 0x03, 0x04, 20, 0, 0, 0, 0, 0]);
            out.extend_from_slice(&[0; 8]);
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&size.to_le_bytes());
            out.extend_from_slice(&n.to_le_bytes());
            out.extend_from_slice(&0u16.to_le_bytes());
            out.extend_from_slice(name.as_bytes());
            out.extend_from_slice(data);
            directory.extend_from_slice(&[0x50, 0x4b, 0x01, 0x02, 20, 0, 20, 0, 0, 0, 0, 0]);
            directory.extend_from_slice(&[0; 8]);
            directory.extend_from_slice(&size.to_le_bytes());
            directory.extend_from_slice(&size.to_le_bytes());
            directory.extend_from_slice(&n.to_le_bytes());
            directory.extend_from_slice(&[0; 12]);
            directory.extend_from_slice(&offset.to_le_bytes());
            directory.extend_from_slice(name.as_bytes());
        }
        let at = out.len() as u32;
        let len = directory.len() as u32;
        out.extend_from_slice(&directory);
        let k = members.len() as u16;
        out.extend_from_slice(&[0x50, 0x4b, 0x05, 0x06, 0, 0, 0, 0]);
        out.extend_from_slice(&k.to_le_bytes());
        out.extend_from_slice(&k.to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&at.to_le_bytes());
        out.extend_from_slice(&[0, 0]);
        out
    }

    fn npy_bytes(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn reads_float_and_integer_arrays_and_scalars() {
        let d: Vec<u8> = [1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let i: Vec<u8> = [7i64].iter().flat_map(|x| x.to_le_bytes()).collect();
        let bytes = zip(&[
            ("D.npy", npy_bytes("<f8", "(2, 3)", &d)),
            ("dt.npy", npy_bytes("<f8", "()", &0.5f64.to_le_bytes())),
            ("n.npy", npy_bytes("<i8", "(1,)", &i)),
        ]);
        let arrays = read(&bytes).unwrap();
        assert_eq!(arrays["D"].shape, vec![2, 3]);
        assert!((arrays["D"].data[5] - 6.0).abs() < 1e-15);
        assert!(arrays["dt"].shape.is_empty());
        assert!((arrays["dt"].data[0] - 0.5).abs() < 1e-15);
        assert!((arrays["n"].data[0] - 7.0).abs() < 1e-15);
    }

    #[test]
    fn other_files_are_refused_with_the_reason() {
        assert!(
            read(b"just text, not a zip")
                .unwrap_err()
                .contains("not an .npz")
        );
        let bytes = zip(&[("s.npy", npy_bytes("<U3", "(1,)", &[0; 12]))]);
        assert!(read(&bytes).unwrap_err().contains("not numeric"));
    }
}
