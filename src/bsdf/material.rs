//! Material types as the scene format names them (`type = "ggx"` in a `[[material]]`), each
//! registered in [`super::MATERIALS`] beside its lobe: a name and a parser that turns the
//! material's fields into a [`Bsdf`]. Fields are validated where they are read, and every
//! error names the file and the field (`material[2].roughness`).

use super::Bsdf;
use crate::error::Result;
pub use crate::scene::params::Params;
use std::path::Path;

/// A kind of material: its name in scene files and how its fields become lobes.
pub struct MaterialType {
    pub name: &'static str,
    pub describe: &'static str,
    /// The fields it reads, for error messages.
    pub fields: &'static [&'static str],
    /// Builds the material; fields it does not read are reported by the caller.
    pub parse: fn(&mut Params) -> Result<Bsdf>,
    /// The χ² cases of its sampling, for the χ² suite and `dibench warp`.
    pub chi2_cases: fn() -> Vec<crate::chi2::WarpEntry>,
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
    let mut params = Params::new(path, "material", index, table);
    let name = match kind {
        Some(k) => k,
        None if params.has("specular") || params.has("exponent") => "phong",
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
    let hint = if kind.is_none() {
        "; a `type` field selects another kind"
    } else {
        ""
    };
    params.reject_leftover(&format!("a `{}` material", t.name), t.fields, hint)?;
    Ok((t, bsdf))
}
