//! Text every export target's files share: numbers as renderers parse them, σ_a as RGB, and
//! the material's name.

use super::source::SourceFit;

/// A number as every renderer parses it: 6 decimals in the ordinary range, else exponent form.
pub fn num(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if (1e-3..1e4).contains(&x.abs()) {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0');
        s.trim_end_matches('.').to_string()
    } else {
        format!("{x:.6e}")
    }
}

/// σ_a as RGB (one channel repeated).
pub fn rgb(sigma_a: &[f64]) -> [f64; 3] {
    match sigma_a {
        [s] => [*s; 3],
        [r, g, b] => [*r, *g, *b],
        other => panic!("rgb needs 1 or 3 channels, got {}", other.len()),
    }
}

/// A name every format accepts: `hairfit_` and the fit directory's name, other characters `_`.
pub fn material_name(source: &SourceFit) -> String {
    let base = source
        .dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let clean: String = base
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("hairfit_{clean}")
}
