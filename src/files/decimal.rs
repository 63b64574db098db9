//! Fast number text for the files hairfit writes in bulk: Rust's own `Display` (`-170`,
//! `0.0000001`) and `LowerExp` (`2.43e-7`, `1e0`) forms of an `f64`, byte for byte, from the
//! shortest round-trip digits zmij finds (ryu's digits, the same `std` picks, about twice as fast
//! as ryu and ~10× `std`, without a `String` per value), and unsigned integers.

/// The formatter the shortest digits come from (one per thread or task).
pub type DigitBuffer = zmij::Buffer;

/// A finite `f64` as sign, shortest significant digits and decimal exponent:
/// `v = ±d₁.d₂…dₙ × 10^exp`. Zero is one digit `0` with exponent 0.
struct Decimal {
    negative: bool,
    digits: [u8; 24],
    len: usize,
    exp: i32,
}

impl Decimal {
    #[inline]
    fn of(v: f64, buf: &mut DigitBuffer) -> Decimal {
        let d = Decimal::parse(buf.format_finite(v).as_bytes());
        // Ryu and zmij round a tie at the 16th/17th digit to even, `std` away from zero: those
        // values (whose exact decimal ends with a 5 right after those digits) take std's digits.
        if d.len >= 16 && tie_possible(v) {
            return Decimal::parse(format!("{v:e}").as_bytes());
        }
        d
    }

    /// Digits and exponent of a decimal text (`-1.25e-7`, `1.5e+16`, `123.5`, `0.0`): at most
    /// 24 digits (shortest texts have at most 17 significant ones and 5 leading zeros).
    #[inline]
    fn parse(text: &[u8]) -> Decimal {
        let (negative, text) = match text.split_first() {
            Some((b'-', rest)) => (true, rest),
            _ => (false, text),
        };
        let (mantissa, e) = split_exponent(text);
        let point = mantissa
            .iter()
            .position(|&b| b == b'.')
            .unwrap_or(mantissa.len());
        let (int, frac) = (&mantissa[..point], mantissa.get(point + 1..).unwrap_or(&[]));
        // Every digit, the point dropped; then the leading and trailing zeros trimmed.
        let mut all = [b'0'; 24];
        let n_int = int.len().min(all.len());
        let n = (n_int + frac.len()).min(all.len());
        all[..n_int].copy_from_slice(&int[..n_int]);
        all[n_int..n].copy_from_slice(&frac[..n - n_int]);
        let lead = all[..n].iter().position(|&b| b != b'0');
        let mut d = Decimal {
            negative,
            digits: [b'0'; 24],
            len: 1,
            exp: 0,
        };
        if let Some(lead) = lead {
            let end = all[..n]
                .iter()
                .rposition(|&b| b != b'0')
                .map_or(n, |k| k + 1);
            d.len = end - lead;
            d.digits[..d.len].copy_from_slice(&all[lead..end]);
            d.exp = n_int as i32 - 1 - lead as i32 + e;
        }
        d
    }
}

/// The mantissa of a decimal text and its exponent (`e-7`, `e+16`, `e16`; 0 when none). The
/// exponent is within the last five bytes (`e-324`), so only those are searched.
#[inline]
fn split_exponent(text: &[u8]) -> (&[u8], i32) {
    let tail = text.len().saturating_sub(5);
    let Some(at) = text[tail..]
        .iter()
        .position(|&b| b == b'e')
        .map(|k| tail + k)
    else {
        return (text, 0);
    };
    let (negative, digits) = match &text[at + 1..] {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        rest => (false, rest),
    };
    let magnitude = digits
        .iter()
        .fold(0i32, |m, &b| m * 10 + i32::from(b.wrapping_sub(b'0')));
    (&text[..at], if negative { -magnitude } else { magnitude })
}

/// Whether `v`'s exact decimal expansion can end with a 5 just after a 16th or 17th
/// significant digit (the only places where two shortest candidates are equally near: the
/// spacing of doubles reaches a unit of the 16th digit): it has at most 18 significant digits,
/// so `v = m·2^e` with `m·5^-e < 10^18`, or is an integer of 16 digits or more.
fn tie_possible(v: f64) -> bool {
    let bits = v.abs().to_bits();
    let biased = (bits >> 52) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    let (mut m, mut e) = if biased == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1u64 << 52), biased - 1075)
    };
    if m == 0 {
        return false;
    }
    let zeros = m.trailing_zeros();
    m >>= zeros;
    e += zeros as i32;
    if e >= 0 {
        v.abs() >= 1e15
    } else {
        let k = e.unsigned_abs();
        k <= 26 && u128::from(m) * 5u128.pow(k) < 10u128.pow(18)
    }
}

