//! The units a parameter is written in (files, reports) and held in (the model), and the
//! intervals its domain is: shared by every family.

/// The unit a parameter is written in (files, reports) and held in (the model).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// A pure number.
    Dimensionless,
    /// Degrees in files and reports, radians inside the model.
    Degrees,
    /// Absorption coefficient per unit fiber RADIUS (the fiber's radius is the length unit).
    PerFiberRadius,
}

impl Unit {
    /// Short label for report tables: `"deg"`, `"per fiber radius"`, or `""`.
    pub fn label(self) -> &'static str {
        match self {
            Unit::Dimensionless => "",
            Unit::Degrees => "deg",
            Unit::PerFiberRadius => "per fiber radius",
        }
    }

    /// Words for documentation.
    pub fn describe(self) -> &'static str {
        match self {
            Unit::Dimensionless => "dimensionless",
            Unit::Degrees => "degrees (radians inside the model)",
            Unit::PerFiberRadius => "per fiber radius",
        }
    }

    /// Factor from the model's value to the file's value (180/π for angles).
    pub fn file_factor(self) -> f64 {
        match self {
            Unit::Degrees => 180.0 / std::f64::consts::PI,
            _ => 1.0,
        }
    }

    /// A file value in model units.
    pub fn to_model(self, file_value: f64) -> f64 {
        match self {
            Unit::Degrees => file_value.to_radians(),
            _ => file_value,
        }
    }
}

/// An interval of allowed values, file units; an infinite end is open.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub lo_open: bool,
    pub hi: f64,
    pub hi_open: bool,
}

impl Interval {
    pub(crate) const fn open_above(lo: f64, lo_open: bool) -> Interval {
        Interval {
            lo,
            lo_open,
            hi: f64::INFINITY,
            hi_open: true,
        }
    }

    /// `(lo, hi]`.
    pub const fn open_closed(lo: f64, hi: f64) -> Interval {
        Interval {
            lo,
            lo_open: true,
            hi,
            hi_open: false,
        }
    }

    /// `[lo, hi)`.
    pub const fn closed_open(lo: f64, hi: f64) -> Interval {
        Interval {
            lo,
            lo_open: false,
            hi,
            hi_open: true,
        }
    }

    /// `(lo, hi)`.
    pub const fn open(lo: f64, hi: f64) -> Interval {
        Interval {
            lo,
            lo_open: true,
            hi,
            hi_open: true,
        }
    }

    /// True for a finite `x` inside the interval.
    pub fn contains(&self, x: f64) -> bool {
        x.is_finite()
            && (if self.lo_open {
                x > self.lo
            } else {
                x >= self.lo
            })
            && (if self.hi_open {
                x < self.hi
            } else {
                x <= self.hi
            })
    }

    /// `(1, 10]`, `[0, inf)`: five significant digits, enough to tell the ends apart.
    pub fn text(&self) -> String {
        let num = |x: f64| {
            if x.is_infinite() {
                if x > 0.0 { "inf" } else { "-inf" }.to_string()
            } else if x == x.round() {
                format!("{x}")
            } else {
                format!("{x:.5}")
                    .trim_end_matches('0')
                    .trim_end_matches('.')
                    .to_string()
            }
        };
        format!(
            "{}{}, {}{}",
            if self.lo_open { '(' } else { '[' },
            num(self.lo),
            num(self.hi),
            if self.hi_open { ')' } else { ']' }
        )
    }
}
