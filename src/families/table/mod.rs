//! The model families that are one parameter table and one scattering function: Kajiya–Kay
//! 1989 and the families real-time renderers approximate Marschner with. A family is one type
//! implementing [`TableFamily`] — its terms ([`Term`]), its parameter table ([`ParamFact`], every
//! parameter's name, unit, domain, fit bounds, typical range and default in one line) and
//! `scatter`, generic over the number type so dual numbers give exact derivatives. Everything
//! else is written once for all of them: the parameter file ([`file`]), evaluation
//! ([`DynTable`], what commands hold), and, in `crate::families::table::fit`, the fit.
//!
//! What a term switch turns off is not computed, and a parameter only the switched-off terms
//! read is not fitted ([`ParamFact::terms`]).

pub mod file;
pub mod fit;

use std::marker::PhantomData;

use num_dual::DualNum;

use crate::error::{Error, Result};
use crate::families::effects::{Effects, Lobes, ModelConfig};
use crate::geometry::Angles;
use crate::geometry::Fitted;
pub use crate::geometry::ParamFact;

pub use file::TableParamFile;

/// Which of curves.csv's per-lobe columns a term adds to (`R`, `TT`, `TRT`; a diffuse or
/// multiple-scattering term goes with `TRT`, as Chiang's p ≥ 3 residual does).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LobeColumn {
    R = 0,
    TT = 1,
    TRT = 2,
}

/// One term of a family's `S`, switched by `--terms`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Term {
    /// The `--terms` word (case-insensitive on input).
    pub name: &'static str,
    pub meaning: &'static str,
    pub column: LobeColumn,
}

/// The terms that are on, as bits over the family's [`TableFamily::TERMS`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TermSet(pub u32);

impl TermSet {
    /// Every one of `n` terms.
    pub fn all(n: usize) -> TermSet {
        TermSet((1u32 << n) - 1)
    }

    /// True when term `k` is on.
    pub fn has(self, k: usize) -> bool {
        self.0 & (1 << k) != 0
    }

    /// Parse `R,TT,TRT` against `terms` (case-insensitive); `family` names the family in errors.
    pub fn parse(list: &str, terms: &[Term], family: &str) -> Result<TermSet> {
        let names = || terms.iter().map(|t| t.name).collect::<Vec<_>>().join(", ");
        let mut bits = 0u32;
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let k = terms
                .iter()
                .position(|t| t.name.eq_ignore_ascii_case(item))
                .ok_or_else(|| {
                    Error::Other(format!(
                        "unknown {family} term `{item}` in `{list}`: use a comma-separated list of {}",
                        names()
                    ))
                })?;
            bits |= 1 << k;
        }
        if bits == 0 {
            return Err(Error::Other(format!(
                "term list `{list}` is empty: name at least one of {}",
                names()
            )));
        }
        Ok(TermSet(bits))
    }

    /// The names of the terms that are on, in the table's order.
    pub fn names(self, terms: &[Term]) -> Vec<String> {
        let on = terms.iter().enumerate().filter(|(k, _)| self.has(*k));
        on.map(|(_, t)| t.name.to_string()).collect()
    }

    /// True when a term named in `names` is on (empty `names`: every term reads it).
    fn any_named(self, terms: &[Term], names: &[&str]) -> bool {
        names.is_empty()
            || terms
                .iter()
                .enumerate()
                .any(|(k, t)| self.has(k) && names.contains(&t.name))
    }
}

/// A family's parameters in model units (radians for angles): one vector per table line, one
/// value (shared) or one per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct TableParams<T> {
    pub values: Vec<Vec<T>>,
    pub n_channels: usize,
}

impl<T: Clone> TableParams<T> {
    /// Parameter `fact` of channel `c` (a shared parameter has one value for every channel).
    #[inline]
    pub fn get(&self, fact: usize, c: usize) -> T {
        let v = &self.values[fact];
        v[if v.len() == 1 { 0 } else { c }].clone()
    }

    /// Map `f` over every value (e.g. lift f64 to duals).
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> TableParams<U> {
        TableParams {
            values: self
                .values
                .iter()
                .map(|v| v.iter().map(&f).collect())
                .collect(),
            n_channels: self.n_channels,
        }
    }
}

impl TableParams<f64> {
    /// Every parameter at its table default, for `nc` channels.
    pub fn defaults(facts: &[ParamFact], nc: usize) -> TableParams<f64> {
        let values = facts
            .iter()
            .map(|f| vec![f.unit.to_model(f.held()); if f.per_channel { nc } else { 1 }])
            .collect();
        TableParams {
            values,
            n_channels: nc,
        }
    }

