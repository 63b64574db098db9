//! MODEL.md "Known values" table, both root modes.

use crate::support::model::table_params;
use hairfit::families::marschner::{scattering, ModelConfig, RootMode};
use hairfit::geometry::Angles;

/// (θ_i, φ_i, θ_r, φ_r) in degrees, S cubic, S exact — MODEL.md's table.
const TABLE: [([f64; 4], f64, f64); 4] = [
    ([-20.0, 0.0, 25.0, 30.0], 4.3725e-02, 4.7482e-02),
    ([10.0, -40.0, -5.0, 170.0], 1.0318e+00, 1.0718e+00),
    ([-60.0, 10.0, 45.0, -80.0], 1.7711e-01, 1.7697e-01),
    ([-10.0, 0.0, 75.0, 0.0], 1.5925e-02, 1.8277e-02),
];

fn s(mode: RootMode, a: [f64; 4]) -> f64 {
    let config = ModelConfig {
        mode,
        ..ModelConfig::default()
    };
    let mut out = [0.0];
    scattering(
        &table_params(),
        &config,
        &Angles::from_degrees(a[0], a[1], a[2], a[3]),
        &mut out,
    );
    out[0]
}

/// The table prints 5 significant digits, so a correct value is within half a unit of the last
/// printed digit: |S − S_table| ≤ 0.5e-4 · 10^floor(log10 S_table).
fn within_printed_precision(got: f64, printed: f64) -> bool {
    let unit = 10f64.powf(printed.abs().log10().floor()) * 1e-4;
    (got - printed).abs() <= 0.5 * unit
}

#[test]
fn known_values_cubic() {
    for (a, cubic, _) in TABLE {
        let got = s(RootMode::Cubic, a);
        assert!(
            within_printed_precision(got, cubic),
            "{a:?}: cubic {got:.6e} vs table {cubic:.4e}"
        );
    }
}

#[test]
fn known_values_exact() {
    for (a, _, exact) in TABLE {
        let got = s(RootMode::Exact, a);
        assert!(
            within_printed_precision(got, exact),
            "{a:?}: exact {got:.6e} vs table {exact:.4e}"
        );
    }
}
