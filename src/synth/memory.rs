//! How much memory `hairfit synth` may use: `--max-memory`, by default half the machine's
//! memory, checked against an estimate before the dataset is allocated.

use crate::error::{readable_bytes, Error, Result};

/// Bytes one sample of `nc` channels takes in memory while synthesized (angles, source line,
/// values, noise bookkeeping): measured peak over samples, rounded up.
pub fn bytes_per_sample(nc: usize) -> u64 {
    104 + 24 * nc as u64
}

/// The default limit: half the machine's memory (`MemTotal` in /proc/meminfo), or 4 GiB where
/// that is unknown.
pub fn machine_default() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib * 1024)
        });
    total.map_or(4 << 30, |t| t / 2)
}

/// `--max-memory`: bytes, or a number with K, M, G or T (powers of 1024; `B`/`iB` optional),
/// e.g. `500M`, `2G`, `1.5GiB`.
pub fn parse_size(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let body = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (number, unit) = match body.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&body[..i], c),
        _ => (body, ' '),
    };
    let power = match unit {
        ' ' => 0,
        'K' => 1,
        'M' => 2,
        'G' => 3,
        'T' => 4,
        _ => return Err(format!("`{t}`: use a size like 500M, 2G or 1T")),
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("`{t}`: use a size like 500M, 2G or 1T"))?;
    let bytes = value * 1024f64.powi(power);
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("`{t}`: give a positive size like 500M, 2G or 1T"));
    }
    Ok(bytes as u64)
}

/// Refuse `samples` of `nc` channels above `limit` bytes; `what` names the options that set
/// the size (e.g. "--rig `azimuthal:steps=…`: use fewer steps").
pub fn check(
    samples: u64,
    nc: usize,
    limit: u64,
    what: impl FnOnce(String) -> Error,
) -> Result<()> {
    let need = samples.saturating_mul(bytes_per_sample(nc));
    if need > limit {
        let (mut n, mut l) = (readable_bytes(need), readable_bytes(limit));
        if n == l {
            // Rounded to one unit they would read alike.
            (n, l) = (format!("{need} bytes"), format!("{limit} bytes"));
        }
        return Err(what(format!(
            "{samples} samples × {nc} channels need about {n}, more than the {l} \
             --max-memory allows (default: half this machine's memory)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_size("1024"), Ok(1024));
        assert_eq!(parse_size("2K"), Ok(2048));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("500mb"), Ok(500 << 20));
        assert_eq!(parse_size(" 1T "), Ok(1 << 40));
        for bad in ["", "G", "2X", "-1G", "0", "1e40T", "nanG"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_estimate_refuses_above_the_limit_only() {
        let err = |m: String| Error::Other(m);
        assert!(check(1000, 3, 1000 * bytes_per_sample(3), err).is_ok());
        let e = check(1001, 3, 1000 * bytes_per_sample(3), err).unwrap_err();
        assert!(e.to_string().contains("--max-memory"), "{e}");
        let e = check(1000, 3, 1000 * bytes_per_sample(3) - 1, err).unwrap_err();
        assert!(
            e.to_string()
                .contains("176000 bytes, more than the 175999 bytes"),
            "{e}"
        );
        assert!(
            check(u64::MAX, 1, u64::MAX - 1, err).is_err(),
            "no overflow"
        );
    }
}
