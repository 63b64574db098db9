//! The battery every registered family runs (`ModelFamily::ALL`, the registry the CLI, compare
//! and batch enumerate): S finite and ≥ 0 over the sphere, even in φ and reciprocal where its
//! page says so, an energy bound (white furnace), exact derivatives, a parameter file that
//! reads back what it wrote, term switches that remove exactly their term, and a noise-free fit
//! that recovers the truth and ends `good`. What a family documents is one exhaustive `match`
//! ([`documented`], [`ad_matches_finite_differences`]): a new family does not compile here
//! until it says, and then it runs every check. A family's own equations are tested in its own
//! file against an independent reference.

use std::f64::consts::{FRAC_PI_2, PI};

use hairfit::demo::{demo_directions, DEMO_SCALE};
use hairfit::families::chiang::fit::ChiangForward;
use hairfit::families::chiang::ChiangFamily;
use hairfit::families::chiang::{ChiangEffects, ChiangModel};
use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::MarschnerFamily;
use hairfit::families::marschner::{Lobes, ModelConfig};
use hairfit::families::shared::quadrature::WidthNodes;
use hairfit::families::table::fit::TableForward;
use hairfit::families::table::{
    demo_params, DynTable, Table, TableFamily, TableParamFile, Term, TermSet,
};
use hairfit::families::{deon::DEon, frostbite::Frostbite, kajiya_kay::KajiyaKay, karis::Karis};
use hairfit::families::{FamilyModel, FamilyParams, ModelFamily, ModelSetup};
use hairfit::files::{FitJson, LoadReport, ParamStatus, Verdict};
use hairfit::fit::family::{Family, FamilyFit, FitInput};
use hairfit::fit::problem::{FitParam, Forward, ParamSet};
use hairfit::fit::registry::family_fit;
use hairfit::fit::FitOptions;
use hairfit::geometry::{Angles, Measurement};
use hairfit::synth::{Acquisition, Noise, Source};

