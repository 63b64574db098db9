//! The parameter file of a table family: a JSON object with `"model": NAME` and the family's
//! keys from its table (angles in degrees), each a number or, for a per-channel parameter, one
//! number per colour channel. Unknown keys, a missing key without a default, channel counts
//! that disagree and values outside the domain are errors that say what to write.

use std::fmt;
use std::path::Path;

use serde::de::{DeserializeSeed, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{DynTable, TableParams};
use crate::error::{Error, Result};
use crate::geometry::Fitted;

/// A table family's parameter file, file units, each value as written (one number, or one
/// per channel).
#[derive(Clone)]
pub struct TableParamFile {
    pub table: &'static dyn DynTable,
    /// One entry per table line, in the table's order.
    pub values: Vec<Vec<f64>>,
}

impl fmt::Debug for TableParamFile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TableParamFile")
            .field("model", &self.table.name())
            .field("values", &self.values)
            .finish()
    }
}

impl PartialEq for TableParamFile {
    fn eq(&self, other: &Self) -> bool {
        self.table.name() == other.table.name() && self.values == other.values
    }
}

impl TableParamFile {
    /// Number of colour channels: the length of the per-channel arrays (1 when all are numbers).
    pub fn n_channels(&self) -> usize {
        self.values.iter().map(Vec::len).max().unwrap_or(1)
    }

    /// True when every value is written as one number (`hairfit eval` then writes one column).
    pub fn is_scalar(&self) -> bool {
        self.values.iter().all(|v| v.len() == 1)
    }

    /// The parameters in model units; a per-channel value written once applies to every channel.
    pub fn to_params(&self) -> TableParams<f64> {
        let nc = self.n_channels();
        let facts = self.table.parameters();
        let values = facts
            .iter()
            .zip(&self.values)
            .map(|(f, v)| {
                let n = if f.per_channel { nc } else { 1 };
                (0..n)
                    .map(|c| f.unit.to_model(v[if v.len() == 1 { 0 } else { c }]))
                    .collect()
            })
            .collect();
        TableParams {
            values,
            n_channels: nc,
        }
    }

    /// The file form of `params` (radians to degrees); one channel writes numbers.
    pub fn from_params(table: &'static dyn DynTable, params: &TableParams<f64>) -> TableParamFile {
        let values = table
            .parameters()
            .iter()
            .zip(&params.values)
            .map(|(f, v)| v.iter().map(|x| x * f.unit.file_factor()).collect())
            .collect();
        TableParamFile { table, values }
    }

    /// Check every value's domain.
    pub fn validate(&self) -> Result<()> {
        self.to_params().validate(self.table.parameters())
    }

    /// Parse JSON text as a parameter file of `table` (its `"model"`, when present, must name
    /// it); errors name `path`, line and column.
    pub fn from_json_str(
        text: &str,
        path: &Path,
        table: &'static dyn DynTable,
    ) -> Result<TableParamFile> {
        let hint = hint(table);
        let mut de = serde_json::Deserializer::from_str(text);
        let file = FileSeed(table)
            .deserialize(&mut de)
            .and_then(|f| de.end().map(|()| f))
            .map_err(|e| Error::json(path, &e, Some(&hint)))?;
        file.validate()
            .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
        Ok(file)
    }
}

/// What a parameter file of `table` holds, for error messages.
fn hint(table: &dyn DynTable) -> String {
    let keys: Vec<String> = table
        .parameters()
        .iter()
        .map(|f| {
            let list = if f.per_channel {
                " (number or one per channel)"
            } else {
                ""
            };
            match f.fitted {
                Fitted::Yes => format!("{}{list}", f.name),
                _ => format!(
                    "{}{list}, optional, {}",
                    f.name,
                    super::table_number(f.held())
                ),
            }
        })
        .collect();
    format!(
        "a {} parameter file is a JSON object with keys model (\"{}\"), {}",
        table.title(),
        table.name(),
        keys.join("; ")
    )
}

impl Serialize for TableParamFile {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.values.len() + 1))?;
        map.serialize_entry("model", self.table.name())?;
        for (f, v) in self.table.parameters().iter().zip(&self.values) {
            if v.len() == 1 {
                map.serialize_entry(f.name, &v[0])?;
            } else {
                map.serialize_entry(f.name, v)?;
            }
        }
        map.end()
    }
}

impl TableParamFile {
    /// Read a parameter file of `table` from parsed JSON (`"model"`, when present, must name it):
    /// how a file whose tag named its family is read once the registry has found the family.
    pub fn from_value(
        table: &'static dyn DynTable,
        value: &serde_json::Value,
    ) -> std::result::Result<TableParamFile, serde_json::Error> {
        FileSeed(table).deserialize(value)
    }
}

