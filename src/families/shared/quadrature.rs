//! Gauss–Legendre rules for the width integral `⟨f⟩_h = ½∫₋₁¹ f dh`, taken in `γ = asin h`
//! (`dh = cos γ dγ`, smooth at h = ±1): the plain rule of `--width-nodes N` (nodes computed once
//! per count and cached), and the composite rule of `--width-nodes auto`, broken where the
//! trimmed logistics wrap (their kinks) with a node density chosen by β_n.

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::fmt;
use std::str::FromStr;
use std::sync::{Arc, Mutex, OnceLock};

use serde::{Deserialize, Serialize};

use super::lanes;
use crate::error::{Error, Result};

/// Fewest width nodes accepted.
pub const MIN_WIDTH_NODES: usize = 2;
/// Most width nodes accepted (memory and build time grow linearly and quadratically).
pub const MAX_WIDTH_NODES: usize = 1 << 16;
/// The plain rule's usual count: CHIANG.md measures a worst relative error of 4.8e-7 at 1024
/// nodes in γ (the composite rule of [`auto_density`] is the default).
pub const DEFAULT_WIDTH_NODES: usize = 1024;

/// Gauss–Legendre nodes `x_k` and weights `w_k` on [−1, 1], ascending.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussLegendre {
    pub nodes: Vec<f64>,
    pub weights: Vec<f64>,
}