/// Which swap of incidence and exit leaves what unchanged, and for which of `by_lobe`'s
/// columns (R, TT, TRT), as the family's page states it.
#[derive(Clone, Copy)]
pub enum Reciprocity {
    /// The page says the model is not reciprocal: nothing to check.
    None,
    /// `S(i, r) = S(r, i)` for these columns.
    S(&'static [usize]),
    /// `S(i, r) cos θ_i = S(r, i) cos θ_r` (f = S cos θ_i reciprocal) for these columns.
    F(&'static [usize]),
}

/// What a family's page documents of its symmetries and energy.
pub struct Documented {
    /// `S(φ) = S(−φ)`.
    pub even_in_phi: bool,
    pub reciprocity: Reciprocity,
    /// The most a fibre with the demo truth returns of a white furnace ([`energy_bounded`]):
    /// 1 for a model that conserves energy; more for the models whose pages say they do not.
    pub energy: f64,
}

/// Each family's documented symmetries, from its page (docs/NAME.md, docs/model.md).
fn documented(family: ModelFamily) -> Documented {
    use Reciprocity as R;
    let (even_in_phi, reciprocity, energy) = match family {
        // docs/model.md: "swapping the incident and outgoing directions leaves S unchanged";
        // for a = 1 (the demo's round fibre) S depends on φ only through |φ|. Marschner 2003's
        // lobes are not normalised on the sphere: up to 1.28 measured at the demo truth (θ_r = 30°),
        // so this bound guards against a regression, not a physical limit.
        ModelFamily::Marschner => (true, R::S(&[0, 1, 2]), 1.35),
        // docs/chiang.md: S is even in φ; "the model is not reciprocal"; energy conserving.
        ModelFamily::Chiang => (true, R::None, 1.0),
        // docs/kajiya-kay.md: nothing depends on φ; not reciprocal as a whole; not energy
        // conserving: the diffuse albedo alone is π² K_d (up to 9.55 measured in the demo truth's
        // third channel), so this bound guards against a regression, not a physical limit.
        ModelFamily::KajiyaKay => (true, R::None, 10.5),
        // docs/deon.md: S(φ) = S(−φ); f is reciprocal only without the tilt (the demo has one);
        // the furnace is 1 up to the share drift, below 1 when absorbing.
        ModelFamily::DEon => (true, R::None, 1.0),
        // docs/karis.md: even in φ; TT and TRT keep f = S cos θ_i reciprocal at any shift; the
        // bound holds for absorbing fibres (exceeded by a few percent only when white).
        ModelFamily::Karis => (true, R::F(&[1, 2]), 1.0),
        // docs/frostbite.md: φ → −φ exact; S_R symmetric under i ↔ r; a white fibre's albedo is
        // about two (1.65 measured at the demo truth).
        ModelFamily::Frostbite => (true, R::S(&[0]), 2.0),
    };
    Documented {
        even_in_phi,
        reciprocity,
        energy,
    }
}

#[test]
fn marschner() {
    battery(&Subject::registered(ModelFamily::Marschner));
}

#[test]
fn chiang() {
    battery(&Subject::registered(ModelFamily::Chiang));
}

#[test]
fn kajiya_kay() {
    battery(&Subject::registered(ModelFamily::KajiyaKay));
}

#[test]
fn deon() {
    battery(&Subject::registered(ModelFamily::DEon));
}

#[test]
fn karis() {
    battery(&Subject::registered(ModelFamily::Karis));
}

#[test]
fn frostbite() {
    battery(&Subject::registered(ModelFamily::Frostbite));
}

/// The tests above name every registered family: one more in the registry fails here until
/// its battery test is added.
#[test]
fn every_registered_family_runs_the_battery() {
    let names: Vec<&str> = ModelFamily::ALL.iter().map(|f| f.as_str()).collect();
    assert_eq!(
        names,
        [
            "marschner",
            "chiang",
            "kajiya-kay",
            "deon",
            "karis",
            "frostbite"
        ],
        "add the new family's #[test] fn calling battery()"
    );
}

/// A family as the battery holds it: what every check reads of it, reached the way commands
/// reach it (its model through [`FamilyModel`], its fit through the [`FamilyFit`] the
/// registry hands out), so a family a test defines ([`Subject::table`]) runs the same checks
/// as a registered one.
pub struct Subject {
    pub name: String,
    /// The demo's truth (3 channels) as the family's parameter file.
    pub truth: FamilyParams,
    /// Its table, for a table family.
    pub table: Option<&'static dyn DynTable>,
    pub documented: Documented,
    /// Its fit, as `--model` picks it.
    pub fit: &'static dyn FamilyFit,
    /// Its `--model` entry; `None` for a family only a test knows.
    pub registered: Option<ModelFamily>,
    /// AD against finite differences on its forward model with every term on.
    pub jacobian: fn(&Subject),
}

impl Subject {
    /// A family of the registry.
    pub fn registered(family: ModelFamily) -> Subject {
        Subject {
            name: family.as_str().to_string(),
            truth: family.demo_truth(),
            table: family.table(),
            documented: documented(family),
            fit: family_fit(family),
            registered: Some(family),
            jacobian: ad_matches_finite_differences,
        }
    }

    /// The table family `F`, registered or not: one type implementing [`TableFamily`] is all
    /// the battery needs.
    pub fn table<F: TableFamily>(documented: Documented) -> Subject {
        let table: &'static dyn DynTable = const { &Table::<F>::NEW };
        let truth = demo_params(F::PARAMETERS, DEMO_SCALE.len());
        Subject {
            name: F::NAME.to_string(),
            truth: TableParamFile::from_params(table, &truth).into(),
            table: Some(table),
            documented,
            fit: const { &Table::<F>::NEW },
            registered: None,
            jacobian: |s| table_jacobian::<F>(s),
        }
    }
}

impl std::fmt::Display for Subject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name)
    }
}

pub fn battery(family: &Subject) {
    finite_and_non_negative_over_the_sphere(family);
    symmetries_where_documented(family);
    energy_bounded(family);
    (family.jacobian)(family);
    file_round_trips(family);
    terms_switch_off_exactly(family);
    noise_free_fit_recovers_truth_and_is_good(family);
}

/// The family's demo truth (3 channels) and its model under `setup`.
fn model(family: &Subject, setup: &ModelSetup) -> FamilyModel {
    FamilyModel::new(&family.truth, setup)
}

