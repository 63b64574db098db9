//! Stand-in for `data::{Dataset, write_csv}` until the `data` branch lands: the same fields and
//! the same file format (radians with a `# angles: rad` directive, shortest round-trip numbers),
//! deleted when the real ones are merged.

use std::path::Path;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};

/// Samples in struct-of-arrays form, angles in radians (mirror of `data::Dataset`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    pub channels: Vec<String>,
    pub theta_i: Vec<f64>,
    pub phi_i: Vec<f64>,
    pub theta_r: Vec<f64>,
    pub phi_r: Vec<f64>,
    pub radiance: Vec<f64>,
    pub sigma: Option<Vec<f64>>,
    pub weight: Option<Vec<f64>>,
    pub source_line: Vec<u64>,
    pub meta: serde_json::Map<String, serde_json::Value>,
}

impl Dataset {
    pub fn len(&self) -> usize {
        self.theta_i.len()
    }
    pub fn is_empty(&self) -> bool {
        self.theta_i.is_empty()
    }
    pub fn n_channels(&self) -> usize {
        self.channels.len()
    }
    pub fn angles(&self, i: usize) -> [f64; 4] {
        [self.theta_i[i], self.phi_i[i], self.theta_r[i], self.phi_r[i]]
    }
}

/// Write `dataset` in the loader's CSV format (mirror of `data::write_csv`).
pub fn write_csv(dataset: &Dataset, path: &Path) -> Result<()> {
    let nc = dataset.n_channels();
    let column = |prefix: &str, c: usize| {
        if nc == 1 && dataset.channels[0] == "radiance" {
            prefix.to_string()
        } else {
            format!("{prefix}_{}", dataset.channels[c])
        }
    };
    let mut header: Vec<String> = ["theta_i", "phi_i", "theta_r", "phi_r"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend((0..nc).map(|c| column("radiance", c)));
    if dataset.sigma.is_some() {
        header.extend((0..nc).map(|c| column("sigma", c)));
    }
    write_atomically(path, |w| {
        let io = |e| Error::io(path, e);
        writeln!(w, "# written by hairfit; angles in radians").map_err(io)?;
        writeln!(w, "# angles: rad").map_err(io)?;
        writeln!(w, "{}", header.join(",")).map_err(io)?;
        for i in 0..dataset.len() {
            let a = dataset.angles(i);
            let mut line = format!("{},{},{},{}", a[0], a[1], a[2], a[3]);
            let row = i * nc..(i + 1) * nc;
            for v in &dataset.radiance[row.clone()] {
                line.push_str(&format!(",{v}"));
            }
            if let Some(s) = &dataset.sigma {
                for v in &s[row.clone()] {
                    line.push_str(&format!(",{v}"));
                }
            }
            writeln!(w, "{line}").map_err(io)?;
        }
        Ok(())
    })
}
