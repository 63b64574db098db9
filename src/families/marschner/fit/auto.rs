//! `--effects auto`: enable only the lobes and effects that contribute measurably at the samples,
//! judged by evaluating the model at MODEL.md's mid-range parameters on the data's geometry.

use rayon::prelude::*;
use serde::Serialize;

use crate::families::marschner::eccentricity::cos_2phi_h_spread;
use crate::families::marschner::parameters::reference_params;
use crate::families::marschner::{
    scattering, scattering_by_lobe, Effects, Lobes, ModelConfig, RootMode,
};
use crate::files::EffectsSource;
use crate::fit::design::subsample;
use crate::fit::problem::FitData;
use crate::fit::stages::ModelChoice;
use crate::fit::{EffectsChoice, FitOptions};

/// A contribution counts as measurable above this fraction of S: 1%, the scale of typical
/// measurement noise (2% in the demo) and well above rounding.
pub const MEASURABLE: f64 = 0.01;
/// A lobe or effect needs this many samples where it is measurable to be determined at all.
pub const MIN_SAMPLES: usize = 3;
/// Eccentricity acts through cos 2φ_h; below this spread of cos 2φ_h it is indistinguishable
/// from a change of η (which is fixed), so it is not fitted.
pub const MIN_COS2PHIH_SPREAD: f64 = 0.2;
/// The judgement uses at most this many samples (chosen by a fixed seed).
const MAX_PROBE: usize = 4000;

/// What `--effects auto` chose, and why.
#[derive(Debug, Clone, Serialize)]
pub struct AutoChoice {
    pub effects: Effects,
    /// One line per lobe/effect: on or off and the evidence.
    pub reasons: Vec<String>,
}

/// Count samples where `frac(i) ≥ MEASURABLE`, and the largest fraction.
fn measurable(fracs: &[f64]) -> (usize, f64) {
    let n = fracs.iter().filter(|&&f| f >= MEASURABLE).count();
    (n, fracs.iter().copied().fold(0.0, f64::max))
}