    /// Check every value against its domain; the error names the parameter (`base_color[1]`).
    pub fn validate(&self, facts: &[ParamFact]) -> Result<()> {
        for (fact, values) in facts.iter().zip(&self.values) {
            for (c, &v) in values.iter().enumerate() {
                let file_value = v * fact.unit.file_factor();
                if let Err(message) = fact.check(file_value) {
                    return Err(Error::Parameter {
                        name: param_name(fact, fact.per_channel.then_some(c)),
                        value: file_value,
                        message,
                    });
                }
            }
        }
        Ok(())
    }
}

/// The demo's truth of a table family for `nc` channels: shared parameters at their default,
/// per-channel ones spread over the typical range (a quarter, half and three quarters of the
/// way for three channels), so the channels differ as hair colours do.
pub fn demo_params(facts: &[ParamFact], nc: usize) -> TableParams<f64> {
    let mut p = TableParams::defaults(facts, nc);
    for (f, values) in facts.iter().zip(&mut p.values) {
        if f.per_channel {
            let (lo, hi) = f.typical;
            for (c, v) in values.iter_mut().enumerate() {
                let t = (c as f64 + 1.0) / (nc as f64 + 1.0);
                *v = f.unit.to_model(lo + t * (hi - lo));
            }
        }
    }
    p
}

/// A table's number as its page and messages write it: seven significant digits
/// (`2.005352`, not `2.0053522829578814`), `inf` for an open end.
pub fn table_number(x: f64) -> String {
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.to_string();
    }
    let rounded: f64 = format!("{x:.6e}").parse().unwrap_or(x);
    format!("{rounded}")
}

/// The parameter table as docs print it (a header and one Markdown row per line), so
/// `tests/families/table_families.rs` can check each family's page holds exactly its table.
pub fn markdown_table(facts: &[ParamFact]) -> Vec<String> {
    let num = table_number;
    let mut rows = vec![
        "| key | symbol | meaning | unit | per channel | domain | fit bounds | typical | default | fitted | read by |".to_string(),
        "|---|---|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    rows.extend(facts.iter().map(|f| {
        let fitted = match f.fitted {
            Fitted::Yes => "yes",
            Fitted::OnRequest => "with `--free eta`",
            Fitted::No => "no (held; `--fix` sets it)",
        };
        let read_by = if f.terms.is_empty() {
            "every term".to_string()
        } else {
            f.terms.join(", ")
        };
        format!(
            "| `{}` | {} | {} | {} | {} | {} | [{}, {}] | {} to {} | {} | {} | {} |",
            f.name,
            f.symbol,
            f.meaning,
            f.unit.describe(),
            if f.per_channel { "yes" } else { "no" },
            f.domain.text(),
            num(f.fit_lo),
            num(f.fit_hi.unwrap_or(f64::INFINITY)),
            num(f.typical.0),
            num(f.typical.1),
            num(f.held()),
            fitted,
            read_by
        )
    }));
    rows
}

/// `name` or `name[c]`.
pub fn param_name(fact: &ParamFact, channel: Option<usize>) -> String {
    match channel {
        Some(c) => format!("{}[{c}]", fact.name),
        None => fact.name.to_string(),
    }
}

