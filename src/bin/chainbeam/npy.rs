//! A writer of NumPy's `.npy` format, version 1.0, for one C-ordered array of little-endian
//! `float64` (`numpy.load` and Julia's `NPZ.npzread` read it directly).
//!
//! The format (numpy.lib.format, "NEP 1"): the magic string `\x93NUMPY`, the version bytes
//! `1 0`, a little-endian `u16` header length L, then L bytes of ASCII: a Python dict literal
//! `{'descr': '<f8', 'fortran_order': False, 'shape': (R, C), }` padded with spaces and ending in
//! `\n`, such that 10 + L is a multiple of 64 (the data is then 64-byte aligned); then the R·C
//! values, row after row, 8 bytes each, little-endian. Version 1.0 allows L < 65536, far more
//! than any shape needs.

use std::io::{self, Write};

/// The magic string that opens every `.npy` file.
pub const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The preamble (magic, version 1.0, header length, header) of a C-ordered `<f8` array of the
/// given shape.
pub fn header(shape: &[usize]) -> Vec<u8> {
    let dims = match shape {
        [d] => format!("({d},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}");
    // Pad with spaces so that magic (6) + version (2) + length (2) + dict + '\n' is a multiple
    // of 64.
    let unpadded = 10 + dict.len() + 1;
    dict.extend(std::iter::repeat_n(
        ' ',
        unpadded.next_multiple_of(64) - unpadded,
    ));
    dict.push('\n');
    let len = u16::try_from(dict.len()).expect("a .npy v1.0 header of a 2-D shape fits in u16");
    let mut out = Vec::with_capacity(10 + dict.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&[1, 0]);
    out.extend_from_slice(&len.to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out
}

/// Writes `row` as little-endian `f64`s (one row of the array, after [`header`]); `buf` is
/// scratch space reused between rows.
pub fn write_row(w: &mut dyn Write, buf: &mut Vec<u8>, row: &[f64]) -> io::Result<()> {
    buf.clear();
    for x in row {
        buf.extend_from_slice(&x.to_le_bytes());
    }
    w.write_all(buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header bytes against the format's definition (numpy.lib.format, version 1.0), and the
    /// header parsed back.
    #[test]
    fn header_follows_the_format() {
        let h = header(&[11, 34]);
        assert_eq!(&h[..6], b"\x93NUMPY");
        assert_eq!(&h[6..8], &[1, 0]);
        let len = u16::from_le_bytes([h[8], h[9]]) as usize;
        assert_eq!(h.len(), 10 + len);
        assert_eq!(h.len() % 64, 0, "data 64-byte aligned");
        let dict = std::str::from_utf8(&h[10..]).unwrap();
        assert!(dict.ends_with('\n'));
        assert_eq!(
            dict.trim_end(),
            "{'descr': '<f8', 'fortran_order': False, 'shape': (11, 34), }"
        );
        assert_eq!(
            std::str::from_utf8(&header(&[5])[10..]).unwrap().trim_end(),
            "{'descr': '<f8', 'fortran_order': False, 'shape': (5,), }"
        );
        // Lengths that land exactly on the boundary still end in '\n'.
        for r in [1, 9, 99, 999, 9999, 123_456_789] {
            let h = header(&[r, 7]);
            assert_eq!(h.len() % 64, 0);
            assert_eq!(h.last(), Some(&b'\n'));
        }
    }

    #[test]
    fn rows_are_little_endian_f64() {
        let mut out = Vec::new();
        let mut buf = Vec::new();
        write_row(&mut out, &mut buf, &[1.0, -0.5]).unwrap();
        assert_eq!(
            out,
            [0, 0, 0, 0, 0, 0, 0xf0, 0x3f, 0, 0, 0, 0, 0, 0, 0xe0, 0xbf]
        );
    }
}