/// zmij's text of a finite `v` in its parts: sign, the digits before the point, those after it
/// (none in `5e-7`; `0` in `12.0`, an integer) and the exponent (0 in fixed notation).
struct Parts<'a> {
    negative: bool,
    mantissa: &'a [u8],
    int: &'a [u8],
    frac: &'a [u8],
    exp: i32,
}

impl Parts<'_> {
    #[inline]
    fn of(text: &[u8]) -> Parts<'_> {
        let (negative, body) = match text.split_first() {
            Some((b'-', rest)) => (true, rest),
            _ => (false, text),
        };
        let (mantissa, exp) = split_exponent(body);
        let (int, frac) = match mantissa.iter().position(|&b| b == b'.') {
            Some(p) => (&mantissa[..p], &mantissa[p + 1..]),
            None => (mantissa, &mantissa[mantissa.len()..]),
        };
        Parts {
            negative,
            mantissa,
            int,
            frac,
            exp,
        }
    }
}

/// Append `v` as `format!("{v}")` writes it (finite `v`).
pub fn push_display(out: &mut Vec<u8>, v: f64, buf: &mut DigitBuffer) {
    // zmij's fixed notation is std's but for an integer's `.0`; its exponent form and the
    // values whose digits may differ (ties) go through the digits.
    if !tie_possible(v) {
        let text = buf.format_finite(v).as_bytes();
        if !has_exponent(text) {
            out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
            return;
        }
    }
    push_display_of(out, &Decimal::of(v, buf));
}

/// Whether zmij wrote `text` with an exponent (within its last five bytes, as in `1e-300`).
#[inline]
fn has_exponent(text: &[u8]) -> bool {
    text[text.len().saturating_sub(5)..].contains(&b'e')
}

fn push_display_of(out: &mut Vec<u8>, d: &Decimal) {
    let digits = &d.digits[..d.len];
    if d.negative {
        out.push(b'-');
    }
    if d.exp >= 0 {
        let int_len = d.exp as usize + 1;
        if digits.len() <= int_len {
            out.extend_from_slice(digits);
            out.resize(out.len() + int_len - digits.len(), b'0');
        } else {
            out.extend_from_slice(&digits[..int_len]);
            out.push(b'.');
            out.extend_from_slice(&digits[int_len..]);
        }
    } else {
        out.extend_from_slice(b"0.");
        out.resize(out.len() + (-d.exp - 1) as usize, b'0');
        out.extend_from_slice(digits);
    }
}

/// Append `v` as `format!("{v:e}")` writes it (finite `v`).
pub fn push_exponent(out: &mut Vec<u8>, v: f64, buf: &mut DigitBuffer) {
    // curves.csv's weight column is 1 on every row of an l2 fit.
    if v == 1.0 {
        out.extend_from_slice(b"1e0");
        return;
    }
    if tie_possible(v) {
        return push_exponent_of(out, &Decimal::of(v, buf));
    }
    // Without a tie zmij's digits are std's: move its point behind the first significant digit.
    let p = Parts::of(buf.format_finite(v).as_bytes());
    if p.negative {
        out.push(b'-');
    }
    let exp = if p.int.len() == 1 && p.int[0] != b'0' && p.frac != b"0" {
        // `1.25`, `5e-7`, `1.5e+16`: the mantissa is std's already.
        out.extend_from_slice(p.mantissa);
        p.exp
    } else if p.int[0] != b'0' {
        // `123.25` → `1.2325e2`; `12300.0` → `1.23e4`.
        out.push(p.int[0]);
        let (rest, frac) = if p.frac == b"0" {
            (trim_trailing_zeros(&p.int[1..]), &p.frac[..0])
        } else {
            (&p.int[1..], p.frac)
        };
        if !rest.is_empty() || !frac.is_empty() {
            out.push(b'.');
            out.extend_from_slice(rest);
            out.extend_from_slice(frac);
        }
        p.int.len() as i32 - 1 + p.exp
    } else {
        // `0.00125` → `1.25e-3`; `0.0` → `0e0`.
        let zeros = p.frac.iter().take_while(|&&b| b == b'0').count();
        match p.frac.get(zeros) {
            None => {
                out.push(b'0');
                0
            }
            Some(&first) => {
                out.push(first);
                if zeros + 1 < p.frac.len() {
                    out.push(b'.');
                    out.extend_from_slice(&p.frac[zeros + 1..]);
                }
                -(zeros as i32) - 1
            }
        }
    };
    push_exponent_suffix(out, exp);
}