/// Every term on: Marschner's lobes and effects, Chiang's four terms (with a plain 256-node
/// width rule: the automatic rule places its nodes by the terms that are on, so its sums over
/// different term sets would differ by its quadrature error), each table term.
fn all_on(family: &Subject) -> ModelSetup {
    ModelSetup {
        terms: term_list(family).map(|t| TermSet::all(t.len())),
        width_nodes: WidthNodes::Fixed(256),
        ..ModelSetup::default()
    }
}

/// The family's `--terms` list (a table family's, Chiang's), if it has one.
fn term_list(family: &Subject) -> Option<&'static [Term]> {
    family
        .registered
        .and_then(ModelFamily::terms)
        .or(family.table.map(|t| t.terms()))
}

fn eval(m: &FamilyModel, angles: &[Angles]) -> Vec<f64> {
    let mut out = vec![0.0; angles.len() * m.n_channels()];
    m.eval_batch(angles, &mut out);
    out
}

/// Directions over the whole sphere pair: θ to within 0.01° of grazing, φ through ±π, and
/// incidence azimuths other than 0.
fn sphere() -> Vec<Angles> {
    let thetas = [-89.99, -75.0, -40.0, -10.0, 0.0, 5.0, 30.0, 60.0, 89.99];
    let phis = [
        -180.0, -135.0, -60.0, -1.0, 0.0, 0.5, 45.0, 90.0, 150.0, 179.9, 180.0,
    ];
    let mut v = Vec::new();
    for (k, &ti) in thetas.iter().enumerate() {
        for &tr in &thetas {
            for &pr in &phis {
                v.push(Angles::from_degrees(ti, 37.0 * k as f64 - 150.0, tr, pr));
            }
        }
    }
    v
}

/// A spread of direction pairs away from grazing, both sides of the specular cone, forward and
/// backward scattering, φ away from 0 and ±π (where |φ| has no derivative for an even model).
fn directions() -> Vec<Angles> {
    let mut v = Vec::new();
    for (k, ti) in [-50.0, -20.0, 15.0, 40.0].into_iter().enumerate() {
        for tr in [-45.0, -10.0, 30.0, 60.0] {
            for pr in [-170.0, -95.0, -20.0, 35.0, 120.0] {
                v.push(Angles::from_degrees(ti, 0.0, tr, pr + 3.0 * k as f64));
            }
        }
    }
    v
}

/// S is a radiance ratio: every value finite and ≥ 0, grazing directions included (exactly,
/// no tolerance: a negative or NaN value is a bug at any size).
fn finite_and_non_negative_over_the_sphere(family: &Subject) {
    let m = model(family, &all_on(family));
    let angles = sphere();
    for (k, s) in eval(&m, &angles).iter().enumerate() {
        assert!(
            s.is_finite() && *s >= 0.0,
            "{family}: S = {s} at {:?}",
            angles[k / 3]
        );
    }
}

/// Evenness and reciprocity where the family's page states them. Both sides are the same
/// arithmetic on mirrored or swapped inputs, so they agree to rounding: 1e-12 relative (of the
/// larger value; 1e-300 absolute below the deepest tails), well above a few hundred operations'
/// rounding and far below any real asymmetry (a few percent where a model is not symmetric).
fn symmetries_where_documented(family: &Subject) {
    let doc = &family.documented;
    let m = model(family, &all_on(family));
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) + 1e-300;
    for a in directions() {
        if doc.even_in_phi {
            let mirrored = Angles {
                phi_r: a.phi_i - (a.phi_r - a.phi_i),
                ..a
            };
            let (s, t) = (eval(&m, &[a]), eval(&m, &[mirrored]));
            for c in 0..3 {
                assert!(
                    close(s[c], t[c]),
                    "{family}: S(φ) {} vs S(−φ) {}",
                    s[c],
                    t[c]
                );
            }
        }
        let swapped = Angles {
            theta_i: a.theta_r,
            phi_i: a.phi_r,
            theta_r: a.theta_i,
            phi_r: a.phi_i,
        };
        let (columns, weigh) = match doc.reciprocity {
            Reciprocity::None => continue,
            Reciprocity::S(cols) => (cols, false),
            Reciprocity::F(cols) => (cols, true),
        };
        let (mut here, mut there) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
        m.by_lobe(&a, &mut here);
        m.by_lobe(&swapped, &mut there);
        let (wi, wr) = if weigh {
            (a.theta_i.cos(), a.theta_r.cos())
        } else {
            (1.0, 1.0)
        };
        for c in 0..3 {
            for &l in columns {
                let (f, g) = (here[c][l] * wi, there[c][l] * wr);
                assert!(
                    close(f, g),
                    "{family}: lobe {l} at {a:?}: {f} vs swapped {g}"
                );
            }
        }
    }
}