/// Choose lobes and effects for `data` under root mode `mode`.
pub fn choose_effects(data: &FitData, mode: RootMode) -> AutoChoice {
    let nc = data.n_channels().max(1);
    let idx = subsample(data.len(), MAX_PROBE, 0x5eed);
    let angles: Vec<_> = idx.iter().map(|&i| data.angles[i]).collect();
    let n = angles.len();
    let mut p = reference_params(nc);
    // A clearly non-circular cross-section, to see whether eccentricity shows at all.
    p.eccentricity = 0.9;
    let all = ModelConfig {
        mode,
        effects: Effects::default(),
    };
    let mut reasons = Vec::new();

    // Lobe fractions of S (largest over channels) per sample.
    let lobe_frac: Vec<[f64; 3]> = angles
        .par_iter()
        .map(|a| {
            let mut out = vec![[0.0; 3]; nc];
            scattering_by_lobe(&p, &all, a, &mut out);
            let mut f = [0.0f64; 3];
            for lobes in &out {
                let tot: f64 = lobes.iter().sum();
                if tot > 0.0 && tot.is_finite() {
                    for k in 0..3 {
                        f[k] = f[k].max(lobes[k] / tot);
                    }
                }
            }
            f
        })
        .collect();
    let mut on = [false; 3];
    for (k, name) in ["R", "TT", "TRT"].iter().enumerate() {
        let fr: Vec<f64> = lobe_frac.iter().map(|f| f[k]).collect();
        let (cnt, max) = measurable(&fr);
        on[k] = cnt >= MIN_SAMPLES;
        reasons.push(format!(
            "{name} {}: >= {:.0}% of S at {cnt} of {n} samples (max {:.1}%)",
            if on[k] { "on" } else { "off" },
            MEASURABLE * 100.0,
            max * 100.0
        ));
    }
    if !on.iter().any(|&b| b) {
        // Nothing stands out (e.g. a tiny dataset): keep every lobe rather than fit nothing.
        on = [true; 3];
        reasons.push("no lobe stands out at the samples: all lobes kept".into());
    }
    let lobes = Lobes {
        r: on[0],
        tt: on[1],
        trt: on[2],
    };
    let mut effects = Effects {
        lobes,
        glints: false,
        eccentricity: false,
    };
    // Relative change of S when an effect is toggled, per sample (largest over channels).
    let rel_change = |a_cfg: &ModelConfig, b_cfg: &ModelConfig, pa: &_, pb: &_| -> Vec<f64> {
        angles
            .par_iter()
            .map(|ang| {
                let mut sa = vec![0.0; nc];
                let mut sb = vec![0.0; nc];
                scattering(pa, a_cfg, ang, &mut sa);
                scattering(pb, b_cfg, ang, &mut sb);
                sa.iter()
                    .zip(&sb)
                    .map(|(x, y)| {
                        let d = (x - y).abs() / x.abs().max(y.abs());
                        if d.is_finite() {
                            d
                        } else {
                            0.0
                        }
                    })
                    .fold(0.0, f64::max)
            })
            .collect()
    };
    if lobes.trt {
        let with = ModelConfig {
            mode,
            effects: Effects {
                lobes,
                glints: true,
                eccentricity: false,
            },
        };
        let without = ModelConfig {
            mode,
            effects: Effects {
                lobes,
                glints: false,
                eccentricity: false,
            },
        };
        let (cnt, max) = measurable(&rel_change(&with, &without, &p, &p));
        effects.glints = cnt >= MIN_SAMPLES;
        reasons.push(format!(
            "glints {}: change S by >= {:.0}% at {cnt} of {n} samples (max {:.1}%){}",
            if effects.glints { "on" } else { "off" },
            MEASURABLE * 100.0,
            max * 100.0,
            if effects.glints {
                ""
            } else {
                "; no sample near the caustic azimuths"
            }
        ));

        let ecc = ModelConfig {
            mode,
            effects: Effects {
                eccentricity: true,
                ..effects
            },
        };
        let round = ModelConfig { mode, effects };
        let mut p1 = p.clone();
        p1.eccentricity = 1.0;
        let (cnt, max) = measurable(&rel_change(&ecc, &round, &p, &p1));
        let spread = cos_2phi_h_spread(&angles);
        effects.eccentricity = cnt >= MIN_SAMPLES && spread >= MIN_COS2PHIH_SPREAD;
        reasons.push(format!(
            "eccentricity {}: a = 0.9 vs 1 changes S by >= {:.0}% at {cnt} of {n} samples (max {:.1}%), spread of cos(2 phi_h) {:.2} (needs >= {})",
            if effects.eccentricity { "on" } else { "off" },
            MEASURABLE * 100.0,
            max * 100.0,
            spread,
            MIN_COS2PHIH_SPREAD
        ));
    } else {
        reasons.push("glints off: TRT is off".into());
        reasons.push("eccentricity off: TRT is off".into());
    }
    AutoChoice { effects, reasons }
}
/// The model a Marschner fit uses, and how its effects were chosen.
pub struct AutoModel {
    pub config: ModelConfig,
    pub choice: ModelChoice,
}

/// Effects: from the data's geometry (`auto`), all, or as given.
pub fn choose_model(data: &FitData, opts: &FitOptions) -> AutoModel {
    let (effects, effects_choice, reasons) = match opts.effects {
        EffectsChoice::Auto => {
            let c = choose_effects(data, opts.model.config.mode);
            (c.effects, EffectsSource::Auto, c.reasons)
        }
        EffectsChoice::All => (
            Effects::default(),
            EffectsSource::All,
            vec!["--effects all".into()],
        ),
        EffectsChoice::Explicit => (
            opts.model.config.effects,
            EffectsSource::Explicit,
            vec!["--lobes/--no-glints/--no-eccentricity".into()],
        ),
    };
    AutoModel {
        config: ModelConfig {
            mode: opts.model.config.mode,
            effects,
        },
        choice: ModelChoice {
            effects_choice,
            reasons,
        },
    }
}
