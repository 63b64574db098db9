//! What the registry asks of the Marschner family ([`OwnTypes`]): its parameter file as every
//! command reads it and its model ready to evaluate.

use super::params::ParamFile;
use super::{
    scattering_batch, scattering_by_lobe, scattering_lanes, MarschnerFamily, ModelConfig, Params,
};
use crate::families::{FamilyModel, FamilyParams, ModelSetup, NoRecord, OwnTypes, SigmaAFile};
use crate::families::{ScatteringModel, SpecularLobe};
use crate::geometry::{Angles, SigmaA};

impl OwnTypes for MarschnerFamily {
    type File = ParamFile;
    type Model = MarschnerModel;
    type Record = NoRecord;
    const SIGNATURE_KEY: &'static str = "alpha_r_deg";
    /// A Marschner file is written without `"model"` (its keys came first).
    const TAGGED: bool = false;
}

/// The Marschner model with its parameters and configuration (`--mode`, `--lobes`, …).
#[derive(Debug, Clone)]
pub struct MarschnerModel {
    pub params: Params<f64>,
    pub config: ModelConfig,
}

impl SigmaAFile for ParamFile {
    fn sigma_a(&self) -> &SigmaA {
        &self.sigma_a
    }

    fn sigma_a_mut(&mut self) -> &mut SigmaA {
        &mut self.sigma_a
    }

    fn warnings(&self) -> Vec<String> {
        self.radians_in_degrees_keys()
    }

    fn model(&self, setup: &ModelSetup) -> FamilyModel {
        FamilyModel::Marschner(MarschnerModel {
            params: self.to_params(),
            config: setup.config,
        })
    }
}

impl ScatteringModel for MarschnerModel {
    fn n_channels(&self) -> usize {
        self.params.sigma_a.len()
    }

    /// One batch: the parameter-only factors are prepared once, not per row.
    fn eval_batch(&self, angles: &[Angles], out: &mut [f64]) {
        scattering_batch(&self.params, &self.config, angles, out)
    }

    /// The cubic mode four samples per vector ([`scattering_lanes`], ~1e-13 relative from the
    /// reference).
    fn eval_batch_fast(&self, angles: &[Angles], out: &mut [f64]) {
        scattering_lanes(&self.params, &self.config, angles, out)
    }

    fn by_lobe(&self, angles: &Angles, out: &mut [[f64; 3]]) {
        scattering_by_lobe(&self.params, &self.config, angles, out)
    }

    /// β_R is R's width in θ_h and α_R its shift.
    fn specular_lobe(&self) -> Option<SpecularLobe> {
        Some(SpecularLobe {
            eta: self.params.eta,
            sigma_a: self.params.sigma_a.clone(),
            width: self.params.beta_r,
            shift: self.params.alpha_r,
        })
    }
}

impl FamilyParams {
    /// The Marschner file, if this is one.
    pub fn marschner(&self) -> Option<&ParamFile> {
        match self {
            FamilyParams::Marschner(p) => Some(p),
            _ => None,
        }
    }
}
