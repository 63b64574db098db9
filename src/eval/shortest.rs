//! The values `hairfit eval` appends: each f64's shortest round-trip text, as ryu writes it
//! (`0.001234`, `12.5`, `1e-7`, `1.5e16`), written by zmij, which finds the same digits about
//! twice as fast and lays them out the same way except for a `+` in positive exponents.

/// Append `v` (finite) as ryu's `format_finite` writes it.
pub(super) fn push_shortest(out: &mut Vec<u8>, buf: &mut zmij::Buffer, v: f64) {
    let text = buf.format_finite(v).as_bytes();
    // zmij writes `1.5e+16` where ryu writes `1.5e16`; no other text holds a `+`. Both write
    // exponents from 16 up only (1e15 is `1000000000000000.0`), so it is among the last four
    // bytes: the scan of the whole text was half the time of writing the rows.
    let tail = text.len().saturating_sub(4);
    match text[tail..].iter().position(|&b| b == b'+') {
        Some(at) => {
            let plus = tail + at;
            out.extend_from_slice(&text[..plus]);
            out.extend_from_slice(&text[plus + 1..]);
        }
        None => out.extend_from_slice(text),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Byte for byte ryu's text: on random bit patterns (every exponent, subnormals) and on
    /// values like the model's (17 significant digits between 1e-20 and 1e20), plus the edges
    /// of ryu's fixed-notation range.
    #[test]
    fn the_text_is_ryus() {
        let mut ryu_buf = ryu::Buffer::new();
        let mut zmij_buf = zmij::Buffer::new();
        let mut out = Vec::new();
        let mut check = |v: f64| {
            if !v.is_finite() {
                return;
            }
            out.clear();
            push_shortest(&mut out, &mut zmij_buf, v);
            assert_eq!(out, ryu_buf.format_finite(v).as_bytes(), "{v:e}");
        };
        let mut h: u64 = 0x2545_F491_4F6C_DD1D;
        for i in 0..1_000_000u64 {
            h ^= h << 13;
            h ^= h >> 7;
            h ^= h << 17;
            check(f64::from_bits(h));
            let unit = (h >> 11) as f64 / (1u64 << 53) as f64;
            check(-unit * 10f64.powi((i % 41) as i32 - 20));
        }
        for e in -8..=20 {
            for m in [1.0, 1.5, 9.999999999999998, 123.456] {
                check(m * 10f64.powi(e));
            }
        }
        for v in [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            f64::MIN,
            1e15,
            1e16,
            1e-5,
            1e-4,
        ] {
            check(v);
        }
    }
}
