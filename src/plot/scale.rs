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

/// Decimal places that show `se` to two significant digits (negative: round to tens, …).
fn se_places(se: f64) -> i32 {
    1 - se.log10().floor() as i32
}

/// `v` to `places` decimals, or in scientific notation with the same last digit when fixed
/// decimals would be too many (or too long a number).
fn at_places(v: f64, places: i32) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    if (0..=8).contains(&places) && v.abs() < 1e6 {
        let s = format!("{v:.*}", places as usize);
        // −0.00 is 0.00.
        return if s
            .trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            s.trim_start_matches('-').to_string()
        } else {
            s
        };
    }
    if places < 0 && v.abs() < 1e6 {
        let step = 10f64.powi(-places);
        return format!("{:.0}", (v / step).round() * step);
    }
    let exponent = if v == 0.0 {
        0
    } else {
        v.abs().log10().floor() as i32
    };
    let digits = (exponent + places).clamp(0, 15) as usize;
    format!("{v:.digits$e}")
}

/// A value with its standard error, both to the standard error's second significant digit
/// (`7.50002`, `0.00021`), so a value differs visibly from its neighbours within a few SEs.
/// Without a usable SE the value reads as [`fmt_num`] and the error as `None`.
pub fn fmt_value_se(v: f64, se: Option<f64>) -> (String, Option<String>) {
    match se.filter(|e| e.is_finite() && *e > 0.0) {
        Some(e) if v.is_finite() => {
            let places = se_places(e);
            let e_text = if places <= 8 && v.abs() < 1e6 {
                at_places(e, places)
            } else {
                format!("{e:.1e}")
            };
            (at_places(v, places), Some(e_text))
        }
        _ => (fmt_num(v), None),
    }
}

/// A profile interval's two ends (`None`: open, read "open") to the digits of the value's
/// standard error (else of the interval's own half-width), with digits added until the ends
/// differ from each other and from `v` whenever the numbers do.
pub fn fmt_interval(lo: Option<f64>, hi: Option<f64>, v: f64, se: Option<f64>) -> [String; 2] {
    let half = match (lo, hi) {
        (Some(a), Some(b)) => 0.5 * (b - a).abs(),
        (Some(a), None) | (None, Some(a)) => (a - v).abs(),
        (None, None) => f64::NAN,
    };
    let scale = se
        .filter(|e| e.is_finite() && *e > 0.0)
        .or_else(|| (half.is_finite() && half > 0.0).then_some(half));
    let Some(scale) = scale else {
        return [lo, hi].map(|x| x.map_or("open".into(), fmt_num));
    };
    let mut places = se_places(scale);
    // An interval much narrower than the SE still gets digits that tell its ends apart.
    if half.is_finite() && half > 0.0 {
        places = places.max(se_places(half));
    }
    let text = |x: Option<f64>, p: i32| x.map_or("open".to_string(), |x| at_places(x, p));
    for p in places..=places + 12 {
        let (a, b, c) = (text(lo, p), text(hi, p), at_places(v, p));
        let clash =
            |x: Option<f64>, tx: &str, y: f64, ty: &str| x.is_some_and(|x| x != y) && tx == ty;
        let distinct = (lo.zip(hi).is_none_or(|(l, h)| l == h) || a != b)
            && !clash(lo, &a, v, &c)
            && !clash(hi, &b, v, &c);
        if distinct {
            return [a, b];
        }
    }
    [text(lo, places + 12), text(hi, places + 12)]
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
    fn a_value_and_its_error_share_the_errors_second_digit() {
        let pm = |v: f64, e: f64| {
            let (a, b) = fmt_value_se(v, Some(e));
            format!("{a} ± {}", b.unwrap())
        };
        // The report's own cases: β_R, w_c, eccentricity, σ_a and k_G of fits/demo.
        assert_eq!(pm(7.500017, 2.09e-4), "7.50002 ± 0.00021");
        assert_eq!(pm(15.000231, 0.001225), "15.0002 ± 0.0012");
        assert_eq!(pm(0.9000112, 3.17e-5), "0.900011 ± 0.000032");
        assert_eq!(pm(0.2503, 4.46e-4), "0.25030 ± 0.00045");
        assert_eq!(pm(2.001, 0.002804), "2.0010 ± 0.0028");
        assert_eq!(pm(12345.0, 560.0), "12350 ± 560");
        assert_eq!(pm(2.5e-9, 3.0e-11), "2.500e-9 ± 3.0e-11");
        assert_eq!(pm(3.0e6, 1.0e4), "3.000e6 ± 1.0e4");
        assert_eq!(pm(-1e-9, 0.01), "0.000 ± 0.010");
        assert_eq!(fmt_value_se(1.55, None), ("1.55".to_string(), None));
        assert_eq!(fmt_value_se(1.55, Some(f64::NAN)).1, None);
        assert_eq!(fmt_value_se(f64::NAN, Some(0.1)).0, "n/a");
    }

    #[test]
    fn interval_ends_differ_from_each_other_and_from_the_value() {
        // fits/demo's β_R, w_c and eccentricity read [7.500, 7.500], [15.00, 15.00], [0.9, 0.9].
        let cases = [
            (7.500017, 2.09e-4, 7.499808, 7.500226),
            (15.000231, 0.001225, 14.999006, 15.001456),
            (0.9000112, 3.17e-5, 0.8999795, 0.9000429),
            // An interval 25× narrower than the SE (cauchy k_G beside undetermined α_R, β_R).
            (2.410580, 0.5533, 2.392262, 2.436283),
            // Ends a hair from the value: digits are added until they differ.
            (1.0, 0.1, 0.999999, 1.000002),
        ];
        for (v, se, lo, hi) in cases {
            let [a, b] = fmt_interval(Some(lo), Some(hi), v, Some(se));
            let (value, _) = fmt_value_se(v, Some(se));
            assert_ne!(a, b, "{v} ± {se}");
            assert!(a.parse::<f64>().unwrap() < b.parse::<f64>().unwrap());
            // Each end reads back within half its last digit of the end itself.
            for (text, end) in [(&a, lo), (&b, hi)] {
                let last = text.split('.').nth(1).map_or(0, str::len) as i32;
                let back: f64 = text.parse().unwrap();
                assert!(
                    (back - end).abs() <= 0.5 * 10f64.powi(-last) + 1e-12,
                    "{text} {end}"
                );
            }
            if value.split('.').nth(1).map_or(0, str::len)
                >= a.split('.').nth(1).map_or(0, str::len)
            {
                assert!(a != value && b != value, "{value} in [{a}, {b}]");
            }
        }
        assert_eq!(
            fmt_interval(Some(7.499808), Some(7.500226), 7.500017, Some(2.09e-4)),
            ["7.49981".to_string(), "7.50023".to_string()]
        );
        assert_eq!(
            fmt_interval(None, Some(2.5), 2.0, None),
            ["open".to_string(), "2.50".to_string()]
        );
        assert_eq!(
            fmt_interval(None, None, 2.0, None),
            ["open".to_string(), "open".to_string()]
        );
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
