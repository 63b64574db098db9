//! The regions of the data over which compare reports every family's RMS normalised residual:
//! three lobe regions (where one lobe of S dominates, by geometry alone, so that every family
//! is judged over the same residuals) and 10° bins of |φ| and θh.
//!
//! Angles as in docs/model.md: φ = φ_r − φ_i wrapped to (−180°, 180°] (|φ| = 0 backward, 180°
//! forward), θh = (θ_i + θ_r)/2 (the specular cone is θh = 0; θ > 0 is toward the tip).
//!
//! - **R**, the specular cone: |θh| ≤ 10° and |φ| ≤ 135°. The R lobe peaks at θh = α (a few
//!   degrees toward the root) with a width of a few degrees, at every |φ| but the forward side.
//! - **TT**, the forward-scattering side: |φ| > 135°, any θh. Light transmitted twice leaves
//!   the fibre on the far side from the light.
//! - **TRT**, beside the cone toward the tip: 10° < θh ≤ 40° and |φ| ≤ 135°. The TRT lobe is
//!   shifted from the cone toward the tip (by 3/2 of R's shift the other way, in Marschner's
//!   model) and is twice as wide as R, so there it carries more of S than R does.
//!
//! The lobes overlap, so a region is where its lobe dominates, not where only it is present.

use super::comparison::{degrees, PerFamily, Region};
use crate::families::ModelFamily;
use crate::files::CurveRow;
use crate::geometry::angles::wrap_deg;

/// Half-width of the specular cone's band in θh, degrees.
pub const CONE_DEG: f64 = 10.0;
/// |φ| beyond this (degrees) is the forward-scattering side.
pub const FORWARD_DEG: f64 = 135.0;
/// The TRT region's far edge in θh, degrees (its near edge is the cone's, [`CONE_DEG`]).
pub const TRT_FAR_DEG: f64 = 40.0;
/// A bin with fewer residuals than this is left out; a lobe region is kept, with no RMS.
pub const MIN_RESIDUALS: usize = 3;

/// A lobe region: its name, definition, and whether a direction `(|φ|, θh)` lies in it.
pub struct LobeRegion {
    pub name: &'static str,
    pub definition: &'static str,
    pub contains: fn(f64, f64) -> bool,
}

/// The lobe regions, in the order compare.json lists them.
pub const LOBE_REGIONS: [LobeRegion; 3] = [
    LobeRegion {
        name: "R",
        definition: "|θh| ≤ 10° and |φ| ≤ 135°: the specular cone, where the R lobe peaks",
        contains: |abs_phi, theta_h| theta_h.abs() <= CONE_DEG && abs_phi <= FORWARD_DEG,
    },
    LobeRegion {
        name: "TT",
        definition: "|φ| > 135°: the forward-scattering side, where the TT lobe peaks",
        contains: |abs_phi, _| abs_phi > FORWARD_DEG,
    },
    LobeRegion {
        name: "TRT",
        definition: "10° < θh ≤ 40° and |φ| ≤ 135°: beside the cone toward the tip, where the \
                     TRT lobe (shifted toward the tip, twice R's width) outweighs R",
        contains: |abs_phi, theta_h| {
            theta_h > CONE_DEG && theta_h <= TRT_FAR_DEG && abs_phi <= FORWARD_DEG
        },
    },
];

/// `(|φ|, θh)` of a row, degrees.
pub fn geometry(row: &CurveRow) -> (f64, f64) {
    (
        wrap_deg(row.phi_r - row.phi_i).abs(),
        0.5 * (row.theta_i + row.theta_r),
    )
}

/// Equal bins of one angle, `lo` to `hi`; values outside go to the first or last bin.
struct Bins {
    axis: &'static str,
    symbol: &'static str,
    lo: f64,
    hi: f64,
    width: f64,
}