/// A model family given by one parameter table and one scattering function.
pub trait TableFamily: Send + Sync + 'static {
    /// The `--model` name.
    const NAME: &'static str;
    /// Who and what, for summaries ("Kajiya–Kay 1989").
    const TITLE: &'static str;
    const TERMS: &'static [Term];
    const PARAMETERS: &'static [ParamFact];
    /// A `--fix` item for messages to show.
    const FIX_EXAMPLE: &'static str;

    /// The terms on without `--terms` (every term unless the family says otherwise).
    fn default_terms() -> TermSet {
        TermSet::all(Self::TERMS.len())
    }

    /// Each channel's `S` term by term (`out[c][k]` for [`TableFamily::TERMS`]`[k]`; they add
    /// up to `S`) at angles `a` with the terms `on`. `out` comes zeroed; a term that is off is
    /// not computed and stays zero.
    fn scatter<T: DualNum<f64>>(p: &TableParams<T>, a: &Angles, on: TermSet, out: &mut [Terms<T>]);

    /// [`TableFamily::scatter`] at every one of `angles`: `each(i, terms)` receives sample `i`'s
    /// terms, in any order of `i`, each exactly once, with the very values `scatter` gives. A
    /// family whose samples share work (the same azimuthal integral at the same θ_d and φ)
    /// overrides it to do that work once.
    fn scatter_each<T: DualNum<f64>>(
        p: &TableParams<T>,
        angles: &[Angles],
        on: TermSet,
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        let mut terms = zero_terms::<T>(p.n_channels);
        for (i, a) in angles.iter().enumerate() {
            clear_terms(&mut terms);
            Self::scatter(p, a, on, &mut terms);
            each(i, &terms);
        }
    }

    /// What the multi-start's screening forward does differently, for fit.json's reasons; `None`
    /// (the default): the multi-start uses [`TableFamily::scatter_each`] itself.
    const SCREENING: Option<&'static str> = None;

    /// [`TableFamily::scatter_each`] with a cheaper rule (fewer quadrature nodes), for the
    /// multi-start on the subsample, which only looks for basins: the polish, the intervals and
    /// everything reported use `scatter_each`. Overridden with [`TableFamily::SCREENING`].
    fn screen_each<T: DualNum<f64>>(
        p: &TableParams<T>,
        angles: &[Angles],
        on: TermSet,
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        Self::scatter_each(p, angles, on, each)
    }

    /// [`TableFamily::scatter_each`] (or `screen_each`, as `pass` says) in a gradient pass, whose
    /// dual numbers carry derivative parts only on the table lines `pass.seeded`: a family may
    /// take a part that reads few of them with shorter duals and chain it. By default the pass's
    /// own `scatter_each` or `screen_each`.
    fn dual_each<T: DualNum<f64>>(
        p: &TableParams<T>,
        angles: &[Angles],
        on: TermSet,
        pass: DualPass,
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        if pass.screening {
            Self::screen_each(p, angles, on, each)
        } else {
            Self::scatter_each(p, angles, on, each)
        }
    }

    /// Whether a gradient pass seeding the table lines `seeded` (bit k: line k) costs little more
    /// than a value pass and gives its values to the bit (`Forward::cheap_gradients`): then
    /// every value pass of the fit computes the gradients too. No by default.
    fn cheap_gradients(_seeded: u32) -> bool {
        false
    }
}

/// What a gradient pass evaluates ([`TableFamily::dual_each`]).
#[derive(Debug, Clone, Copy)]
pub struct DualPass {
    /// The multi-start's screening forward (`screen_each`), not `scatter_each`.
    pub screening: bool,
    /// Bit k: table line k's values carry derivative parts (the others' are zero).
    pub seeded: u32,
}

impl DualPass {
    /// True when table line `k` carries derivative parts.
    pub fn seeds(self, k: usize) -> bool {
        self.seeded & (1 << k) != 0
    }
}

/// The most terms a family has.
pub const MAX_TERMS: usize = 6;

/// One channel's value of each term.
pub type Terms<T> = [T; MAX_TERMS];

/// `nc` channels of zeroed terms.
pub fn zero_terms<T: DualNum<f64>>(nc: usize) -> Vec<Terms<T>> {
    (0..nc)
        .map(|_| std::array::from_fn(|_| T::zero()))
        .collect()
}

/// Zero every term of `out` (the state [`TableFamily::scatter`] expects).
pub fn clear_terms<T: DualNum<f64>>(out: &mut [Terms<T>]) {
    for t in out.iter_mut().flatten() {
        *t = T::zero();
    }
}

/// The terms of one channel summed into curves.csv's columns `[R, TT, TRT]`.
pub fn columns<T: DualNum<f64>>(terms: &[Term], values: &Terms<T>) -> [T; 3] {
    let mut out = [T::zero(), T::zero(), T::zero()];
    for (t, v) in terms.iter().zip(values) {
        let col = &mut out[t.column as usize];
        *col = col.clone() + v.clone();
    }
    out
}

/// The terms of one channel summed: `S`.
pub fn total<T: DualNum<f64>>(values: &Terms<T>) -> T {
    values.iter().fold(T::zero(), |s, v| s + v.clone())
}

/// A [`TableFamily`] as a value: what commands hold ([`DynTable`]) and what the fit implements
/// its `Family` for.
pub struct Table<F>(PhantomData<fn() -> F>);

impl<F> Table<F> {
    pub const NEW: Table<F> = Table(PhantomData);
}

/// A table family's model with its parameters and the terms that are on.
#[derive(Debug, Clone)]
pub struct TableModel {
    pub table: &'static dyn DynTable,
    pub params: TableParams<f64>,
    pub terms: TermSet,
}

impl crate::families::ScatteringModel for TableModel {
    fn n_channels(&self) -> usize {
        self.params.n_channels
    }