/// The white furnace seen from ω_r: `E(ω_r) = ∫ S(ω_i, ω_r) cos θ_i dω_i` with
/// `dω_i = cos θ_i dθ_i dφ`, the radiance a fibre returns toward ω_r under unit radiance from
/// every direction (the convention of the Chiang and d'Eon furnace tests). θ_i: `n`
/// Gauss–Legendre nodes on (−π/2, π/2); φ: `4n` equally spaced points (the midpoint rule,
/// spectrally accurate for a smooth periodic integrand).
fn albedo(m: &FamilyModel, theta_r: f64, n: usize) -> [f64; 3] {
    let gl = hairfit::families::shared::quadrature::GaussLegendre::new(n);
    let n_phi = 4 * n;
    let mut angles = Vec::with_capacity(n * n_phi);
    let mut weights = Vec::with_capacity(n * n_phi);
    for (x, w) in gl.nodes.iter().zip(&gl.weights) {
        let theta_i = FRAC_PI_2 * x;
        for j in 0..n_phi {
            angles.push(Angles {
                theta_i,
                phi_i: 0.0,
                theta_r,
                phi_r: -PI + 2.0 * PI * (j as f64 + 0.5) / n_phi as f64,
            });
            weights.push(FRAC_PI_2 * w * theta_i.cos().powi(2) * 2.0 * PI / n_phi as f64);
        }
    }
    let s = eval(m, &angles);
    let mut e = [0.0; 3];
    for (k, w) in weights.iter().enumerate() {
        for c in 0..3 {
            e[c] += w * s[3 * k + c];
        }
    }
    e
}

/// The white furnace: at the family's demo truth (absorbing hair) `E(ω_r)` stays within the
/// family's documented bound ([`Documented::energy`]: 1 where the model conserves energy) per
/// exit direction and channel.
/// The tolerance is the quadrature's own error, measured: the rule at 96 and at 192 nodes, and
/// `E₁₉₂ + |E₁₉₂ − E₉₆| ≤ 1` (the demo lobes, β ≥ 5°, span ≥ 10 nodes at 96, so the difference
/// overstates the error of the finer rule).
fn energy_bounded(family: &Subject) {
    let bound = family.documented.energy;
    let m = model(family, &all_on(family));
    for theta_r in [-60.0f64, -15.0, 30.0] {
        let coarse = albedo(&m, theta_r.to_radians(), 96);
        let fine = albedo(&m, theta_r.to_radians(), 192);
        for c in 0..3 {
            let err = (fine[c] - coarse[c]).abs();
            assert!(
                fine[c] + err <= bound && fine[c] > 0.0,
                "{family}: θ_r {theta_r}°, channel {c}: E = {} ± {err:e}",
                fine[c]
            );
        }
    }
}

/// The parameters nudged off the demo truth (each by a different 1.3%·(j+1), down where up
/// would leave the domain), so no derivative is taken at a special point.
fn nudged<W: Forward>(p: &ParamSet<W>, free: &[W::Param]) -> ParamSet<W>
where
    ParamSet<W>: Clone,
{
    let mut p = p.clone();
    for (j, q) in free.iter().enumerate() {
        let v = q.get(&p);
        let step = 0.013 * (j % 7 + 1) as f64;
        let up = v * (1.0 + step);
        let inside = q.check_domain(up * q.report_factor()).is_ok();
        q.set(&mut p, if inside { up } else { v * (1.0 - step) });
    }
    p
}

/// How closely a gradient pass's values must match the values pass's: relative to the value,
/// plus a floor relative to the pass's largest value.
#[derive(Clone, Copy)]
struct Agreement {
    relative: f64,
    floor: f64,
}