impl GaussLegendre {
    /// Newton on `P_n` from Tricomi's initial guesses; `P_n, P_n'` by the three-term recurrence.
    /// Converges to ~1 ulp in a few steps for any n; cost O(n²), done once per n.
    pub fn new(n: usize) -> GaussLegendre {
        assert!(n >= 1, "at least one node");
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for k in 0..n.div_ceil(2) {
            // k-th largest root.
            let mut x = (PI * (k as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() <= 1e-16 * x.abs().max(1e-300) {
                    let (_, d) = legendre(n, x);
                    dp = d;
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[n - 1 - k] = x;
            weights[n - 1 - k] = w;
            nodes[k] = -x;
            weights[k] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        GaussLegendre { nodes, weights }
    }
}

/// `(P_n(x), P_n'(x))`.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for j in 2..=n {
        let jf = j as f64;
        let p2 = ((2.0 * jf - 1.0) * x * p1 - (jf - 1.0) * p0) / jf;
        p0 = p1;
        p1 = p2;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

/// One node of the width rule: `γ`, `h = sin γ`, `cos γ` and the weight with the Jacobian folded
/// in, so that `⟨f⟩_h ≈ Σ_k weight_k f(h_k)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WidthNode {
    pub gamma: f64,
    pub h: f64,
    pub cos_gamma: f64,
    pub weight: f64,
}

/// The width rule in γ for `n` Gauss–Legendre nodes:
/// `⟨f⟩_h = ½∫_{−π/2}^{π/2} f cos γ dγ = (π/4) Σ w_k cos γ_k f(sin γ_k)` with `γ_k = (π/2) x_k`.
#[derive(Debug, Clone, PartialEq)]
pub struct WidthRule {
    pub nodes: Vec<WidthNode>,
}

impl WidthRule {
    fn build(n: usize) -> WidthRule {
        let gl = GaussLegendre::new(n);
        let nodes = gl
            .nodes
            .iter()
            .zip(&gl.weights)
            .map(|(&x, &w)| {
                let gamma = FRAC_PI_2 * x;
                let (h, cos_gamma) = gamma.sin_cos();
                WidthNode {
                    gamma,
                    h,
                    cos_gamma,
                    weight: FRAC_PI_4 * w * cos_gamma,
                }
            })
            .collect();
        WidthRule { nodes }
    }

    /// An error unless `n` is within [`MIN_WIDTH_NODES`, `MAX_WIDTH_NODES`].
    pub fn check_nodes(n: usize) -> Result<()> {
        if !(MIN_WIDTH_NODES..=MAX_WIDTH_NODES).contains(&n) {
            return Err(Error::Other(format!(
                "{n} width-quadrature nodes requested: the width integral takes between \
                 {MIN_WIDTH_NODES} and {MAX_WIDTH_NODES} nodes (1024 gives ~5e-7 relative error)"
            )));
        }
        Ok(())
    }

    /// The shared rule for `n` nodes (built on first use, then cached for the process).
    /// Errors if `n` is outside [`MIN_WIDTH_NODES`, `MAX_WIDTH_NODES`].
    pub fn cached(n: usize) -> Result<Arc<WidthRule>> {
        Self::check_nodes(n)?;
        static CACHE: OnceLock<Mutex<HashMap<usize, Arc<WidthRule>>>> = OnceLock::new();
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        // A poisoned lock only means another thread panicked mid-insert of an Arc: the map is intact.
        let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
        Ok(map
            .entry(n)
            .or_insert_with(|| Arc::new(WidthRule::build(n)))
            .clone())
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false for a built rule (at least [`MIN_WIDTH_NODES`]).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// Sizes a composite rule's piece may take, each Gauss–Legendre rule built once; at most 25%
/// apart, so rounding a piece up costs at most a quarter more nodes than its share.
const PIECE_SIZES: [usize; 24] = [
    6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64, 80, 96, 128, 160, 192, 256, 320, 384, 448, 512, 640,
    768, 1024,
];

fn piece_rule(n: usize) -> &'static GaussLegendre {
    static RULES: [OnceLock<GaussLegendre>; PIECE_SIZES.len()] =
        [const { OnceLock::new() }; PIECE_SIZES.len()];
    let k = PIECE_SIZES
        .iter()
        .position(|&m| m >= n)
        .unwrap_or(PIECE_SIZES.len() - 1);
    RULES[k].get_or_init(|| GaussLegendre::new(PIECE_SIZES[k]))
}

/// Node density of the automatic rule (nodes per π of γ) for azimuthal roughness `beta_n`: at
/// each band's lowest β_n (where it is hardest: narrower peaks) the composite rule's worst
/// relative error of `S` stays at or below 4.1e-8 over 600 random cases of CHIANG.md's domain
/// against a 2048-density reference (`tests/families/chiang_quadrature.rs` checks the bound 1e-7; the plain
/// 1024-node rule's worst there is 7.4e-7, at β_n = 0.9). Below β_n = 0.05, the fit's bound,
/// 1024 nodes per π resolve the peaks no better than the plain rule does.
pub fn auto_density(beta_n: f64) -> usize {
    // (lowest β_n of the band, density), ascending.
    const LADDER: [(f64, usize); 8] = [
        (0.0, 1024),
        (0.07, 768),
        (0.1, 512),
        (0.13, 384),
        (0.16, 256),
        (0.2, 192),
        (0.3, 96),
        (0.7, 64),
    ];
    LADDER
        .iter()
        .rev()
        .find(|(lo, _)| beta_n >= *lo)
        .map_or(LADDER[0].1, |b| b.1)
}

/// The composite rule over γ ∈ [−π/2, π/2] broken at `breaks` (any order; points outside or
/// within 1e-9 of another are ignored), `density` nodes per π of γ, at least 6 per piece. Written
/// into `out` (cleared first), ascending in γ, weights as [`WidthRule`]'s.
pub fn composite(density: usize, breaks: &mut [f64], out: &mut Vec<WidthNode>) {
    const MERGE: f64 = 1e-9;
    out.clear();
    breaks.sort_unstable_by(f64::total_cmp);
    let mut start = -FRAC_PI_2;
    let ends = breaks
        .iter()
        .copied()
        .filter(|b| b.abs() < FRAC_PI_2 - MERGE)
        .chain(std::iter::once(FRAC_PI_2));
    for end in ends {
        if end - start < MERGE && end < FRAC_PI_2 {
            continue;
        }
        let half = 0.5 * (end - start);
        let mid = 0.5 * (end + start);
        let wanted = (density as f64 * (end - start) / PI).ceil() as usize;
        let gl = piece_rule(wanted);
        for (&x, &w) in gl.nodes.iter().zip(&gl.weights) {
            // h, cos γ and the weight's cos γ below, on the lanes for every node at once.
            out.push(WidthNode {
                gamma: mid + half * x,
                h: 0.0,
                cos_gamma: 0.0,
                weight: 0.5 * half * w,
            });
        }
        start = end;
    }
    let gammas: Vec<f64> = out.iter().map(|n| n.gamma).collect();
    let (mut sin, mut cos) = (vec![0.0; gammas.len()], vec![0.0; gammas.len()]);
    lanes::slices::sin_cos(&gammas, &mut sin, &mut cos);
    for ((node, h), c) in out.iter_mut().zip(sin).zip(cos) {
        node.h = h;
        node.cos_gamma = c;
        node.weight *= c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        // An n-point rule is exact for degree ≤ 2n−1: ∫x^{2j} = 2/(2j+1), odd moments 0.
        for n in [2, 5, 16, 1024, 4096] {
            let gl = GaussLegendre::new(n);
            let total: f64 = gl.weights.iter().sum();
            assert!((total - 2.0).abs() < 1e-13, "n = {n}: Σw = {total}");
            let j = (n - 1).min(20);
            let m: f64 = gl
                .nodes
                .iter()
                .zip(&gl.weights)
                .map(|(x, w)| w * x.powi(2 * j as i32))
                .sum();
            assert!(
                (m - 2.0 / (2 * j + 1) as f64).abs() < 1e-13,
                "n = {n}, degree {}",
                2 * j
            );
            assert!(gl.nodes.windows(2).all(|p| p[0] < p[1]), "ascending");
        }
    }

    #[test]
    fn width_rule_averages_over_h() {
        // ⟨1⟩_h = 1 and ⟨h²⟩_h = 1/3; the γ-form integrand cos γ·sin²γ is smooth, so 64 nodes suffice.
        let rule = WidthRule::cached(64).unwrap();
        let one: f64 = rule.nodes.iter().map(|n| n.weight).sum();
        let h2: f64 = rule.nodes.iter().map(|n| n.weight * n.h * n.h).sum();
        assert!((one - 1.0).abs() < 1e-14 && (h2 - 1.0 / 3.0).abs() < 1e-14);
        assert!(WidthRule::cached(1).is_err() && WidthRule::cached(MAX_WIDTH_NODES + 1).is_err());
    }

    #[test]
    fn composite_rule_averages_over_h_across_breaks() {
        // Breaks anywhere (also duplicated, unsorted, outside) leave a rule exact for smooth
        // integrands: ⟨1⟩ = 1, ⟨h²⟩ = 1/3 and ⟨|h|⟩ = 1/2 with a break at its kink h = 0.
        let mut out = Vec::new();
        for mut breaks in [
            vec![],
            vec![0.3, -1.2, 0.3, 2.0],
            vec![0.0, FRAC_PI_2 - 1e-12],
        ] {
            composite(64, &mut breaks, &mut out);
            let sum =
                |f: &dyn Fn(&WidthNode) -> f64| out.iter().map(|n| n.weight * f(n)).sum::<f64>();
            assert!((sum(&|_| 1.0) - 1.0).abs() < 1e-14, "{breaks:?}");
            assert!(
                (sum(&|n| n.h * n.h) - 1.0 / 3.0).abs() < 1e-14,
                "{breaks:?}"
            );
            assert!(
                out.windows(2).all(|w| w[0].gamma < w[1].gamma),
                "{breaks:?}"
            );
        }
        composite(64, &mut [0.0], &mut out);
        let abs_h: f64 = out.iter().map(|n| n.weight * n.h.abs()).sum();
        assert!((abs_h - 0.5).abs() < 1e-14, "{abs_h}");
        assert!(auto_density(0.05) == 1024 && auto_density(1.0) < auto_density(0.3));
    }
}

/// The width rule of a model (`--width-nodes auto | N`), as files record it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WidthNodes {
    /// Composite rule broken at the kinks, density [`auto_density`]`(β_n)`.
    #[default]
    Auto,
    /// The composite rule at half the automatic density, at most this many nodes per π: the
    /// fit's multi-start, which only looks for basins (S within ~1e-4 relative for β_n ≥ 0.07,
    /// 7e-2 at 0.05; the plain 256-node rule it replaces had 0.11 there).
    Coarse(usize),
    /// The plain Gauss–Legendre rule with this many nodes.
    Fixed(usize),
}

impl WidthNodes {
    /// An error unless a fixed count is within the plain rule's range.
    pub fn check(self) -> Result<WidthNodes> {
        if let WidthNodes::Fixed(n) | WidthNodes::Coarse(n) = self {
            WidthRule::check_nodes(n)?;
        }
        Ok(self)
    }

    /// True when the nodes depend on the exit direction and the parameters.
    pub fn per_direction(self) -> bool {
        !matches!(self, WidthNodes::Fixed(_))
    }

    /// The nodes per π of γ used at `beta_n` (the plain rule's count when fixed).
    pub fn density(self, beta_n: f64) -> usize {
        match self {
            WidthNodes::Auto => auto_density(beta_n),
            WidthNodes::Coarse(most) => (auto_density(beta_n) / 2).min(most),
            WidthNodes::Fixed(n) => n,
        }
    }
}

impl fmt::Display for WidthNodes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WidthNodes::Auto => f.write_str("auto"),
            WidthNodes::Coarse(n) => write!(f, "auto at half density, at most {n}"),
            WidthNodes::Fixed(n) => write!(f, "{n}"),
        }
    }
}

impl FromStr for WidthNodes {
    type Err = Error;

    /// `auto` or a node count.
    fn from_str(text: &str) -> Result<WidthNodes> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("auto") {
            return Ok(WidthNodes::Auto);
        }
        let n: usize = text.parse().map_err(|_| {
            Error::Other(format!(
                "`{text}` is not a width rule: give `auto` (the default: nodes chosen by beta_n, \
                 split at the lobes' kinks) or a node count such as 1024 (the plain rule)"
            ))
        })?;
        WidthNodes::Fixed(n).check()
    }
}

/// Files hold `"auto"` or the plain rule's count.
impl Serialize for WidthNodes {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            WidthNodes::Fixed(n) => s.serialize_u64(*n as u64),
            _ => s.serialize_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for WidthNodes {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Repr {
            Count(usize),
            Word(String),
        }
        match Repr::deserialize(d)? {
            Repr::Count(n) => WidthNodes::Fixed(n).check(),
            Repr::Word(w) => w.parse(),
        }
        .map_err(serde::de::Error::custom)
    }
}
