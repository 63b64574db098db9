//! What the registry asks of the Chiang family ([`OwnTypes`], [`OwnFamily`]): its parameter
//! file as every command reads it, its model ready to evaluate, its demo truth and what result
//! files record of its configuration.

use serde::{Deserialize, Serialize};

use super::evaluator::{scattering_batch, scattering_by_lobe};
use super::{ChiangEffects, ChiangFamily, ChiangModel, ChiangParamFile, ChiangParams, WidthNodes};
use crate::error::Result;
use crate::families::table::Term;
use crate::families::SpecularLobe;
use crate::families::{FamilyModel, FamilyParams, ModelSetup, OwnTypes, SigmaAFile};
use crate::families::{FamilyRecord, ModelRecords, OwnFamily, OwnRecord, ScatteringModel};
use crate::geometry::{Angles, SigmaA};

impl OwnTypes for ChiangFamily {
    type File = ChiangParamFile;
    type Model = ChiangEvaluation;
    type Record = ChiangRecord;
    const SIGNATURE_KEY: &'static str = "beta_m";
    /// A Chiang file may carry `"model": "chiang"` (a fit writes it).
    const TAGGED: bool = true;
}

/// The Chiang model with its parameters and configuration (`--terms`, `--width-nodes`).
#[derive(Debug, Clone)]
pub struct ChiangEvaluation {
    pub params: ChiangParams<f64>,
    pub model: ChiangModel,
}

impl SigmaAFile for ChiangParamFile {
    fn sigma_a(&self) -> &SigmaA {
        &self.sigma_a
    }

    fn sigma_a_mut(&mut self) -> &mut SigmaA {
        &mut self.sigma_a
    }

    fn model(&self, setup: &ModelSetup) -> FamilyModel {
        FamilyModel::Chiang(ChiangEvaluation {
            params: self.to_params(),
            model: ChiangModel::of_setup(setup),
        })
    }
}

impl ScatteringModel for ChiangEvaluation {
    fn n_channels(&self) -> usize {
        self.params.sigma_a.len()
    }

    /// Batches share the width integral per exit direction.
    fn eval_batch(&self, angles: &[Angles], out: &mut [f64]) {
        scattering_batch(&self.params, &self.model, angles, out)
    }

    fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]) {
        scattering_by_lobe(&self.params, &self.model, angles, out)
    }

    /// d'Eon's M_p has standard deviation ≈ 0.726 β_m in θ_r, so half that in θ_h.
    fn specular_lobe(&self) -> Option<SpecularLobe> {
        Some(SpecularLobe {
            eta: self.params.eta,
            sigma_a: self.params.sigma_a.clone(),
            width: 0.363 * self.params.beta_m,
            shift: self.params.alpha,
        })
    }
}

impl FamilyParams {
    /// The Chiang file, if this is one.
    pub fn chiang(&self) -> Option<&ChiangParamFile> {
        match self {
            FamilyParams::Chiang(p) => Some(p),
            _ => None,
        }
    }
}

impl OwnFamily for ChiangFamily {
    fn demo_truth(&self) -> FamilyParams {
        ChiangParamFile::from_params(&super::demo::demo_truth()).into()
    }

    /// Chiang records the lobes its terms draw in `model`, and its terms and width rule in
    /// `chiang`.
    fn records(&self, setup: &ModelSetup) -> ModelRecords {
        let model = ChiangModel::of_setup(setup);
        ModelRecords {
            config: super::lobes_config(&model.effects),
            family_record: Some(FamilyRecord::Chiang(ChiangRecord {
                effects: model.effects,
                width_nodes: model.width(),
            })),
            terms: None,
        }
    }

    fn terms(&self) -> Option<&'static [Term]> {
        Some(&super::TERMS)
    }
}

/// fit.json → `chiang`: a Chiang fit's model configuration (its terms are not `terms`, which
/// table families write, for files written before them to read alike).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChiangRecord {
    /// The terms of `S` that were on.
    pub effects: ChiangEffects,
    /// The width rule: `"auto"` or the plain rule's Gauss–Legendre node count.
    pub width_nodes: WidthNodes,
}

impl ChiangRecord {
    /// `R+TT+TRT+residual`: the terms that were on.
    pub fn effects_text(&self) -> String {
        self.effects.terms().names(&super::TERMS).join("+")
    }
}

impl OwnRecord for ChiangRecord {
    fn describe(&self) -> Vec<String> {
        vec![
            format!("terms {}", self.effects_text()),
            format!("{} width nodes", self.width_nodes),
        ]
    }

    fn configure(&self, setup: &mut ModelSetup) -> Result<()> {
        setup.terms = Some(self.effects.terms());
        setup.width_nodes = self.width_nodes.check()?;
        Ok(())
    }
}

impl FamilyRecord {
    /// The Chiang record, if this is one.
    pub fn chiang(&self) -> Option<&ChiangRecord> {
        match self {
            FamilyRecord::Chiang(r) => Some(r),
            #[allow(unreachable_patterns)]
            _ => None,
        }
    }
}