/// Both passes run the same code: 64 ulp (a dual number divides by multiplying with the
/// reciprocal, which rounds the last bits of some of a value's ~100 operations differently).
const SAME_CODE: Agreement = Agreement {
    relative: 64.0 * f64::EPSILON,
    floor: 0.0,
};

/// Marschner's values pass runs the SIMD lanes (their own exp, sin/cos, asin, acos), its
/// gradient pass the scalar model in dual numbers: the bound tests/families/marschner_lanes.rs
/// derives for lanes against the scalar model (1e-11 relative plus 1e-15 of the largest value;
/// 3e-13 measured there, 1.5e-14 here), still far below any change a wrong derivative or value
/// makes.
const MARSCHNER_LANES: Agreement = Agreement {
    relative: 1e-11,
    floor: 1e-15,
};

/// The family's forward model with every term on, its parameter set and its free parameters,
/// handed to [`jacobian_check`]: one arm per registered family, so a new family must give its
/// own.
fn ad_matches_finite_differences(subject: &Subject) {
    let family = subject.registered.expect("a registered family");
    let file = &subject.truth;
    let name = subject.name.as_str();
    match family {
        ModelFamily::Marschner => {
            let forward = MarschnerForward {
                config: ModelConfig::default(),
                measurement: Measurement::S,
            };
            let p = file.marschner().unwrap().to_params();
            jacobian_check(
                name,
                &forward,
                &p,
                &MarschnerFamily::parameters(3),
                MARSCHNER_LANES,
            );
        }
        ModelFamily::Chiang => {
            // A plain 128-node width rule: the Jacobian is of the discrete sum, which any node
            // count tests alike (the automatic rule moves its nodes with the parameters).
            let forward = ChiangForward {
                model: ChiangModel::new(ChiangEffects::default(), 128).unwrap(),
                measurement: Measurement::S,
            };
            let p = file.chiang().unwrap().to_params();
            jacobian_check(name, &forward, &p, &ChiangFamily::parameters(3), SAME_CODE);
        }
        ModelFamily::KajiyaKay => table_jacobian::<KajiyaKay>(subject),
        ModelFamily::DEon => table_jacobian::<DEon>(subject),
        ModelFamily::Karis => table_jacobian::<Karis>(subject),
        ModelFamily::Frostbite => table_jacobian::<Frostbite>(subject),
    }
}

fn table_jacobian<F: TableFamily>(subject: &Subject) {
    let FamilyParams::Table(t) = &subject.truth else {
        panic!("{subject}: a table family's file")
    };
    let forward = TableForward::<F>::new(TermSet::all(F::TERMS.len()), Measurement::S);
    jacobian_check(
        &subject.name,
        &forward,
        &t.to_params(),
        &Table::<F>::parameters(3),
        SAME_CODE,
    );
}