const ABS_PHI_BINS: Bins = Bins {
    axis: "abs_phi",
    symbol: "|φ|",
    lo: 0.0,
    hi: 180.0,
    width: 10.0,
};
const THETA_H_BINS: Bins = Bins {
    axis: "theta_h",
    symbol: "θh",
    lo: -90.0,
    hi: 90.0,
    width: 10.0,
};

impl Bins {
    fn count(&self) -> usize {
        ((self.hi - self.lo) / self.width).ceil() as usize
    }

    fn index(&self, x: f64) -> usize {
        (((x - self.lo) / self.width).floor().max(0.0) as usize).min(self.count() - 1)
    }

    fn region(&self, k: usize, acc: &Sums, families: &[ModelFamily]) -> Region {
        let centre = self.lo + (k as f64 + 0.5) * self.width;
        let (a, b) = (
            degrees(centre - 0.5 * self.width),
            degrees(centre + 0.5 * self.width),
        );
        let last = k + 1 == self.count();
        Region {
            axis: self.axis.into(),
            name: format!("{} {a} to {b}", self.symbol),
            definition: format!("{a} ≤ {} {} {b}", self.symbol, if last { "≤" } else { "<" }),
            centre_deg: Some(centre),
            half_width_deg: Some(0.5 * self.width),
            n: acc.n,
            rms: acc.rms(families),
        }
    }
}

/// Residual count and each family's Σ r² over one region.
#[derive(Clone)]
struct Sums {
    n: usize,
    squares: Vec<f64>,
}

impl Sums {
    fn new(families: usize) -> Sums {
        Sums {
            n: 0,
            squares: vec![0.0; families],
        }
    }

    fn add(&mut self, residuals: &[f64]) {
        self.n += 1;
        for (s, r) in self.squares.iter_mut().zip(residuals) {
            *s += r * r;
        }
    }

    /// Each family's RMS; none below [`MIN_RESIDUALS`] residuals.
    fn rms(&self, families: &[ModelFamily]) -> PerFamily {
        if self.n < MIN_RESIDUALS {
            return PerFamily::default();
        }
        PerFamily(
            families
                .iter()
                .zip(&self.squares)
                .map(|(&f, s)| (f, (s / self.n.max(1) as f64).sqrt()))
                .collect(),
        )
    }
}

