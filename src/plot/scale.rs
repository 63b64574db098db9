//! Axis scales and number formats: log or linear value axes with their tick labels, compact
//! numbers for labels and tables, and padded ranges of finite values.

/// Log axes spanning at least this many decades label decades only.
const DECADES_ONLY: f64 = 2.5;

/// Log or linear vertical scale; log plots log10(y) on linear axes with 10^k tick labels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum YScale {
    Log,
    Linear,
}

impl YScale {
    /// Plot coordinate of a value, `None` when it cannot be shown (≤ 0 on a log scale, NaN).
    pub fn map(self, y: f64) -> Option<f64> {
        let v = match self {
            YScale::Log if y > 0.0 => y.log10(),
            YScale::Log => return None,
            YScale::Linear => y,
        };
        v.is_finite().then_some(v)
    }

    /// Tick label for a plot coordinate on an axis spanning `span`: on a log axis spanning more
    /// than [`DECADES_ONLY`] decades only decades are labelled (other grid lines stay unlabelled).
    pub fn label(self, v: f64, span: f64) -> String {
        match self {
            YScale::Log if span >= DECADES_ONLY => {
                let k = v.round();
                if (v - k).abs() > 1e-6 {
                    String::new()
                } else if (-3.0..=3.0).contains(&k) {
                    fmt_num(10f64.powf(k))
                } else {
                    format!("1e{k}")
                }
            }
            YScale::Log => sig2(10f64.powf(v)),
            YScale::Linear => fmt_num(v),
        }
    }

    /// How many tick positions to ask plotters for on an axis spanning `span` (log: one per
    /// decade, so ticks fall on decades).
    pub fn ticks(self, span: f64) -> usize {
        match self {
            YScale::Log if span >= DECADES_ONLY => (span.ceil() as usize + 1).clamp(3, 16),
            YScale::Log => 6,
            YScale::Linear => 10,
        }
    }

    /// The axis-label suffix naming the scale.
    pub fn suffix(self) -> &'static str {
        match self {
            YScale::Log => ", log scale",
            YScale::Linear => "",
        }
    }
}

/// A compact number for labels and tables; never prints NaN or inf.
pub fn fmt_num(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        // Keep four significant digits at most.
        let digits = s.chars().filter(|c| c.is_ascii_digit()).count();
        if digits > 4 {
            let p = 3 - a.log10().floor() as i32;
            format!("{v:.*}", p.max(0) as usize)
        } else {
            s
        }
    } else {
        format!("{v:.2e}")
    }
}

/// A tick label on an axis spanning `span`: enough decimals to tell apart ticks a fifth of the
/// span apart (plotters' steps are 1, 2 or 5 × 10ᵏ, about that size). [`fmt_num`]'s four
/// significant digits print `15.00` for every tick of an axis 0.004 wide around 15.
pub fn fmt_tick(v: f64, span: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    if !(span.is_finite() && span > 0.0) {
        return fmt_num(v);
    }
    let decimals = (-(span / 5.0).log10()).ceil().max(0.0) as usize;
    let a = v.abs().max(span);
    if (1e-3..1e5).contains(&a) && decimals <= 8 {
        // −0.000 is 0.
        let s = format!("{v:.decimals$}");
        if s.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            s.trim_start_matches('-').to_string()
        } else {
            s
        }
    } else {
        let sig = ((a / span).log10().ceil().max(0.0) as usize + 1).min(12);
        format!("{v:.sig$e}")
    }
}

/// Two significant digits (tick labels between decades), never NaN text.
pub fn sig2(v: f64) -> String {
    if !v.is_finite() || v == 0.0 {
        return fmt_num(v);
    }
    let p = 1 - v.abs().log10().floor() as i32;
    if (0..=5).contains(&p) {
        format!("{v:.*}", p as usize)
    } else {
        format!("{v:.1e}")
    }
}

/// A padded range holding every finite value; `fallback` when none.
pub fn range_of(values: impl Iterator<Item = f64>, pad: f64, fallback: (f64, f64)) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return fallback;
    }
    let span = hi - lo;
    if span <= 1e-12 * hi.abs().max(1.0) {
        let d = if hi == 0.0 { 1.0 } else { 0.5 * hi.abs() };
        return (lo - d, hi + d);
    }
    (lo - pad * span, hi + pad * span)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_never_print_nan() {
        assert_eq!(fmt_num(f64::NAN), "n/a");
        assert_eq!(fmt_num(f64::INFINITY), "n/a");
        assert_eq!(fmt_num(0.0), "0");
        assert_eq!(fmt_num(1.5), "1.5");
        assert_eq!(fmt_num(123.456789), "123.5");
        assert_eq!(fmt_num(2.5e-5), "2.50e-5");
    }

    #[test]
    fn ticks_on_a_narrow_axis_stay_distinct() {
        // Axes from 0.004 to 4000 wide around 15, ticks at a fifth of the span or a step of
        // 1, 2 or 5 × 10ᵏ near it: distinct labels that read back as the tick.
        for span in [0.004f64, 0.02, 0.3, 7.0, 4000.0] {
            let fifth = span / 5.0;
            for nice in [1.0, 2.0, 5.0] {
                let step = nice * 10f64.powf(fifth.log10().floor());
                let ticks: Vec<f64> = (-2..=2).map(|k| 15.0 + step * k as f64).collect();
                let labels: Vec<String> = ticks.iter().map(|&t| fmt_tick(t, span)).collect();
                for (t, l) in ticks.iter().zip(&labels) {
                    let back: f64 = l.parse().unwrap();
                    assert!((back - t).abs() < 1e-6 * step, "{span}: {t} → {l}");
                }
                let mut unique = labels.clone();
                unique.dedup();
                assert_eq!(unique.len(), labels.len(), "{span}: {labels:?}");
            }
        }
        assert_eq!(fmt_tick(0.25, 0.002), "0.2500");
        assert_eq!(fmt_tick(14.999, 0.004), "14.9990");
        assert_eq!(fmt_tick(-1e-12, 2.0), "0.0");
        assert_eq!(fmt_tick(3.0e6, 1.0e5), "3.000e6");
        assert_eq!(fmt_tick(f64::NAN, 1.0), "n/a");
    }

    #[test]
    fn log_scale_hides_non_positive_values() {
        assert_eq!(YScale::Log.map(0.0), None);
        assert_eq!(YScale::Log.map(-1.0), None);
        assert_eq!(YScale::Log.map(100.0), Some(2.0));
        assert_eq!(YScale::Linear.map(-1.0), Some(-1.0));
        assert_eq!(YScale::Linear.map(f64::NAN), None);
    }

    #[test]
    fn wide_log_axes_label_decades_only() {
        assert_eq!(YScale::Log.label(2.0, 4.0), "100");
        assert_eq!(YScale::Log.label(2.5, 4.0), "");
        assert_eq!(YScale::Log.label(-5.0, 4.0), "1e-5");
    }

    #[test]
    fn a_single_value_gets_a_range_around_it() {
        assert_eq!(
            range_of([2.0, 2.0].into_iter(), 0.1, (0.0, 1.0)),
            (1.0, 3.0)
        );
        assert_eq!(
            range_of([f64::NAN].into_iter(), 0.1, (0.0, 1.0)),
            (0.0, 1.0)
        );
    }
}
