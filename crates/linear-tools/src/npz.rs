//! NumPy's `.npz` files, written without a dependency: a ZIP archive (stored, not
//! compressed) of `.npy` files, as `numpy.savez` writes them and `numpy.load` reads them.
//!
//! * `.npy`, format version 1.0 (NumPy, `numpy.lib.format`): the magic `\x93NUMPY`, the
//!   version bytes `1, 0`, a little-endian `u16` header length, then the header, an ASCII
//!   Python dict literal `{'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }`
//!   padded with spaces and ended by `\n` so that the data starts at a multiple of 64
//!   bytes; then the data in C (row-major) order. Strings are `<Un`: `n` UTF-32LE code
//!   points per entry, zero-padded.
//! * ZIP (PKWARE, *APPNOTE.TXT*, version 6.3): per entry a local file header (signature
//!   `0x04034b50`), the bytes; then the central directory (`0x02014b50` per entry) and the
//!   end-of-central-directory record (`0x06054b50`). Method 0 (stored), the CRC-32 of
//!   ISO 3309 (reflected polynomial `0xEDB88320`), DOS date 1980-01-01 so that the same
//!   arrays give the same bytes. No ZIP64: an archive over 4 GiB is refused.

/// The data of one array.
#[derive(Debug, Clone, PartialEq)]
pub enum NpyData {
    /// `float64` values in row-major order with their shape.
    F64 {
        /// The shape (`[rows, cols]`, `[n]`, ...).
        shape: Vec<usize>,
        /// The values, row-major.
        values: Vec<f64>,
    },
    /// A 1-D array of unicode strings (`<Un`, `n` the longest, at least 1).
    Unicode(Vec<String>),
}

impl NpyData {
    /// A matrix from a function of `(row, col)`.
    pub fn matrix(rows: usize, cols: usize, at: impl Fn(usize, usize) -> f64) -> Self {
        let values = (0..rows)
            .flat_map(|i| (0..cols).map(move |j| (i, j)))
            .map(|(i, j)| at(i, j))
            .collect();
        NpyData::F64 {
            shape: vec![rows, cols],
            values,
        }
    }

    /// A 1-D `float64` array.
    pub fn vector(values: &[f64]) -> Self {
        NpyData::F64 {
            shape: vec![values.len()],
            values: values.to_vec(),
        }
    }
}

/// The `.npy` bytes of `data`.
pub fn npy(data: &NpyData) -> Vec<u8> {
    let (descr, shape, body) = match data {
        NpyData::F64 { shape, values } => (
            "<f8".to_string(),
            shape.clone(),
            values
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect::<Vec<u8>>(),
        ),
        NpyData::Unicode(strings) => {
            let width = strings
                .iter()
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
                .max(1);
            let mut body = Vec::with_capacity(4 * width * strings.len());
            for s in strings {
                let mut count = 0;
                for c in s.chars() {
                    body.extend_from_slice(&u32::from(c).to_le_bytes());
                    count += 1;
                }
                body.resize(body.len() + 4 * (width - count), 0);
            }
            (format!("<U{width}"), vec![strings.len()], body)
        }
    };
    let shape = match shape.as_slice() {
        [n] => format!("({n},)"),
        dims => format!(
            "({})",
            dims.iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // magic (6) + version (2) + length (2) + header + '\n' is a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + body.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(&body);
    out
}

/// The CRC-32 table of the reflected polynomial `0xEDB88320`.
const fn crc_table() -> [u32; 256] {
    let mut table = [0u32; 256];
    let mut n = 0;
    while n < 256 {
        let mut c = n as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        table[n] = c;
        n += 1;
    }
    table
}

const CRC_TABLE: [u32; 256] = crc_table();

/// The CRC-32 (ISO 3309, as ZIP and PNG use it) of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |c, b| {
        CRC_TABLE[((c ^ u32::from(*b)) & 0xFF) as usize] ^ (c >> 8)
    })
}

