//! The [`Dataset`]: samples in struct-of-arrays form (angles in radians) as every loader
//! returns them and the fit and the synthesizer use them, and the degree text that reloads
//! bit-exactly ([`round_trip_degrees`]).

/// The four angle columns every dataset has, in this order.
pub const ANGLE_COLUMNS: [&str; 4] = ["theta_i", "phi_i", "theta_r", "phi_r"];

/// Samples in struct-of-arrays form; memory is proportional to the accepted samples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    /// Channel names, e.g. `["radiance"]` or `["r", "g", "b"]` (from `radiance_<name>`).
    pub channels: Vec<String>,
    /// Incident inclination, radians.
    pub theta_i: Vec<f64>,
    /// Incident azimuth, radians.
    pub phi_i: Vec<f64>,
    /// Outgoing inclination, radians.
    pub theta_r: Vec<f64>,
    /// Outgoing azimuth, radians.
    pub phi_r: Vec<f64>,
    /// Row-major: `radiance[i * n_channels + c]`.
    pub radiance: Vec<f64>,
    /// Per sample per channel, same layout as `radiance` (an unsuffixed column is broadcast).
    pub sigma: Option<Vec<f64>>,
    /// Per sample per channel, same layout as `radiance`.
    pub weight: Option<Vec<f64>>,
    /// 1-based line in the source file of each accepted sample.
    pub source_line: Vec<u64>,
    /// Free-form metadata (from JSON datasets or the synthesizer).
    pub meta: serde_json::Map<String, serde_json::Value>,
}

impl Dataset {
    /// An empty dataset with these channels (and sigma/weight arrays when asked for).
    pub fn with_channels(channels: Vec<String>, sigma: bool, weight: bool) -> Self {
        Dataset {
            channels,
            sigma: sigma.then(Vec::new),
            weight: weight.then(Vec::new),
            ..Dataset::default()
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.theta_i.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.theta_i.is_empty()
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.channels.len()
    }

    /// Radiance of sample `i` in channel `c`.
    pub fn value(&self, i: usize, c: usize) -> f64 {
        self.radiance[i * self.n_channels() + c]
    }

    /// Sigma of sample `i` in channel `c`, if the dataset has sigmas.
    pub fn sigma_of(&self, i: usize, c: usize) -> Option<f64> {
        let n = self.n_channels();
        self.sigma.as_ref().map(|s| s[i * n + c])
    }

    /// Weight of sample `i` in channel `c`, if the dataset has weights.
    pub fn weight_of(&self, i: usize, c: usize) -> Option<f64> {
        let n = self.n_channels();
        self.weight.as_ref().map(|w| w[i * n + c])
    }

    /// The four angles of sample `i` in radians: `[θ_i, φ_i, θ_r, φ_r]`.
    pub fn angles(&self, i: usize) -> [f64; 4] {
        [
            self.theta_i[i],
            self.phi_i[i],
            self.theta_r[i],
            self.phi_r[i],
        ]
    }

    /// The four angles of sample `i` in degrees, `[θ_i, φ_i, θ_r, φ_r]`, as
    /// [`round_trip_degrees`] gives them (what the writers put in files).
    pub fn angles_deg(&self, i: usize) -> [f64; 4] {
        self.angles(i).map(round_trip_degrees)
    }

    /// Append one sample (angles in radians; `radiance`, `sigma`, `weight` one per channel).
    /// Panics if the slices do not match the dataset's channels (a programming error).
    pub fn push(
        &mut self,
        angles: [f64; 4],
        radiance: &[f64],
        sigma: Option<&[f64]>,
        weight: Option<&[f64]>,
        source_line: u64,
    ) {
        assert_eq!(radiance.len(), self.n_channels(), "radiance per channel");
        self.theta_i.push(angles[0]);
        self.phi_i.push(angles[1]);
        self.theta_r.push(angles[2]);
        self.phi_r.push(angles[3]);
        self.radiance.extend_from_slice(radiance);
        if let Some(s) = self.sigma.as_mut() {
            s.extend_from_slice(sigma.expect("dataset has sigma"));
        }
        if let Some(w) = self.weight.as_mut() {
            w.extend_from_slice(weight.expect("dataset has weight"));
        }
        self.source_line.push(source_line);
    }
}

/// Radians → degrees such that the loader's `f64::to_radians` gives back exactly `radians`,
/// choosing the shortest text among such degrees; when no degree value maps back exactly, the
/// one that maps back nearest (1 ulp off).
///
/// Why: `radians.to_degrees()` alone can come back 1 ulp off, so a file in degrees would not
/// reload bit-exactly even for angles that began as degrees. `to_radians` is monotone, so the
/// degrees that map back to `radians` are a run of at most two neighbouring f64s (measured over
/// 2·10⁷ random angles), and `to_degrees` lands within one ulp of them: searching ±3 ulp is
/// ample. Every `d.to_radians()` round-trips exactly (`d` itself is a candidate); about 9% of
/// arbitrary normal radian values have no exact preimage (`to_radians` scales by less than one
/// and skips them) and come back 1 ulp off. Non-finite values are `to_degrees` unchanged.
pub fn round_trip_degrees(radians: f64) -> f64 {
    let nearest = radians.to_degrees();
    if !nearest.is_finite() {
        return nearest;
    }
    // Candidates from the nearest outwards: 0, −1, +1, −2, +2, −3, +3 ulp.
    let mut candidates = [nearest; 7];
    let (mut down, mut up) = (nearest, nearest);
    for k in 1..=3 {
        down = next_f64(down, false);
        up = next_f64(up, true);
        candidates[2 * k - 1] = down;
        candidates[2 * k] = up;
    }
    let maps_back = |d: &f64| d.to_radians().to_bits() == radians.to_bits();
    let mut exact = candidates.iter().copied().filter(maps_back);
    match (exact.next(), exact.next()) {
        // Two exact candidates: the shorter text (the nearer when equally long).
        (Some(a), Some(b)) => {
            if format!("{b:?}").len() < format!("{a:?}").len() {
                b
            } else {
                a
            }
        }
        (Some(a), None) => a,
        // min_by keeps the first (nearest) of equal misses.
        _ => candidates
            .into_iter()
            .min_by(|a, b| {
                let miss = |d: f64| (d.to_radians() - radians).abs();
                miss(*a).total_cmp(&miss(*b))
            })
            .unwrap_or(nearest),
    }
}

/// The neighbouring f64 of a finite `x`, above or below (`f64::next_up`/`next_down`, which are
/// newer than the crate's minimum Rust version).
fn next_f64(x: f64, up: bool) -> f64 {
    if x == 0.0 {
        let tiny = f64::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    // Bits order magnitudes: one more is one ulp further from zero.
    let bits = x.to_bits();
    f64::from_bits(if (x > 0.0) == up { bits + 1 } else { bits - 1 })
}
