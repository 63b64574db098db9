//! Which share of a manifest one process runs: `--shard K/N` (0-based K) or `--shard auto`,
//! read from the variables a scheduler sets (Slurm job arrays, Kubernetes Indexed Jobs).

use crate::error::{Error, Result};

/// One deterministic share of the items: item `i` (manifest order, 0-based) belongs to shard
/// `i mod count`, so shards differ by at most one item and adding shards never reorders items.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// The whole manifest in one process.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Whether item `i` (0-based, manifest order) is this shard's.
    pub fn owns(&self, item: usize) -> bool {
        item % self.count == self.index
    }

    /// `K/N` with `0 ≤ K < N`, or `auto` (see [`Shard::from_env`]).
    pub fn parse(text: &str) -> Result<Shard> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("auto") {
            return Shard::from_env(|k| std::env::var(k).ok());
        }
        let bad = || {
            Error::Other(format!(
                "--shard `{text}`: write K/N with 0 ≤ K < N (e.g. 0/4 … 3/4), or `auto` under Slurm or a Kubernetes Indexed Job"
            ))
        };
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        Shard::new(index, count).map_err(|e| Error::Other(format!("--shard `{text}`: {e}")))
    }

    fn new(index: usize, count: usize) -> std::result::Result<Shard, String> {
        if count == 0 {
            return Err("N must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "K = {index} is not below N = {count} (K is 0-based: 0 … {})",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// The shard a scheduler assigned: Slurm's (`SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN`)
    /// / `SLURM_ARRAY_TASK_STEP` of `SLURM_ARRAY_TASK_COUNT`, or Kubernetes' `JOB_COMPLETION_INDEX` of
    /// `HAIRFIT_SHARD_COUNT` (Indexed Jobs do not expose their completion count; the shipped
    /// recipe sets it). `HAIRFIT_SHARD_COUNT` also overrides Slurm's count.
    pub fn from_env(var: impl Fn(&str) -> Option<String>) -> Result<Shard> {
        let num = |name: &str| -> Result<Option<usize>> {
            match var(name) {
                None => Ok(None),
                Some(v) if v.trim().is_empty() => Ok(None),
                Some(v) => v.trim().parse().map(Some).map_err(|_| {
                    Error::Other(format!(
                        "--shard auto: {name}=`{v}` is not a non-negative whole number"
                    ))
                }),
            }
        };
        let count_override = num("HAIRFIT_SHARD_COUNT")?;
        let (index, count, source) = if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let count = count_override.or(num("SLURM_ARRAY_TASK_COUNT")?).ok_or_else(|| {
                Error::Other("--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not (set HAIRFIT_SHARD_COUNT, or pass --shard K/N)".into())
            })?;
            let step = num("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let offset = id.checked_sub(min).ok_or_else(|| {
                Error::Other(format!(
                    "--shard auto: SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}"
                ))
            })?;
            // A stepped array (`--array=0-12:4`) numbers its tasks min, min+step, …
            if offset % step != 0 {
                return Err(Error::Other(format!(
                    "--shard auto: SLURM_ARRAY_TASK_ID={id} is not SLURM_ARRAY_TASK_MIN={min} plus a multiple of SLURM_ARRAY_TASK_STEP={step}; pass --shard K/N"
                )));
            }
            let index = offset / step;
            (index, count, "Slurm")
        } else if let Some(index) = num("JOB_COMPLETION_INDEX")? {
            let count = count_override.ok_or_else(|| {
                Error::Other("--shard auto: JOB_COMPLETION_INDEX is set but HAIRFIT_SHARD_COUNT is not: set it to the Job's completions (see scripts/k8s-indexed-job.yaml), or pass --shard K/N".into())
            })?;
            (index, count, "Kubernetes")
        } else {
            return Err(Error::Other(
                "--shard auto: no scheduler variables found (SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX); pass --shard K/N instead".into(),
            ));
        };
        Shard::new(index, count).map_err(|e| {
            Error::Other(format!(
                "--shard auto ({source}): shard {index} of {count}: {e}"
            ))
        })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn shards_partition_the_items() {
        for count in 1..6 {
            for item in 0..20 {
                let owners = (0..count)
                    .filter(|&index| Shard { index, count }.owns(item))
                    .count();
                assert_eq!(owners, 1, "item {item} with {count} shards");
            }
        }
    }

    #[test]
    fn parses_k_of_n_and_refuses_bad_ones() {
        assert_eq!(Shard::parse("2/4").unwrap(), Shard { index: 2, count: 4 });
        for bad in ["4/4", "1/0", "a/2", "3", "-1/2"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        assert!(Shard::parse("4/4")
            .unwrap_err()
            .to_string()
            .contains("0-based"));
    }

    #[test]
    fn reads_slurm_and_kubernetes_variables() {
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ]);
        assert_eq!(
            Shard::from_env(slurm).unwrap(),
            Shard { index: 4, count: 8 }
        );
        // `--array=0-4:4`: tasks 0 and 4 are shards 0 and 1 of 2.
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_STEP", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ]);
        assert_eq!(
            Shard::from_env(stepped).unwrap(),
            Shard { index: 1, count: 2 }
        );
        let k8s = env(&[("JOB_COMPLETION_INDEX", "2"), ("HAIRFIT_SHARD_COUNT", "3")]);
        assert_eq!(Shard::from_env(k8s).unwrap(), Shard { index: 2, count: 3 });
        let k8s_no_count = env(&[("JOB_COMPLETION_INDEX", "2")]);
        assert!(Shard::from_env(k8s_no_count)
            .unwrap_err()
            .to_string()
            .contains("HAIRFIT_SHARD_COUNT"));
        assert!(Shard::from_env(env(&[])).is_err());
    }
}