fn trim_trailing_zeros(digits: &[u8]) -> &[u8] {
    let end = digits.iter().rposition(|&b| b != b'0').map_or(0, |k| k + 1);
    &digits[..end]
}

fn push_exponent_of(out: &mut Vec<u8>, d: &Decimal) {
    if d.negative {
        out.push(b'-');
    }
    out.push(d.digits[0]);
    if d.len > 1 {
        out.push(b'.');
        out.extend_from_slice(&d.digits[1..d.len]);
    }
    push_exponent_suffix(out, d.exp);
}

/// `e-3`, `e16`, `e0`.
#[inline]
fn push_exponent_suffix(out: &mut Vec<u8>, exp: i32) {
    out.push(b'e');
    if exp < 0 {
        out.push(b'-');
    }
    push_u64(out, exp.unsigned_abs() as u64);
}

/// Append `v` in decimal.
pub fn push_u64(out: &mut Vec<u8>, mut v: u64) {
    let mut tmp = [0u8; 20];
    let mut i = tmp.len();
    loop {
        i -= 1;
        tmp[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&tmp[i..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn both(v: f64) -> (String, String) {
        let mut buf = DigitBuffer::new();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        push_display(&mut a, v, &mut buf);
        push_exponent(&mut b, v, &mut buf);
        (String::from_utf8(a).unwrap(), String::from_utf8(b).unwrap())
    }

    /// Byte-identical to `std` on hand-picked edge cases and on a million pseudo-random bit
    /// patterns spanning every exponent (the formats must never drift from the old writer's).
    #[test]
    fn matches_std_display_and_lower_exp() {
        let mut cases = vec![
            0.0,
            -0.0,
            1.0,
            -170.0,
            -29.999999999999996,
            1e-7,
            2.43e-7,
            1e15,
            1e16,
            1.5e16,
            123456789012345680.0,
            5e-324,
            f64::MAX,
            f64::MIN_POSITIVE,
            0.1,
            0.5,
            100.0,
            1e21,
            1e22,
            f64::from_bits(0x44b5_2d02_c7e1_4af6), // 1e23, which has no exact double
            6632827120354249.0 / 4.0, // exact 1658206780088562.25: a tie at the 17th digit
            2651745884931749.0 / 4.0, // exact 662936471232937.25: a tie at the 16th digit
            2f64.powi(-25),           // exact 2.98023223876953125e-8: a tie too
        ];
        let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..1_000_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                cases.push(v);
            }
        }
        // Values of every decade zmij writes in fixed notation and around it (random bits seldom
        // land there): integers, short and full-length digit strings, both signs.
        for exp in -8..=18 {
            let decade = 10f64.powi(exp);
            for k in 0..2_000u64 {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let unit = (x >> 11) as f64 / (1u64 << 53) as f64;
                let v = if k % 2 == 0 {
                    1.0 + 9.0 * unit
                } else {
                    -(1.0 + 9.0 * unit)
                };
                cases.push(v * decade);
                cases.push((v * 1000.0).round() / 1000.0 * decade);
                cases.push((v * decade).round());
            }
        }
        cases.extend([
            5.0, 12300.0, 0.00125, 123.25, 1e-5, 1.5e-5, 9.5e-6, 1e-6, 0.1, 1e17,
        ]);
        for v in cases {
            let (display, exp) = both(v);
            assert_eq!(display, format!("{v}"), "{v:e}");
            assert_eq!(exp, format!("{v:e}"));
        }
        let mut out = Vec::new();
        push_u64(&mut out, 0);
        out.push(b',');
        push_u64(&mut out, u64::MAX);
        assert_eq!(out, format!("0,{}", u64::MAX).as_bytes());
    }
}