/// DOS date of 1980-01-01 (`((year - 1980) << 9) | (month << 5) | day`), time 00:00.
const DOS_DATE: u16 = (1 << 5) | 1;

/// The `.npz` bytes of the named arrays (each stored as `NAME.npy`, read back by
/// `numpy.load(path)[NAME]`).
///
/// # Errors
/// A name that is empty, repeated or not a plain file name, or an archive that would need
/// ZIP64 (over 4 GiB or 65535 entries).
pub fn npz(arrays: &[(&str, NpyData)]) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    let mut central = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    if arrays.len() > usize::from(u16::MAX) {
        return Err(format!(
            "{} arrays: a .npz holds at most 65535",
            arrays.len()
        ));
    }
    for (name, data) in arrays {
        if name.is_empty() || name.contains(['/', '\\']) || !seen.insert(*name) {
            return Err(format!(
                "array name {name:?}: expected a distinct plain name"
            ));
        }
        let file = format!("{name}.npy");
        let bytes = npy(data);
        let too_big = |_| format!("{file}: over 4 GiB (ZIP64 is not written)");
        let size = u32::try_from(bytes.len()).map_err(too_big)?;
        let offset = u32::try_from(out.len()).map_err(too_big)?;
        let crc = crc32(&bytes);
        let name_len = file.len() as u16;
        // Local file header.
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        for field in [20u16, 0, 0, 0, DOS_DATE] {
            out.extend_from_slice(&field.to_le_bytes());
        }
        for field in [crc, size, size] {
            out.extend_from_slice(&field.to_le_bytes());
        }
        out.extend_from_slice(&name_len.to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(file.as_bytes());
        out.extend_from_slice(&bytes);
        // Its central directory entry.
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        for field in [20u16, 20, 0, 0, 0, DOS_DATE] {
            central.extend_from_slice(&field.to_le_bytes());
        }
        for field in [crc, size, size] {
            central.extend_from_slice(&field.to_le_bytes());
        }
        for field in [name_len, 0, 0, 0, 0] {
            central.extend_from_slice(&field.to_le_bytes());
        }
        central.extend_from_slice(&0u32.to_le_bytes());
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(file.as_bytes());
    }
    let too_big = |_| "the archive is over 4 GiB (ZIP64 is not written)".to_string();
    let directory_offset = u32::try_from(out.len()).map_err(too_big)?;
    let directory_size = u32::try_from(central.len()).map_err(too_big)?;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    let entries = arrays.len() as u16;
    for field in [0u16, 0, entries, entries] {
        out.extend_from_slice(&field.to_le_bytes());
    }
    out.extend_from_slice(&directory_size.to_le_bytes());
    out.extend_from_slice(&directory_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_of_the_check_string() {
        // The standard check value of CRC-32 (ISO 3309 / ITU-T V.42).
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn npy_headers_are_aligned_and_literal() {
        let bytes = npy(&NpyData::matrix(2, 3, |i, j| (i * 3 + j) as f64));
        let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + len) % 64, 0);
        let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
        assert!(header.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }"));
        assert!(header.ends_with('\n'));
        assert_eq!(bytes.len(), 10 + len + 6 * 8);
        assert_eq!(&bytes[10 + len + 8..10 + len + 16], &1.0f64.to_le_bytes());
        let names = npy(&NpyData::Unicode(vec!["ab".into(), "ρ".into()]));
        let len = u16::from_le_bytes([names[8], names[9]]) as usize;
        let header = std::str::from_utf8(&names[10..10 + len]).unwrap();
        assert!(header.contains("'descr': '<U2'") && header.contains("'shape': (2,)"));
        assert_eq!(
            &names[10 + len + 8..10 + len + 12],
            &0x03C1u32.to_le_bytes()
        );
        assert!(npz(&[("A", NpyData::vector(&[1.0])), ("A", NpyData::vector(&[]))]).is_err());
    }
}
