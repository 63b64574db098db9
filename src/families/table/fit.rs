//! `hairfit fit --model NAME` for every table family ([`crate::families::table`]), written once:
//! its parameters as the fit sees them ([`TableParam`], facts from the family's table), its
//! forward model with exact derivatives by forward-mode dual numbers ([`TableForward`]), and
//! its part of a fit (free parameters from the terms in play, `--fix` names, the words for an
//! undetermined parameter) handed to the shared stages ([`crate::fit::fit_with`]).

use std::marker::PhantomData;

use nalgebra::{allocator::Allocator, DefaultAllocator, Dim, U1};
use num_dual::{Derivative, DualNum, DualVec64};

use crate::error::Result;
use crate::families::table::{
    every_parameter, fitted, lobes_config, param_name, total, DualPass, DynTable, ParamFact, Table,
    TableFamily, TableParamFile, TableParams, TermSet, Terms,
};
use crate::families::{FamilyParams, ModelRecords};
use crate::files::{EffectsSource, Floored};
use crate::fit::bounds::Bound;
use crate::fit::family::{Family, FitInput};
use crate::fit::fixes::FreeSet;
use crate::fit::problem::{with_dual_dim, FitData, FitParam, Forward};
use crate::fit::stages::{options_record, ModelChoice};
use crate::fit::{diagnostics, fit_with, require_samples, FitOutcome, FitRun};
use crate::geometry::{Angles, Measurement};

/// One parameter of the table family `F`: a line of its table and, for a per-channel line,
/// the channel.
pub struct TableParam<F> {
    fact: u16,
    channel: Option<u16>,
    family: PhantomData<fn() -> F>,
}

impl<F> Clone for TableParam<F> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<F> Copy for TableParam<F> {}
impl<F> PartialEq for TableParam<F> {
    fn eq(&self, other: &Self) -> bool {
        (self.fact, self.channel) == (other.fact, other.channel)
    }
}

impl<F: TableFamily> std::fmt::Debug for TableParam<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.json_name())
    }
}

impl<F: TableFamily> TableParam<F> {
    /// Line `fact` of `F`'s table, channel `channel` of a per-channel line.
    pub fn new((fact, channel): (usize, Option<usize>)) -> TableParam<F> {
        TableParam {
            fact: fact as u16,
            channel: channel.map(|c| c as u16),
            family: PhantomData,
        }
    }

    fn fact(self) -> &'static ParamFact {
        &F::PARAMETERS[self.fact as usize]
    }

    fn at(self) -> (usize, usize) {
        (self.fact as usize, self.channel.unwrap_or(0) as usize)
    }
}

impl<F: TableFamily> FitParam for TableParam<F> {
    type Set = TableParams<f64>;
    fn get(self, p: &TableParams<f64>) -> f64 {
        let (k, c) = self.at();
        p.values[k][c]
    }
    fn set(self, p: &mut TableParams<f64>, value: f64) {
        let (k, c) = self.at();
        p.values[k][c] = value;
    }
    fn bound(self) -> Bound {
        let f = self.fact();
        let factor = f.unit.file_factor();
        Bound::Both(
            f.fit_lo / factor,
            f.fit_hi.unwrap_or(f64::INFINITY) / factor,
        )
    }
    fn json_name(self) -> String {
        param_name(self.fact(), self.channel.map(usize::from))
    }
    fn report_factor(self) -> f64 {
        self.fact().unit.file_factor()
    }
    fn typical_range(self) -> (f64, f64) {
        let f = self.fact();
        let factor = f.unit.file_factor();
        (f.typical.0 / factor, f.typical.1 / factor)
    }
    fn check_domain(self, report_value: f64) -> std::result::Result<(), String> {
        self.fact().check(report_value)
    }
    fn channel(self) -> Option<usize> {
        self.channel.map(usize::from)
    }
}

/// The table family `F` under its terms `on`, as the data measure it: `S`, or `S · cos θ_i`.
pub struct TableForward<F> {
    pub on: TermSet,
    pub measurement: Measurement,
    /// Evaluate with [`TableFamily::screen_each`] (the multi-start's screening forward).
    screening: bool,
    family: PhantomData<fn() -> F>,
}

impl<F: TableFamily> TableForward<F> {
    pub fn new(on: TermSet, measurement: Measurement) -> TableForward<F> {
        TableForward {
            on,
            measurement,
            screening: false,
            family: PhantomData,
        }
    }