    fn eval_batch(&self, angles: &[Angles], out: &mut [f64]) {
        self.table.eval_batch(&self.params, self.terms, angles, out)
    }

    fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]) {
        self.table.by_lobe(&self.params, self.terms, angles, out)
    }
}

/// A table family behind a pointer, chosen at run time by `--model`; its name, title and
/// parameter table are its [`FamilyFacts`](crate::geometry::FamilyFacts).
pub trait DynTable: crate::geometry::FamilyFacts {
    fn terms(&self) -> &'static [Term];
    /// The terms on without `--terms`.
    fn default_terms(&self) -> TermSet;
    /// `S` of a batch, `out[k·nc + c]`.
    fn eval_batch(&self, p: &TableParams<f64>, on: TermSet, angles: &[Angles], out: &mut [f64]);
    /// Per-column values `[R, TT, TRT]` per channel at one direction pair.
    fn by_lobe(&self, p: &TableParams<f64>, on: TermSet, a: &Angles, out: &mut [[f64; 3]]);
}

impl<F: TableFamily> crate::geometry::FamilyFacts for Table<F> {
    fn name(&self) -> &'static str {
        F::NAME
    }
    fn title(&self) -> &'static str {
        F::TITLE
    }
    fn citation(&self) -> &'static str {
        F::TITLE
    }
    fn parameters(&self) -> &'static [ParamFact] {
        F::PARAMETERS
    }
    fn own_options(&self) -> &'static [&'static str] {
        &["--terms"]
    }
}

impl<F: TableFamily> DynTable for Table<F> {
    fn terms(&self) -> &'static [Term] {
        F::TERMS
    }
    fn default_terms(&self) -> TermSet {
        F::default_terms()
    }
    fn eval_batch(&self, p: &TableParams<f64>, on: TermSet, angles: &[Angles], out: &mut [f64]) {
        let nc = p.n_channels;
        F::scatter_each(p, angles, on, &mut |i, terms| {
            for (v, t) in out[i * nc..(i + 1) * nc].iter_mut().zip(terms) {
                *v = total(t);
            }
        });
    }
    fn by_lobe(&self, p: &TableParams<f64>, on: TermSet, a: &Angles, out: &mut [[f64; 3]]) {
        let mut terms = zero_terms(p.n_channels);
        F::scatter(p, a, on, &mut terms);
        for (o, t) in out.iter_mut().zip(&terms) {
            *o = columns(F::TERMS, t);
        }
    }
}

impl std::fmt::Debug for dyn DynTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The Marschner-shaped record of which lobe columns the terms `on` fill (fit.json `model`,
/// what the report draws): no glints, no eccentricity.
pub fn lobes_config(terms: &[Term], on: TermSet) -> ModelConfig {
    let filled = |col: LobeColumn| {
        terms
            .iter()
            .enumerate()
            .any(|(k, t)| on.has(k) && t.column == col)
    };
    ModelConfig {
        mode: Default::default(),
        effects: Effects {
            lobes: Lobes {
                r: filled(LobeColumn::R),
                tt: filled(LobeColumn::TT),
                trt: filled(LobeColumn::TRT),
            },
            glints: false,
            eccentricity: false,
        },
    }
}

/// The parameters (table index, channel) a fit of `facts` under the terms `on` varies before
/// `--fix`: those an on term reads, an `OnRequest` `eta` only when `free_on_request`
/// (`--free eta`).
pub fn fitted(
    facts: &[ParamFact],
    terms: &[Term],
    on: TermSet,
    nc: usize,
    free_on_request: bool,
) -> Vec<(usize, Option<usize>)> {
    let wanted = |f: &ParamFact| {
        let asked = match f.fitted {
            Fitted::Yes => true,
            // `--free` frees η only; the tables mark nothing else on request.
            Fitted::OnRequest => free_on_request && f.name == "eta",
            Fitted::No => false,
        };
        asked && on.any_named(terms, f.terms)
    };
    let mut all = every_parameter(facts, nc);
    all.retain(|&(k, _)| wanted(&facts[k]));
    all
}

/// Every parameter (table index, channel) for `nc` channels, in output order.
pub fn every_parameter(facts: &[ParamFact], nc: usize) -> Vec<(usize, Option<usize>)> {
    let mut out = Vec::new();
    for (k, f) in facts.iter().enumerate() {
        if f.per_channel {
            out.extend((0..nc).map(|c| (k, Some(c))));
        } else {
            out.push((k, None));
        }
    }
    out
}
