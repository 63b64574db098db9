//! `sigma_a` as parameter files write it, one number or one per colour channel: every family
//! whose fibre absorbs (Marschner, Chiang, the tracer's fibre) reads it the same way.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// `sigma_a` as written: one number (one channel) or an array (one per channel).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum SigmaA {
    Scalar(f64),
    PerChannel(Vec<f64>),
}

/// Read by hand: serde's untagged enum says only "did not match any variant of untagged enum
/// SigmaA", where the user needs to hear what `sigma_a` must be.
impl<'de> Deserialize<'de> for SigmaA {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = SigmaA;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "sigma_a as a number or an array of numbers, one per colour channel \
                     (e.g. 0.4 or [0.2, 0.4, 0.8])",
                )
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<SigmaA, E> {
                Ok(SigmaA::Scalar(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<SigmaA, E> {
                Ok(SigmaA::Scalar(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<SigmaA, E> {
                Ok(SigmaA::Scalar(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<SigmaA, A::Error> {
                let mut values = Vec::new();
                while let Some(v) = seq.next_element::<Number>()? {
                    values.push(v.0);
                }
                Ok(SigmaA::PerChannel(values))
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// One channel's σ_a inside the array, with the same words when it is not a number.
struct Number(f64);

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Number;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number for each channel of sigma_a (e.g. [0.2, 0.4, 0.8])")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Number, E> {
                Ok(Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Number, E> {
                Ok(Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Number, E> {
                Ok(Number(v as f64))
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl SigmaA {
    /// Number of colour channels it gives.
    pub fn n_channels(&self) -> usize {
        match self {
            SigmaA::Scalar(_) => 1,
            SigmaA::PerChannel(v) => v.len(),
        }
    }

    /// Given once, written as `n` values (`hairfit synth --channels n`): `Some(note)` when it
    /// was replicated; `Err(("sigma_a", count))` when it gives another number of channels.
    pub fn replicate(
        &mut self,
        n: usize,
    ) -> std::result::Result<Option<String>, (&'static str, usize)> {
        match self.clone() {
            SigmaA::Scalar(s) if n > 1 => {
                *self = SigmaA::PerChannel(vec![s; n]);
                Ok(Some(format!("sigma_a = {s}")))
            }
            SigmaA::PerChannel(v) if v.len() != n => Err(("sigma_a", v.len())),
            _ => Ok(None),
        }
    }

    /// True when it is one number for every channel.
    pub fn is_scalar(&self) -> bool {
        matches!(self, SigmaA::Scalar(_))
    }

    /// An empty array gives no channel: an error naming `sigma_a`.
    pub fn require_channels(&self) -> Result<()> {
        if self.n_channels() == 0 {
            return Err(Error::Parameter {
                name: "sigma_a".into(),
                value: f64::NAN,
                message: "the array is empty: give one value per colour channel".into(),
            });
        }
        Ok(())
    }
}

/// A parameter set's absorption coefficients give at least one colour channel (one σ_a).
pub fn require_channels(sigma_a: &[f64]) -> Result<()> {
    if sigma_a.is_empty() {
        return Err(Error::Parameter {
            name: "sigma_a".into(),
            value: f64::NAN,
            message: "give at least one colour channel".into(),
        });
    }
    Ok(())
}
