//! What every model family shares and none owns: the fibre frame's angles ([`Angles`],
//! wrapping and half/difference angles), the units and domains of parameters ([`units`]), what
//! a data file's values are ([`Measurement`]), a σ_a of one or more channels ([`SigmaA`]) and
//! the one parameter-fact type every family's table is made of ([`fact::ParamFact`]).

pub mod angles;
pub mod fact;
pub mod measurement;
pub mod sigma_a;
pub mod units;

pub use angles::Angles;
pub use fact::{FamilyFacts, Fitted, ParamFact};
pub use measurement::Measurement;
pub use sigma_a::SigmaA;
pub use units::{Interval, Unit};