    /// The family's screening forward ([`TableFamily::screen_each`]), if it has one.
    pub fn screening(&self) -> Option<TableForward<F>> {
        F::SCREENING.map(|_| TableForward {
            screening: true,
            ..TableForward::new(self.on, self.measurement)
        })
    }

    /// `each(i, terms)` for every sample: [`TableFamily::scatter_each`], or `screen_each`.
    fn each<T: DualNum<f64>>(
        &self,
        p: &TableParams<T>,
        angles: &[Angles],
        each: &mut dyn FnMut(usize, &[Terms<T>]),
    ) {
        if self.screening {
            F::screen_each(p, angles, self.on, each)
        } else {
            F::scatter_each(p, angles, self.on, each)
        }
    }

    /// Values and gradients in the measured quantity with `slots` derivative parts, each
    /// `(parameter, slot)` of `seeds` seeded in its slot ([`Self::dual_pass`]).
    fn seeded_pass(
        &self,
        p: &TableParams<f64>,
        seeds: &[(TableParam<F>, usize)],
        slots: usize,
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        with_dual_dim!(slots, |dim| self.dual_pass(
            dim,
            p,
            seeds,
            angles,
            (out, grad)
        ));
        let rows = angles.len() * p.n_channels;
        self.measurement.apply(angles, &mut out[..rows]);
        self.measurement.apply(angles, grad);
    }

    /// Values and the `dim` derivative parts: each `(parameter, slot)` of `seeds` is seeded in
    /// its slot (several parameters may share one when no row depends on two of them).
    fn dual_pass<D: Dim>(
        &self,
        dim: D,
        p: &TableParams<f64>,
        seeds: &[(TableParam<F>, usize)],
        angles: &[Angles],
        (out, grad): (&mut [f64], &mut [f64]),
    ) where
        DefaultAllocator: Allocator<D>,
        DualVec64<D>: DualNum<f64>,
    {
        let mut pd = p.map(|&x| DualVec64::<D>::from_re(x));
        for &(q, j) in seeds {
            let (k, c) = q.at();
            let direction = Derivative::derivative_generic(dim, U1, j);
            pd.values[k][c] = DualVec64::new(p.values[k][c], direction);
        }
        let pass = DualPass {
            screening: self.screening,
            seeded: seeded_lines(seeds.iter().map(|&(q, _)| q)),
        };
        let nc = p.n_channels;
        let nw = dim.value();
        F::dual_each(&pd, angles, self.on, pass, &mut |i, terms| {
            for (c, t) in terms.iter().enumerate() {
                let r = i * nc + c;
                let v = total(t);
                out[r] = v.re;
                let e = v.eps.unwrap_generic(dim, U1);
                grad[r * nw..(r + 1) * nw].copy_from_slice(e.as_slice());
            }
        });
    }
}

/// The table lines of `params`, as bits (bit k: line k).
fn seeded_lines<F>(params: impl IntoIterator<Item = TableParam<F>>) -> u32 {
    params.into_iter().fold(0, |bits, q| bits | 1 << q.fact)
}

impl<F: TableFamily> Forward for TableForward<F> {
    type Param = TableParam<F>;

    fn values(&self, p: &TableParams<f64>, angles: &[Angles], out: &mut [f64]) {
        let nc = p.n_channels;
        let out = &mut out[..angles.len() * nc];
        self.each(p, angles, &mut |i, terms| {
            for (v, t) in out[i * nc..(i + 1) * nc].iter_mut().zip(terms) {
                *v = total(t);
            }
        });
        self.measurement.apply(angles, out);
    }

    fn gradients(
        &self,
        p: &TableParams<f64>,
        free: &[TableParam<F>],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        let seeds: Vec<_> = free.iter().copied().zip(0..).collect();
        self.seeded_pass(p, &seeds, free.len(), angles, out, grad);
    }

    /// Every channel's local parameter seeded in the one last slot: a table family's channel
    /// `c` reads only its own per-channel values (`p.get(k, c)`), so the slot holds
    /// ∂value_c/∂local[c] exactly, at the cost of `shared.len() + 1` derivative parts instead
    /// of one per channel more.
    fn gradients_compressed(
        &self,
        p: &TableParams<f64>,
        shared: &[TableParam<F>],
        local: &[Option<TableParam<F>>],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        let ns = shared.len();
        let mut seeds: Vec<_> = shared.iter().copied().zip(0..).collect();
        seeds.extend(local.iter().flatten().map(|&q| (q, ns)));
        self.seeded_pass(p, &seeds, ns + 1, angles, out, grad);
    }

