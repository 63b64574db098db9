//! A family defined here, in a test, and nowhere in the library: one type implementing
//! `TableFamily`, its table and its scattering function. It runs the whole battery through the
//! paths commands use (its model through `FamilyModel`, its parameter file through
//! `TableParamFile`, its fit through the `FamilyFit` a registry line would hand out), which is
//! what CONTRIBUTING.md promises a new family costs: its folder, plus the registry's line that
//! lets `--model NAME` and a file's `"model"` tag find it.

use std::f64::consts::PI;

use hairfit::families::table::{LobeColumn, TableFamily, TableParams, Term, TermSet, Terms};
use hairfit::geometry::{Angles, Fitted, Interval, ParamFact, Unit};
use num_dual::DualNum;

use crate::battery::{battery, Documented, Reciprocity, Subject};

/// A Gaussian lobe around the specular cone, shifted by a tilt, plus a per-channel diffuse
/// term: `S = g(θ_i + θ_r − 2α; β) / 2π + K_d / π²`, with `g` the unit-area normal density.
struct Toy;

const ALPHA: usize = 0;
const BETA: usize = 1;
const K_D: usize = 2;
const LOBE: usize = 0;
const DIFFUSE: usize = 1;

impl TableFamily for Toy {
    const NAME: &'static str = "toy";
    const TITLE: &'static str = "a test's toy family";
    const FIX_EXAMPLE: &'static str = "beta_deg=8";
    const TERMS: &'static [Term] = &[
        Term {
            name: "lobe",
            meaning: "the tilted Gaussian lobe",
            column: LobeColumn::R,
        },
        Term {
            name: "diffuse",
            meaning: "K_d, the same in every direction",
            column: LobeColumn::TRT,
        },
    ];
    const PARAMETERS: &'static [ParamFact] = &[
        ParamFact {
            name: "alpha_deg",
            symbol: "α",
            meaning: "the lobe's shift from the specular cone (half of it)",
            unit: Unit::Degrees,
            domain: Interval::open(-45.0, 45.0),
            fit_lo: -20.0,
            fit_hi: Some(20.0),
            typical: (-8.0, -1.0),
            reference: Some(-3.0),
            terms: &["lobe"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "beta_deg",
            symbol: "β",
            meaning: "the lobe's width",
            unit: Unit::Degrees,
            domain: Interval::open(0.0, 90.0),
            fit_lo: 1.0,
            fit_hi: Some(45.0),
            typical: (3.0, 15.0),
            reference: Some(7.0),
            terms: &["lobe"],
            ..ParamFact::BASE
        },
        ParamFact {
            name: "k_d",
            symbol: "K_d",
            meaning: "the diffuse albedo, one per colour channel",
            per_channel: true,
            domain: Interval::closed_open(0.0, f64::INFINITY),
            fit_lo: 0.0,
            fit_hi: Some(10.0),
            typical: (0.05, 0.5),
            reference: Some(0.2),
            fitted: Fitted::Yes,
            terms: &["diffuse"],
            ..ParamFact::BASE
        },
    ];

    fn scatter<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, on: TermSet, out: &mut [Terms<T>]) {
        let lobe = on.has(LOBE).then(|| {
            let beta = p.get(BETA, 0);
            let x = -(p.get(ALPHA, 0) * 2.0) + a.theta_i + a.theta_r;
            let z = x / beta.clone();
            (-(z.clone() * z) * 0.5).exp() / (beta * (2.0 * PI).sqrt() * 2.0 * PI)
        });
        for (c, o) in out.iter_mut().enumerate() {
            if let Some(l) = &lobe {
                o[LOBE] = l.clone();
            }
            if on.has(DIFFUSE) {
                o[DIFFUSE] = p.get(K_D, c) / (PI * PI);
            }
        }
    }
}

/// The toy runs every check a registered family runs.
#[test]
fn a_family_defined_in_a_test_runs_the_battery() {
    battery(&Subject::table::<Toy>(Documented {
        // Nothing depends on φ, and `θ_i + θ_r` is symmetric in i ↔ r.
        even_in_phi: true,
        reciprocity: Reciprocity::S(&[0, 1, 2]),
        // The furnace `∫∫ S cos²θ_i dθ_i dφ`: the lobe gives at most `∫ g = 1` (cos² ≤ 1), the
        // diffuse term `K_d/π² · π/2 · 2π = K_d`; the demo truth's largest K_d is 0.3875.
        energy: 1.3875 + 1e-9,
    }));
}
