//! Material types as the scene format names them (`type = "ggx"` in a `[[material]]`), each
//! registered in [`super::MATERIALS`] beside its lobe: a name and a parser that turns the
//! material's fields into a [`Bsdf`]. Fields are validated where they are read, and every
//! error names the file and the field (`material[2].roughness`).

use super::Bsdf;
use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

/// A kind of material: its name in scene files and how its fields become lobes.
pub struct MaterialType {
    pub name: &'static str,
    pub describe: &'static str,
    /// The fields it reads, for error messages.
    pub fields: &'static [&'static str],
    /// Builds the material; fields it does not read are reported by the caller.
    pub parse: fn(&mut Params) -> Result<Bsdf>,
}

impl std::fmt::Debug for MaterialType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// The type named `name`.
pub fn by_name(name: &str) -> Option<&'static MaterialType> {
    super::MATERIALS.iter().copied().find(|t| t.name == name)
}

/// The material `[[material]]` number `index` of the scene file at `path`: its `type` (absent:
/// `phong` when it has a `specular` or `exponent` field, else `diffuse`, so files written
/// before types existed keep their meaning) and its other fields.
pub fn parse(
    path: &Path,
    index: usize,
    kind: Option<&str>,
    table: toml::Table,
) -> Result<(&'static MaterialType, Bsdf)> {
    let mut params = Params { path, index, table };
    let name = match kind {
        Some(k) => k,
        None if params.table.contains_key("specular") || params.table.contains_key("exponent") => {
            "phong"
        }
        None => "diffuse",
    };
    let Some(t) = by_name(name) else {
        let known: Vec<_> = super::MATERIALS.iter().map(|t| t.name).collect();
        return Err(params.error(
            "type",
            format!(
                "unknown material type `{name}` (types: {})",
                known.join(", ")
            ),
        ));
    };
    let bsdf = (t.parse)(&mut params)?;
    if let Some(key) = params.table.keys().next() {
        return Err(params.error(
            key,
            format!(
                "unknown field for a `{}` material (its fields: {}{})",
                t.name,
                t.fields.join(", "),
                if kind.is_none() {
                    "; a `type` field selects another kind"
                } else {
                    ""
                }
            ),
        ));
    }
    Ok((t, bsdf))
}

/// A material's fields, consumed as its type reads them.
pub struct Params<'a> {
    path: &'a Path,
    index: usize,
    table: toml::Table,
}

impl Params<'_> {
    /// `material[i].key` (`material[i]` for an empty key).
    pub fn field(&self, key: &str) -> String {
        if key.is_empty() {
            format!("material[{}]", self.index)
        } else {
            format!("material[{}].{key}", self.index)
        }
    }

    pub fn error(&self, key: &str, message: impl Into<String>) -> Error {
        Error::field(self.path, self.field(key), message)
    }

    pub fn has(&self, key: &str) -> bool {
        self.table.contains_key(key)
    }

    /// A finite number (integers accepted) that fits in f32.
    pub fn number(&mut self, key: &str) -> Result<Option<f32>> {
        let Some(v) = self.table.remove(key) else {
            return Ok(None);
        };
        self.to_f32(key, &v).map(Some)
    }

    fn to_f32(&self, key: &str, v: &toml::Value) -> Result<f32> {
        let x = match v {
            toml::Value::Float(x) => *x,
            toml::Value::Integer(i) => *i as f64,
            other => {
                return Err(self.error(key, format!("expected a number, got {}", other.type_str())));
            }
        };
        let f = x as f32;
        if !f.is_finite() {
            return Err(self.error(key, format!("must be finite (in f32), got {x}")));
        }
        Ok(f)
    }

    /// A number in [lo, hi].
    pub fn number_in(&mut self, key: &str, lo: f32, hi: f32) -> Result<Option<f32>> {
        match self.number(key)? {
            Some(x) if !(lo..=hi).contains(&x) => {
                Err(self.error(key, format!("must be in [{lo}, {hi}], got {x}")))
            }
            x => Ok(x),
        }
    }

    /// Exactly three finite numbers.
    pub fn rgb(&mut self, key: &str) -> Result<Option<Vec3>> {
        let Some(v) = self.table.remove(key) else {
            return Ok(None);
        };
        let toml::Value::Array(a) = &v else {
            return Err(self.error(key, format!("expected 3 numbers, got {}", v.type_str())));
        };
        if a.len() != 3 {
            return Err(self.error(key, format!("expected 3 numbers, got {}", a.len())));
        }
        let mut c = [0.0f32; 3];
        for (k, x) in a.iter().enumerate() {
            c[k] = self.to_f32(key, x)?;
        }
        Ok(Some(Vec3::from_array(c)))
    }

    /// Three numbers each in [lo, hi].
    pub fn rgb_in(&mut self, key: &str, lo: f32, hi: f32) -> Result<Option<Vec3>> {
        match self.rgb(key)? {
            Some(c) if c.min_element() < lo || c.max_element() > hi => Err(self.error(
                key,
                format!("each channel must be in [{lo}, {hi}], got {}", c),
            )),
            c => Ok(c),
        }
    }

    /// One number or a pair of numbers.
    pub fn number_or_pair(&mut self, key: &str) -> Result<Option<[f32; 2]>> {
        let Some(v) = self.table.remove(key) else {
            return Ok(None);
        };
        match &v {
            toml::Value::Array(a) if a.len() == 2 => {
                Ok(Some([self.to_f32(key, &a[0])?, self.to_f32(key, &a[1])?]))
            }
            toml::Value::Array(a) => Err(self.error(
                key,
                format!("expected a number or 2 numbers, got {}", a.len()),
            )),
            x => self.to_f32(key, x).map(|a| Some([a, a])),
        }
    }

    pub fn text(&mut self, key: &str) -> Result<Option<String>> {
        match self.table.remove(key) {
            None => Ok(None),
            Some(toml::Value::String(s)) => Ok(Some(s)),
            Some(v) => Err(self.error(key, format!("expected a string, got {}", v.type_str()))),
        }
    }
}