/// Each family's RMS residual over every region: the three lobe regions (always; with no RMS
/// when they hold fewer than [`MIN_RESIDUALS`] residuals), then the |φ| bins, then the θh bins
/// (those with at least [`MIN_RESIDUALS`] residuals). `curves[i]` are the
/// curves of `families[i]`, all of the same samples in the same order. A residual counts
/// only where every family's is finite, so each region holds the same residuals for all.
pub fn regions(families: &[ModelFamily], curves: &[Vec<CurveRow>]) -> Vec<Region> {
    let nf = families.len();
    let mut lobes = vec![Sums::new(nf); LOBE_REGIONS.len()];
    let mut phi = vec![Sums::new(nf); ABS_PHI_BINS.count()];
    let mut theta = vec![Sums::new(nf); THETA_H_BINS.count()];
    let mut r = vec![0.0; nf];
    let rows = curves.first().map_or(0, Vec::len);
    for k in 0..rows {
        for (slot, c) in r.iter_mut().zip(curves) {
            *slot = c[k].residual;
        }
        let (abs_phi, theta_h) = geometry(&curves[0][k]);
        if !(r.iter().all(|v| v.is_finite()) && abs_phi.is_finite() && theta_h.is_finite()) {
            continue;
        }
        for (lobe, sums) in LOBE_REGIONS.iter().zip(&mut lobes) {
            if (lobe.contains)(abs_phi, theta_h) {
                sums.add(&r);
            }
        }
        phi[ABS_PHI_BINS.index(abs_phi)].add(&r);
        theta[THETA_H_BINS.index(theta_h)].add(&r);
    }
    let mut out: Vec<Region> = LOBE_REGIONS
        .iter()
        .zip(&lobes)
        .map(|(lobe, sums)| Region {
            axis: "lobe".into(),
            name: lobe.name.into(),
            definition: lobe.definition.into(),
            centre_deg: None,
            half_width_deg: None,
            n: sums.n,
            rms: sums.rms(families),
        })
        .collect();
    for (bins, sums) in [(&ABS_PHI_BINS, &phi), (&THETA_H_BINS, &theta)] {
        out.extend(
            sums.iter()
                .enumerate()
                .map(|(k, s)| bins.region(k, s, families)),
        );
    }
    out.retain(|r| r.n >= MIN_RESIDUALS || r.axis == "lobe");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: ModelFamily = ModelFamily::Marschner;
    const B: ModelFamily = ModelFamily::Chiang;

    /// A curves row at (θ_i, φ_i, θ_r, φ_r) with `residual`.
    fn row(sample: u64, [ti, pi, tr, pr]: [f64; 4], residual: f64) -> CurveRow {
        CurveRow {
            sample,
            line: sample + 2,
            channel: "s".into(),
            theta_i: ti,
            phi_i: pi,
            theta_r: tr,
            phi_r: pr,
            data: 1.0,
            sigma: None,
            fit: 1.0,
            fit_r: 0.5,
            fit_tt: 0.3,
            fit_trt: 0.2,
            residual,
            weight: 1.0,
        }
    }

    /// Eleven directions (with `θh`, `|φ|` noted) and two families' residuals there.
    fn fixture() -> Vec<Vec<CurveRow>> {
        let at: [[f64; 4]; 11] = [
            [5.0, 0.0, -5.0, 10.0],      // θh 0, |φ| 10: R
            [5.0, 0.0, -3.0, 30.0],      // θh 1, |φ| 30: R
            [0.0, 0.0, 0.0, 135.0],      // θh 0, |φ| 135 (edge, not TT): R
            [20.0, 0.0, 0.0, 40.0],      // θh 10 (edge, not TRT): R
            [20.0, 0.0, 10.0, 40.0],     // θh 15, |φ| 40: TRT
            [30.0, 10.0, 20.0, 70.0],    // θh 25, |φ| 60: TRT
            [40.0, 0.0, 40.0, -80.0],    // θh 40 (edge), |φ| 80: TRT
            [0.0, 0.0, 0.0, 170.0],      // θh 0, |φ| 170: TT
            [10.0, 10.0, -10.0, -170.0], // θh 0, φ wraps to 180: TT
            [-10.0, 0.0, -30.0, 175.0],  // θh −20, |φ| 175: TT
            [-20.0, 0.0, -40.0, 20.0],   // θh −30, |φ| 20: no lobe region
        ];
        let a = [
            1.0,
            -2.0,
            2.0,
            4.0,
            3.0,
            -1.0,
            1.0,
            0.5,
            0.5,
            -1.0,
            f64::NAN,
        ];
        let b = [0.5, 0.5, -0.5, 0.5, 1.0, 1.0, 1.0, 2.0, 4.0, 2.0, 7.0];
        [a, b]
            .iter()
            .map(|res| {
                at.iter()
                    .zip(res)
                    .enumerate()
                    .map(|(k, (&angles, &r))| row(k as u64, angles, r))
                    .collect()
            })
            .collect()
    }

    fn find<'a>(regions: &'a [Region], name: &str) -> &'a Region {
        regions.iter().find(|r| r.name == name).unwrap()
    }

    #[test]
    fn lobe_regions_hold_the_residuals_their_definitions_say() {
        let regions = regions(&[A, B], &fixture());
        let check = |name: &str, n: usize, a: f64, b: f64| {
            let r = find(&regions, name);
            assert_eq!(r.n, n, "{name}");
            assert_eq!(r.axis, "lobe");
            assert!(
                (r.rms.get(A).unwrap() - a).abs() < 1e-12,
                "{name}: {:?}",
                r.rms
            );
            assert!(
                (r.rms.get(B).unwrap() - b).abs() < 1e-12,
                "{name}: {:?}",
                r.rms
            );
        };
        // R: rows 0–3; (1 + 4 + 4 + 16)/4 and (0.25·4)/4.
        check("R", 4, (25.0f64 / 4.0).sqrt(), 0.5);
        // TRT: rows 4–6; (9 + 1 + 1)/3 and 3/3.
        check("TRT", 3, (11.0f64 / 3.0).sqrt(), 1.0);
        // TT: rows 7–9; (0.25 + 0.25 + 1)/3 and (4 + 16 + 4)/3.
        check("TT", 3, 0.5f64.sqrt(), 8.0f64.sqrt());
        // Row 10 (Marschner's residual NaN) is in no region: nor in the |φ| 20° to 30° bin.
        assert!(regions.iter().all(|r| r.name != "|φ| 20° to 30°"));
        let kinds: Vec<&str> = regions.iter().map(|r| r.axis.as_str()).collect();
        assert_eq!(&kinds[..3], ["lobe"; 3]);
        assert!(!find(&regions, "R").misses(B, A));
        assert!(find(&regions, "TT").misses(B, A));
        assert!(find(&regions, "R").misses(A, B));
    }

    #[test]
    fn bins_of_theta_h_and_abs_phi() {
        let regions = regions(&[A, B], &fixture());
        // θh 0–10°: rows 0, 1, 2, 7, 8 (θh 0, 1, 0, 0, 0); row 3 has θh = 10 (next bin).
        let bin = find(&regions, "θh 0° to 10°");
        assert_eq!(bin.n, 5);
        assert_eq!(bin.centre_deg, Some(5.0));
        assert_eq!(bin.definition, "0° ≤ θh < 10°");
        let a = (1.0 + 4.0 + 4.0 + 0.25 + 0.25) / 5.0f64;
        let b = (0.25 + 0.25 + 0.25 + 4.0 + 16.0) / 5.0f64;
        assert!((bin.rms.get(A).unwrap() - a.sqrt()).abs() < 1e-12);
        assert!((bin.rms.get(B).unwrap() - b.sqrt()).abs() < 1e-12);
        // The last |φ| bin holds 180° too (rows 7, 8, 9: |φ| 170, 180, 175).
        let last = find(&regions, "|φ| 170° to 180°");
        assert_eq!((last.n, last.definition.as_str()), (3, "170° ≤ |φ| ≤ 180°"));
        // Bins with fewer than 3 residuals are left out; a lobe region stays, without RMS.
        assert!(regions
            .iter()
            .all(|r| r.n >= MIN_RESIDUALS || r.axis == "lobe"));
        // θh −30° (row 10) is a bin of its own, named with a minus sign; too few to be listed.
        assert_eq!(degrees(-30.0), "−30°");
        assert!(regions.iter().all(|r| r.name != "θh −30° to −20°"));
        let few: Vec<Vec<CurveRow>> = fixture().iter().map(|c| c[..2].to_vec()).collect();
        let few = super::regions(&[A, B], &few);
        let names: Vec<&str> = few.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["R", "TT", "TRT"]);
        assert_eq!((few[0].n, few[1].n), (2, 0));
        assert!(few.iter().all(|r| r.rms.0.is_empty()));
    }

    #[test]
    fn per_family_values_are_a_json_object_in_order() {
        let v = PerFamily(vec![(B, 2.5), (A, 1.0)]);
        let text = serde_json::to_string(&v).unwrap();
        assert_eq!(text, r#"{"chiang":2.5,"marschner":1.0}"#);
        let back: PerFamily = serde_json::from_str(&text).unwrap();
        assert_eq!(back, v);
        assert!(serde_json::from_str::<PerFamily>(r#"{"nope":1}"#).is_err());
    }
}