/// Reads a file of the family `--model` or the file's tag named (the tag may be left out).
struct FileSeed(&'static dyn DynTable);

/// A value as written: one number, or an array of them.
struct Written(Vec<f64>, bool);

impl<'de> Deserialize<'de> for Written {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Written;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, or an array of numbers (one per colour channel)")
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<Written, E> {
                Ok(Written(vec![v], false))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<Written, E> {
                Ok(Written(vec![v as f64], false))
            }
            fn visit_u64<E>(self, v: u64) -> std::result::Result<Written, E> {
                Ok(Written(vec![v as f64], false))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Written, A::Error> {
                let mut out = Vec::new();
                while let Some(v) = seq.next_element::<f64>()? {
                    out.push(v);
                }
                Ok(Written(out, true))
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> DeserializeSeed<'de> for FileSeed {
    type Value = TableParamFile;
    fn deserialize<D: Deserializer<'de>>(
        self,
        d: D,
    ) -> std::result::Result<TableParamFile, D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for FileSeed {
    type Value = TableParamFile;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a parameter file: a JSON object")
    }

    fn visit_map<A: MapAccess<'de>>(
        self,
        mut map: A,
    ) -> std::result::Result<Self::Value, A::Error> {
        use serde::de::Error as _;
        let mut tag: Option<String> = None;
        let mut entries: Vec<(String, Written)> = Vec::new();
        while let Some(key) = map.next_key::<String>()? {
            if key == "model" {
                tag = Some(map.next_value()?);
            } else if entries.iter().any(|(k, _)| *k == key) {
                return Err(A::Error::custom(format!("`{key}` is given twice")));
            } else {
                let value = map.next_value()?;
                entries.push((key, value));
            }
        }
        let table = self.0;
        if let Some(t) = tag.as_deref().filter(|t| *t != table.name()) {
            return Err(A::Error::custom(format!(
                "the file says \"model\": \"{t}\" but it is read as a {} file: pass --model {t} \
                     (or write \"model\": \"{}\")",
                table.name(),
                table.name()
            )));
        }
        resolve(table, entries).map_err(A::Error::custom)
    }
}

/// The entries of a file of `table`, checked against its keys and channel counts.
fn resolve(
    table: &'static dyn DynTable,
    mut entries: Vec<(String, Written)>,
) -> std::result::Result<TableParamFile, String> {
    let facts = table.parameters();
    let keys = || facts.iter().map(|f| f.name).collect::<Vec<_>>().join(", ");
    if let Some((key, _)) = entries
        .iter()
        .find(|(k, _)| !facts.iter().any(|f| f.name == k))
    {
        let closest = facts
            .iter()
            .map(|f| (strsim::jaro_winkler(key, f.name), f.name))
            .filter(|(score, _)| *score > 0.8)
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(String::new(), |(_, name)| {
                format!(" (did you mean `{name}`?)")
            });
        return Err(format!(
            "unknown key `{key}`{closest} for the {} model: its keys are model, {}",
            table.name(),
            keys()
        ));
    }
    let mut values = Vec::with_capacity(facts.len());
    let mut channels: Option<(usize, &str)> = None;
    for f in facts {
        let Some(at) = entries.iter().position(|(k, _)| k == f.name) else {
            if f.fitted == Fitted::Yes {
                return Err(format!(
                    "missing `{}` ({}); a {} file has keys model, {}",
                    f.name,
                    f.meaning,
                    table.name(),
                    keys()
                ));
            }
            values.push(vec![f.held()]);
            continue;
        };
        let Written(v, is_array) = entries.swap_remove(at).1;
        if is_array && !f.per_channel {
            return Err(format!(
                "`{}` takes one number: it is not per colour channel",
                f.name
            ));
        }
        if is_array {
            if v.is_empty() {
                return Err(format!(
                    "`{}` is an empty array: give one value per colour channel",
                    f.name
                ));
            }
            if let Some((n, other)) = channels.filter(|(n, _)| *n != v.len()) {
                return Err(format!(
                    "`{}` has {} values but `{other}` has {n}: give every per-channel parameter \
                     one value per channel (or one number for all)",
                    f.name,
                    v.len()
                ));
            }
            channels = Some((v.len(), f.name));
        }
        values.push(v);
    }
    Ok(TableParamFile { table, values })
}

impl crate::families::FamilyFile for TableParamFile {
    fn n_channels(&self) -> usize {
        TableParamFile::n_channels(self)
    }

    fn is_scalar(&self) -> bool {
        TableParamFile::is_scalar(self)
    }

    fn replicate_channels(
        &mut self,
        n: usize,
    ) -> std::result::Result<Option<String>, (&'static str, usize)> {
        let mut replicated = Vec::new();
        for (f, v) in self.table.parameters().iter().zip(&mut self.values) {
            if !f.per_channel || v.len() == n {
                continue;
            }
            if v.len() != 1 {
                return Err((f.name, v.len()));
            }
            *v = vec![v[0]; n];
            replicated.push(format!("{} = {}", f.name, v[0]));
        }
        Ok((!replicated.is_empty()).then(|| replicated.join(", ")))
    }

    fn check(&self) -> Result<()> {
        self.validate()
    }

    fn model(&self, setup: &crate::families::ModelSetup) -> crate::families::FamilyModel {
        crate::families::FamilyModel::Table(super::TableModel {
            table: self.table,
            params: self.to_params(),
            terms: setup.table_terms(self.table),
        })
    }
}