    fn cheap_gradients(&self, free: &[TableParam<F>]) -> bool {
        F::cheap_gradients(seeded_lines(free.iter().copied()))
    }

    fn by_lobe(&self, p: &TableParams<f64>, angles: &Angles, out: &mut [[f64; 3]]) -> bool {
        table::<F>().by_lobe(p, self.on, angles, out);
        self.measurement
            .apply(std::slice::from_ref(angles), out.as_flattened_mut());
        true
    }

    fn measurement(&self) -> Measurement {
        self.measurement
    }
}

/// `F` as the table family commands hold.
fn table<F: TableFamily>() -> &'static dyn DynTable {
    const { &Table::<F>::NEW }
}

impl<F: TableFamily> Family for Table<F> {
    type Param = TableParam<F>;
    const PARAMETER_WORD: &'static str = "parameter";
    const FIX_EXAMPLE: &'static str = F::FIX_EXAMPLE;

    fn parameters(nc: usize) -> Vec<TableParam<F>> {
        every_parameter(F::PARAMETERS, nc)
            .into_iter()
            .map(TableParam::new)
            .collect()
    }

    fn fit(i: FitInput<'_>) -> Result<FitOutcome<FamilyParams>> {
        let out = fit_table::<F>(i)?;
        let file = TableParamFile::from_params(table::<F>(), &out.params);
        Ok(out.map_params(|_| FamilyParams::Table(file)))
    }
}

/// Why the data cannot determine `p`: the terms that read it, then its partners.
fn why_undetermined<F: TableFamily>(
    p: TableParam<F>,
    data: &FitData,
    partners: &[String],
) -> String {
    let tail = diagnostics::correlated_tail(partners);
    let terms = p.fact().terms;
    let reads = if terms.is_empty() {
        "every term".to_string()
    } else {
        terms.join(", ")
    };
    format!(
        "{} reads it; the samples span theta_h by {:.1} deg and {} of them have |phi| > 135 deg{tail}",
        reads,
        diagnostics::theta_h_span(data).to_degrees(),
        diagnostics::tt_region_samples(data)
    )
}

/// Fit the table family `F` under `opts.model.terms` (all when absent).
fn fit_table<F: TableFamily>(i: FitInput<'_>) -> Result<FitOutcome<TableParams<f64>>> {
    let FitInput {
        data, file, opts, ..
    } = i;
    let nc = require_samples(data, file)?;
    let on = opts.model.terms.unwrap_or(F::default_terms());
    let forward = TableForward::<F>::new(on, opts.measurement);
    let screening = forward.screening();
    let mut warnings = Vec::new();
    let params_of = |on: TermSet| -> Vec<TableParam<F>> {
        fitted(F::PARAMETERS, F::TERMS, on, nc, opts.free_eta)
            .into_iter()
            .map(TableParam::new)
            .collect()
    };
    let set = FreeSet::new(
        <Table<F> as Family>::parse_fixes(&opts.fix, nc)?,
        TableParams::defaults(F::PARAMETERS, nc),
        params_of(on),
        params_of(TermSet::all(F::TERMS.len())),
        "the terms in play do not read it",
        &mut warnings,
    );
    let records = ModelRecords {
        terms: Some(on.names(F::TERMS)),
        ..ModelRecords::of_config(lobes_config(F::TERMS, on))
    };
    let choice = ModelChoice {
        effects_choice: EffectsSource::Explicit,
        reasons: vec![format!(
            "{} model, terms {} (--terms){}",
            F::TITLE,
            on.names(F::TERMS).join("+"),
            F::SCREENING.map_or(String::new(), |s| format!("; the multi-start screens {s}"))
        )],
    };
    let options = |sub: usize, explicit: bool, floored: Floored| {
        options_record(opts, &choice, &set, sub, explicit, floored)
    };
    let why = |p: TableParam<F>, _: &TableParams<f64>, partners: &[String]| {
        why_undetermined(p, data, partners)
    };
    fit_with(
        FitRun {
            input: i,
            forward: &forward,
            screening: screening.as_ref(),
            base: set.base.clone(),
            free: set.free.clone(),
            options: &options,
            records,
            all: <Table<F> as Family>::parameters(nc),
            why: &why,
            params_file: |p| FamilyParams::Table(TableParamFile::from_params(table::<F>(), p)),
        },
        warnings,
    )
}
