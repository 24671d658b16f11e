//! The TOML scene format, as serde structs. Unknown keys are errors (`deny_unknown_fields`):
//! a misspelt key silently ignored would change the experiment without telling anyone.
//! Units and conventions: `docs/conventions.md`.

use serde::Deserialize;

/// Exactly three numbers: a point, a direction or an RGB triple. serde's `[f32; 3]` would
/// silently drop a fourth component, so the list is read whole and its length checked (two
/// components and four are both errors, with the line).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(try_from = "Vec<f32>")]
pub struct Triple(pub [f32; 3]);

impl TryFrom<Vec<f32>> for Triple {
    type Error = String;
    fn try_from(v: Vec<f32>) -> Result<Self, String> {
        <[f32; 3]>::try_from(v)
            .map(Triple)
            .map_err(|v| format!("expected 3 numbers, got {}", v.len()))
    }
}

/// The whole file. Every top-level key is either one of these fields or a light type's table
/// array (`[[point_light]]`, …: `lights::LIGHT_TYPES`), which lands in `lights` for its type
/// to parse; `Scene::parse` refuses any other key (serde's `deny_unknown_fields` cannot be
/// combined with the catch-all).
#[derive(Debug, Deserialize)]
pub struct SceneFile {
    pub camera: CameraDesc,
    pub image: ImageDesc,
    #[serde(default, rename = "material")]
    pub materials: Vec<MaterialDesc>,
    #[serde(default, rename = "mesh")]
    pub meshes: Vec<MeshDesc>,
    #[serde(default, rename = "quad")]
    pub quads: Vec<QuadDesc>,
    #[serde(default, rename = "sphere")]
    pub spheres: Vec<SphereDesc>,
    /// Present: the scene also has the ambient-occlusion integrand (`ao-*` strategies).
    pub ambient_occlusion: Option<AmbientOcclusionDesc>,
    /// Radiance arriving from infinitely far away (a lat/long EXR or a constant).
    pub environment: Option<EnvironmentDesc>,
    /// Every other top-level key: the light types' table arrays.
    #[serde(flatten)]
    pub lights: toml::Table,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub eye: Triple,
    pub look_at: Triple,
    #[serde(default = "default_up")]
    pub up: Triple,
    /// Full vertical field of view in degrees.
    pub fov_y_deg: f32,
}

fn default_up() -> Triple {
    Triple([0.0, 1.0, 0.0])
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageDesc {
    pub width: u32,
    pub height: u32,
}

/// A material: its name, its type, and the type's own fields, which the type parses and
/// validates (`bsdf::MATERIALS`; unknown fields are errors there). Without a `type`, a material
/// with `specular` or `exponent` is `phong` (albedo kd + normalized Phong ks, exponent n) and
/// any other `diffuse` (albedo kd), as before types existed.
#[derive(Debug, Deserialize)]
pub struct MaterialDesc {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: Option<String>,
    #[serde(flatten)]
    pub fields: toml::Table,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// OBJ file, relative to the scene file.
    pub file: String,
    pub material: String,
    #[serde(default)]
    pub transform: TransformDesc,
    /// Emitted radiance [W/(m² sr)] on the front faces (counter-clockwise winding) makes
    /// this mesh a light.
    pub emission: Option<Triple>,
}

/// Applied as scale, then rotation about +Y, then translation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    #[serde(default = "one")]
    pub scale: f32,
    #[serde(default)]
    pub rotate_y_deg: f32,
    #[serde(default)]
    pub translate: Triple,
}

fn one() -> f32 {
    1.0
}

impl Default for TransformDesc {
    fn default() -> Self {
        TransformDesc {
            scale: 1.0,
            rotate_y_deg: 0.0,
            translate: Triple::default(),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadDesc {
    /// The parallelogram corner + s·edge_u + t·edge_v, s, t in [0, 1]. Its front side (the side
    /// that emits) is the side of edge_u × edge_v.
    pub corner: Triple,
    pub edge_u: Triple,
    pub edge_v: Triple,
    pub material: String,
    pub emission: Option<Triple>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    pub center: Triple,
    pub radius: f32,
    pub material: String,
    /// Emitted radiance, on both faces: outward, and inward for points inside the sphere.
    pub emission: Option<Triple>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmbientOcclusionDesc {
    /// Occluders farther than this do not count.
    pub distance: f32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDesc {
    /// Lat/long RGB EXR, relative to the scene file (orientation: docs/conventions.md).
    pub file: Option<String>,
    /// A constant radiance [W/(m² sr)] instead of a file.
    pub constant: Option<Triple>,
    /// Multiplies the radiance (default 1).
    #[serde(default = "one")]
    pub scale: f32,
    /// Rotation about +Y, counter-clockwise seen from +Y (as mesh transforms).
    #[serde(default)]
    pub rotate_y_deg: f32,
}
