//! The Marschner section of the accuracy-vs-time ledger (`hairfit cost`): root mode × effect set
//! ([`model`]), the Jacobian by AD against central differences ([`jacobian`]) and the fit's
//! knobs ([`fits`]).

mod fits;
mod jacobian;
mod model;

pub use model::effect_ladder;

use crate::cost::{CostRow, FamilyCost};
use crate::error::Result;
use crate::families::marschner::MarschnerFamily;

impl FamilyCost for MarschnerFamily {
    fn rows(&self, quick: bool) -> Result<Vec<CostRow>> {
        let mut rows = model::model_rows(quick);
        let data = fits::synthetic_data();
        rows.extend(jacobian::jacobian_rows(&data, quick)?);
        rows.extend(fits::fit_rows(&data, quick)?);
        Ok(rows)
    }

    fn metrics(&self) -> &'static [(&'static str, &'static str)] {
        &[
            ("model", "relative error of S per channel against exact roots with every effect, denominator floored at 1e-3 x the median reference S; time per evaluation (one direction pair, all channels, one thread)"),
            ("jacobian", "per parameter column: ||J_fd - J_ad|| / ||J_ad|| (max and RMS over columns); time per full Jacobian of the synthetic data"),
            ("fit", "|estimate - truth| / width of the parameter's typical range (docs/model.md), over the free shape parameters (max and RMS); wall time of the whole fit"),
        ]
    }
}