/// The dual-number Jacobian is the derivative of the values: against central differences with
/// steps `h = 1e-5·max(|x|, 1)` and h/2, Richardson-extrapolated, whose truncation error is
/// O(h⁴·S⁽⁵⁾) (below 1e-10 relative even in lobe tails) and whose rounding error is ≈
/// 1e-16/h ≈ 1e-11; 1e-6 relative (of the row's largest entry) leaves room for curvature near
/// lobe peaks and interpolation-table knots and nothing more. The values of the gradient pass
/// are the values pass's to `agreement` ([`SAME_CODE`] where both run the same code).
fn jacobian_check<W: Forward>(
    family: &str,
    forward: &W,
    truth: &ParamSet<W>,
    free: &[W::Param],
    agreement: Agreement,
) where
    ParamSet<W>: Clone,
{
    let p = nudged::<W>(truth, free);
    let angles = directions();
    let m = angles.len() * 3;
    let (mut out, mut grad) = (vec![0.0; m], vec![0.0; m * free.len()]);
    forward.gradients(&p, free, &angles, &mut out, &mut grad);
    let mut plain = vec![0.0; m];
    forward.values(&p, &angles, &mut plain);
    let floor = agreement.floor * plain.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, (a, b)) in out.iter().zip(&plain).enumerate() {
        assert!(
            (a - b).abs() <= agreement.relative * a.abs().max(b.abs()) + floor,
            "{family}: value {k}: the gradients pass gives {a:e}, the values pass {b:e}"
        );
    }
    for (j, q) in free.iter().enumerate() {
        let x = q.get(&p);
        let h = 1e-5 * x.abs().max(1.0);
        let at = |dx: f64| {
            let mut pp = p.clone();
            q.set(&mut pp, x + dx);
            let mut o = vec![0.0; m];
            forward.values(&pp, &angles, &mut o);
            o
        };
        let (up, down) = (at(h), at(-h));
        let (half_up, half_down) = (at(h / 2.0), at(-h / 2.0));
        for r in 0..m {
            let fd_h = (up[r] - down[r]) / (2.0 * h);
            let fd_half = (half_up[r] - half_down[r]) / h;
            let fd = (4.0 * fd_half - fd_h) / 3.0;
            let ad = grad[r * free.len() + j];
            let row_scale = (0..free.len())
                .map(|k| grad[r * free.len() + k].abs())
                .fold(out[r].abs(), f64::max);
            assert!(
                (fd - ad).abs() <= 1e-6 * row_scale.max(1e-300),
                "{family} d/d{}: row {r} at {:?}: AD {ad} vs FD {fd}",
                q.json_name(),
                angles[r / 3]
            );
        }
    }
}

/// A parameter file reads back as the parameters it was written from (JSON text, bit for bit),
/// names its family, and is refused under another family's `--model` with the file's name. A
/// registered family is read as `--model NAME` reads it; one only a test knows, as that path
/// reads a table family's file once `NAME` has found its table.
fn file_round_trips(subject: &Subject) {
    let file = &subject.truth;
    let path = std::path::Path::new("p.json");
    let text = serde_json::to_string_pretty(file).unwrap();
    let back = match (subject.registered, subject.table) {
        (Some(family), _) => {
            let back = FamilyParams::from_json_text(text.clone(), path, family).unwrap();
            assert_eq!(back.family(), family);
            let tagged: FamilyParams = serde_json::from_str(&text).unwrap();
            assert_eq!(
                &tagged, file,
                "{subject}: fit.json's params read by the tag"
            );
            back
        }
        (None, Some(table)) => TableParamFile::from_json_str(&text, path, table)
            .unwrap()
            .into(),
        (None, None) => panic!("{subject}: only a table family can be unregistered"),
    };
    assert_eq!(&back, file, "{subject}");
    let other = ModelFamily::ALL
        .into_iter()
        .find(|f| Some(*f) != subject.registered && *f != ModelFamily::Marschner)
        .unwrap();
    let e = FamilyParams::from_json_text(text, path, other)
        .unwrap_err()
        .to_string();
    assert!(e.contains("p.json"), "{subject} read as {other}: {e}");
}

/// Each switchable term of the family, as (its name, the setup without it, the setup with it
/// alone): each of the family's `--terms` (Chiang's, a table family's), else each lobe.
fn switches(family: &Subject) -> Vec<(String, ModelSetup, ModelSetup)> {
    let all = all_on(family);
    if let Some(terms) = term_list(family) {
        let n = terms.len();
        let every = TermSet::all(n);
        return (0..n)
            .filter(|&k| every.0 & !(1 << k) != 0)
            .map(|k| {
                let with = |on: TermSet| ModelSetup {
                    terms: Some(on),
                    ..all.clone()
                };
                (
                    terms[k].name.to_string(),
                    with(TermSet(every.0 & !(1 << k))),
                    with(TermSet(1 << k)),
                )
            })
            .collect();
    }
    // A family without terms switches the lobes of `--lobes`.
    (0..3)
        .map(|k| {
            let lobes = |on: [bool; 3]| {
                let mut s = all.clone();
                s.config.effects.lobes = Lobes {
                    r: on[0],
                    tt: on[1],
                    trt: on[2],
                };
                s
            };
            let mut without = [true; 3];
            without[k] = false;
            let mut only = [false; 3];
            only[k] = true;
            (format!("lobe {k}"), lobes(without), lobes(only))
        })
        .collect()
}

