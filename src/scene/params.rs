//! The fields of one table of a scene file, read by the type that owns the table: a material
//! type (`bsdf::MATERIALS`) or a light type (`lights::LIGHT_TYPES`). Every error names the file
//! and the field (`material[2].roughness`, `spot_light[0].cone_angle_deg`).

use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

/// One table of a scene file (`[[material]]` number 2, `[[spot_light]]` number 0), its fields
/// consumed as the type that reads it asks for them: each reader validates what it takes, and
/// whatever is left over is an unknown field.
pub struct Params<'a> {
    path: &'a Path,
    section: &'a str,
    index: usize,
    table: toml::Table,
}

impl<'a> Params<'a> {
    /// Table number `index` of the array `section` of the scene file at `path`.
    pub fn new(path: &'a Path, section: &'a str, index: usize, table: toml::Table) -> Self {
        Params {
            path,
            section,
            index,
            table,
        }
    }

    /// `section[i].key` (`section[i]` for an empty key).
    pub fn field(&self, key: &str) -> String {
        if key.is_empty() {
            format!("{}[{}]", self.section, self.index)
        } else {
            format!("{}[{}].{key}", self.section, self.index)
        }
    }

    /// An error naming the first field no reader took, if any: `what` names the table's kind
    /// (`a \`ggx\` material`), `fields` those it reads, `hint` is appended to the message.
    pub fn reject_leftover(&self, what: &str, fields: &[&str], hint: &str) -> Result<()> {
        match self.table.keys().next() {
            None => Ok(()),
            Some(key) => Err(self.error(
                key,
                format!(
                    "unknown field for {what} (its fields: {}{hint})",
                    fields.join(", ")
                ),
            )),
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

    /// Three finite numbers, required.
    pub fn required_rgb(&mut self, key: &str) -> Result<Vec3> {
        self.rgb(key)?
            .ok_or_else(|| self.error(key, "missing: expected 3 numbers"))
    }

    /// A finite number, required.
    pub fn required_number(&mut self, key: &str) -> Result<f32> {
        self.number(key)?
            .ok_or_else(|| self.error(key, "missing: expected a number"))
    }

    /// A non-zero direction, required, normalized.
    pub fn direction(&mut self, key: &str) -> Result<Vec3> {
        let d = self.required_rgb(key)?.normalize_or_zero();
        if d == Vec3::ZERO {
            return Err(self.error(key, "must be a non-zero direction"));
        }
        Ok(d)
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