/// With one term off, S is the sum of the others: total = without + alone, and the by-lobe
/// columns sum to S, to a few ulps (sums of the same terms in different orders: 1e-12
/// relative).
fn terms_switch_off_exactly(family: &Subject) {
    let angles = directions();
    let m = model(family, &all_on(family));
    let total = eval(&m, &angles);
    let mut lobes = vec![[0.0; 3]; 3];
    for (k, a) in angles.iter().enumerate() {
        m.by_lobe(a, &mut lobes);
        for c in 0..3 {
            let sum: f64 = lobes[c].iter().sum();
            let s = total[3 * k + c];
            assert!(
                (sum - s).abs() <= 1e-12 * s.abs(),
                "{family}: by lobe {sum} vs S {s}"
            );
        }
    }
    for (name, without, only) in switches(family) {
        let rest = eval(&model(family, &without), &angles);
        let term = eval(&model(family, &only), &angles);
        for k in 0..total.len() {
            assert!(
                (rest[k] + term[k] - total[k]).abs() <= 1e-12 * total[k].abs(),
                "{family}: term {name} at {:?}: {} + {} vs {}",
                angles[k / 3],
                rest[k],
                term[k],
                total[k]
            );
        }
    }
}

/// Synthesize the demo geometry from the family's demo truth without noise and fit it with the
/// default options, through the family's [`FamilyFit`] (what `--model NAME` runs).
fn noise_free_fit(family: &Subject) -> FitJson {
    let file = &family.truth;
    let setup = ModelSetup::default();
    let model = FamilyModel::new(file, &setup);
    let source = Source {
        model: &model,
        file,
        records: match family.table {
            Some(table) => setup.table_records(table),
            None => setup.records(family.registered.unwrap()),
        },
    };
    let how = Acquisition {
        directions: &demo_directions(),
        label: "battery",
        noise: &Noise::parse("none").unwrap(),
        scale: &DEMO_SCALE,
        measurement: Measurement::S,
        seed: 7,
    };
    let (dataset, _) = hairfit::synth::synthesize_model(&source, &how).unwrap();
    let data = hairfit::fit::fit_data(&dataset);
    let opts = FitOptions {
        family: family.registered.unwrap_or_default(),
        intervals: hairfit::fit::Intervals::Linear,
        ..FitOptions::default()
    };
    let input = FitInput::new(&data, "battery.csv", LoadReport::default(), &opts);
    family.fit.fit(input).unwrap().json
}

/// Noise-free data are an exact zero of the residual: the verdict is `good`, every free
/// parameter and scale is recovered to 1e-6 relative (the solver's stopping tolerance, far
/// above rounding; 1e-6 absolute for a parameter whose truth is within 1e-3 of zero).
fn noise_free_fit_recovers_truth_and_is_good(family: &Subject) {
    let fit = noise_free_fit(family);
    assert_eq!(fit.verdict, Verdict::Good, "{family}: {:?}", fit.reasons);
    let truth = serde_json::to_value(&family.truth).unwrap();
    for e in fit
        .parameters
        .iter()
        .filter(|e| e.status == ParamStatus::Free)
    {
        let want = value_of(&truth, &e.name);
        let got = e.value.unwrap();
        assert!(
            (got - want).abs() <= 1e-6 * want.abs().max(1e-3),
            "{family}: {} = {got}, truth {want}",
            e.name
        );
    }
    for (s, want) in fit.scale.iter().zip(DEMO_SCALE) {
        let got = s.value.unwrap();
        assert!((got - want).abs() <= 1e-6 * want, "{family}: scale {got}");
    }
}

/// The value of `name` (`sigma_a[1]` included) in a parameter file's JSON; a scalar stands for
/// every channel.
fn value_of(file: &serde_json::Value, name: &str) -> f64 {
    let (base, channel) = match name.strip_suffix(']').and_then(|n| n.split_once('[')) {
        Some((b, c)) => (b, c.parse::<usize>().unwrap()),
        None => (name, 0),
    };
    match &file[base] {
        serde_json::Value::Array(v) => v[if v.len() == 1 { 0 } else { channel }].as_f64().unwrap(),
        v => v
            .as_f64()
            .unwrap_or_else(|| panic!("{name} not in the truth file {file}")),
    }
}
