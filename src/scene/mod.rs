//! The scene as plain data, loaded and validated from a TOML file (format: `scene::file`).
//! Nothing here is derived for rendering; `prepare` builds only what a scene needs.

pub mod file;
mod obj;
pub mod params;

use crate::bounded;
use crate::env::map::LatLongImage;
use crate::error::{Error, Result};
use crate::lights::{LIGHT_TYPES, LightSpec, LightType, light_type};
use file::SceneFile;
use glam::{Quat, Vec3};
use params::Params;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The largest image side a scene may ask for (whether it fits in memory is checked apart).
pub const MAX_IMAGE_SIDE: u32 = 16384;

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub path: PathBuf,
    /// SHA-256 over the scene file and every file it references: a reference image is reused
    /// only for the exact same content.
    pub content_hash: String,
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
    pub materials: Vec<Material>,
    pub meshes: Vec<Mesh>,
    pub quads: Vec<Quad>,
    pub spheres: Vec<SphereShape>,
    /// The lights that are not a shape's surface or the environment, in the order of
    /// `lights::LIGHT_TYPES`, each type's in file order.
    pub lights: Vec<SceneLight>,
    /// Occlusion distance of the ambient-occlusion integrand, when the scene asks for it.
    pub ao_distance: Option<f32>,
    pub environment: Option<EnvironmentSpec>,
    /// Total power of the lights [W], luminance-weighted (as light selection weighs them).
    pub light_power: f64,
}

/// Environment light as given: the source radiance and how it is placed.
#[derive(Clone, Debug)]
pub struct EnvironmentSpec {
    pub source: EnvSource,
    pub scale: f32,
    /// Rotation about +Y applied to the map (counter-clockwise seen from +Y).
    pub rotation: Quat,
}

#[derive(Clone, Debug)]
pub enum EnvSource {
    Image(Arc<LatLongImage>),
    Constant(Vec3),
}

impl EnvironmentSpec {
    /// Radiance arriving from world direction `w` (unit, pointing away from the scene), from
    /// the source's own piecewise-constant reconstruction.
    pub fn radiance(&self, w: Vec3) -> Vec3 {
        let l = match &self.source {
            EnvSource::Image(img) => img.radiance(self.rotation.inverse() * w),
            EnvSource::Constant(c) => *c,
        };
        self.scale * l
    }
}

/// Pinhole camera, right-handed: `forward` = normalize(look_at - eye), `right` = forward × up.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub eye: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// tan(fov_y / 2): the vertical field of view is the one stated in the file.
    pub tan_half_fov_y: f32,
}

/// A named material: its type (`diffuse`, `phong`, `ggx`, `principled`) and its lobes, as the
/// type built them from the file's fields (see `bsdf::MATERIALS`).
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub kind: &'static str,
    pub bsdf: crate::bsdf::Bsdf,
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub file: PathBuf,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub material: u32,
    pub emission: Option<Vec3>,
}

#[derive(Clone, Copy, Debug)]
pub struct Quad {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    pub material: u32,
    pub emission: Option<Vec3>,
}

#[derive(Clone, Copy, Debug)]
pub struct SphereShape {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
    pub emission: Option<Vec3>,
}

/// One light of a type in `lights::LIGHT_TYPES`, as parsed (placed in the scene by
/// `prepare`).
#[derive(Clone, Debug)]
pub struct SceneLight {
    pub kind: &'static LightType,
    /// `spot_light[0]`: the table it came from, for messages.
    pub field: String,
    pub spec: Arc<dyn LightSpec>,
}

/// The top-level keys `SceneFile` reads itself (the rest must be light types).
const SCENE_KEYS: &[&str] = &[
    "camera",
    "image",
    "material",
    "mesh",
    "quad",
    "sphere",
    "ambient_occlusion",
    "environment",
];

/// Each remaining top-level key as a light type's table array, parsed by its type in
/// `LIGHT_TYPES` order; any other key is an error naming it.
fn parse_lights(path: &Path, mut tables: toml::Table) -> Result<Vec<SceneLight>> {
    if let Some(key) = tables.keys().find(|k| light_type(k).is_none()) {
        let types: Vec<_> = LIGHT_TYPES.iter().map(|t| t.name).collect();
        return Err(Error::field(
            path,
            key.as_str(),
            format!(
                "unknown key `{key}` (the scene's keys: {}; light types: {})",
                SCENE_KEYS.join(", "),
                types.join(", ")
            ),
        ));
    }
    let mut lights = Vec::new();
    for kind in LIGHT_TYPES.iter().copied() {
        let Some(value) = tables.remove(kind.name) else {
            continue;
        };
        let toml::Value::Array(entries) = value else {
            return Err(Error::field(
                path,
                kind.name,
                format!(
                    "expected an array of tables `[[{}]]`, got {}",
                    kind.name,
                    value.type_str()
                ),
            ));
        };
        for (i, entry) in entries.into_iter().enumerate() {
            let toml::Value::Table(table) = entry else {
                return Err(Error::field(
                    path,
                    format!("{}[{i}]", kind.name),
                    format!("expected a table, got {}", entry.type_str()),
                ));
            };
            let mut params = Params::new(path, kind.name, i, table);
            let spec = (kind.parse)(&mut params)?;
            params.reject_leftover(&format!("a `{}`", kind.name), kind.fields, "")?;
            lights.push(SceneLight {
                kind,
                field: params.field(""),
                spec,
            });
        }
    }
    Ok(lights)
}

impl Scene {
    pub fn has_emitters(&self) -> bool {
        self.meshes.iter().any(|m| m.emission.is_some())
            || self.quads.iter().any(|q| q.emission.is_some())
            || self.spheres.iter().any(|s| s.emission.is_some())
    }

    pub fn has_environment(&self) -> bool {
        self.environment.is_some()
    }

    pub fn has_delta_lights(&self) -> bool {
        // The radius does not change whether a light is a delta light.
        self.lights.iter().any(|l| l.spec.place(1.0).is_delta())
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Finds a scene by path, or by name under `scenes/` (in the working directory, then in the
    /// source tree this binary was built from).
    pub fn resolve(name_or_path: &str) -> Result<PathBuf> {
        let direct = PathBuf::from(name_or_path);
        match std::fs::metadata(&direct) {
            Ok(m) if m.is_file() => return Ok(direct),
            // A FIFO or a device by that name is what the user meant, and cannot be read: say
            // so rather than look for a scene of that name (a directory may share a name).
            Ok(m) if !m.is_dir() => {
                bounded::open_regular(&direct)?;
            }
            _ => {}
        }
        let file = if name_or_path.ends_with(".toml") {
            name_or_path.to_string()
        } else {
            format!("{name_or_path}.toml")
        };
        for root in [
            PathBuf::from("scenes"),
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"),
        ] {
            let candidate = root.join(&file);
            if candidate.is_file() {
                return Ok(candidate);
            }
        }
        let known = Self::builtin_names().join(", ");
        Err(Error::Usage(format!(
            "no scene file `{name_or_path}` and no scene of that name in scenes/ (known: {known})"
        )))
    }

    /// The names of the scenes shipped in `scenes/`.
    pub fn builtin_names() -> Vec<String> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| {
                let p = e.path();
                if p.extension()? == "toml" {
                    Some(p.file_stem()?.to_string_lossy().into_owned())
                } else {
                    None
                }
            })
            .collect();
        names.sort();
        names
    }

    pub fn load(path: &Path) -> Result<Scene> {
        // The TOML document tree takes a few times the text.
        let bytes = bounded::read_file(path, 16)?;
        Self::parse(utf8(&bytes, path)?, path)
    }

    /// Parses scene text as if read from `path` (which names errors and anchors mesh files).
    pub fn parse(text: &str, path: &Path) -> Result<Scene> {
        let desc: SceneFile = toml::from_str(text).map_err(|e| Error::Parse {
            path: path.to_path_buf(),
            message: shorten_lines(&e.to_string()),
        })?;
        let mut hasher = Sha256::new();
        hasher.update(text.as_bytes());
        let base = path.parent().unwrap_or(Path::new("."));
        let v = Validator { path };

        let camera = v.camera(&desc.camera)?;
        let side = 1..=MAX_IMAGE_SIDE;
        if !side.contains(&desc.image.width) || !side.contains(&desc.image.height) {
            return Err(Error::field(
                path,
                "image",
                format!(
                    "width and height must be in 1..={MAX_IMAGE_SIDE}, got {}×{}",
                    desc.image.width, desc.image.height
                ),
            ));
        }

        let mut materials = Vec::new();
        for (i, m) in desc.materials.iter().enumerate() {
            let (kind, bsdf) =
                crate::bsdf::material::parse(path, i, m.kind.as_deref(), m.fields.clone())?;
            if materials.iter().any(|x: &Material| x.name == m.name) {
                return Err(Error::field(
                    path,
                    format!("material[{i}].name"),
                    format!("duplicate material `{}`", m.name),
                ));
            }
            materials.push(Material {
                name: m.name.clone(),
                kind: kind.name,
                bsdf,
            });
        }
        let material = |field: String, name: &str| -> Result<u32> {
            materials
                .iter()
                .position(|m| m.name == name)
                .map(|i| i as u32)
                .ok_or_else(|| {
                    let known: Vec<_> = materials.iter().map(|m| m.name.as_str()).collect();
                    Error::field(
                        path,
                        field,
                        format!("unknown material `{name}` (defined: {})", known.join(", ")),
                    )
                })
        };

        let mut meshes = Vec::new();
        for (i, m) in desc.meshes.iter().enumerate() {
            let file = base.join(&m.file);
            // Name the scene's field too: the user may not know which scene line the OBJ came from.
            let in_field = |e: Error| Error::field(path, format!("mesh[{i}].file"), e.to_string());
            // Read once, so that what is hashed is what is parsed; OBJ text becomes positions,
            // indices and then a BVH, some 40 bytes per byte of text.
            let bytes = bounded::read_file(&file, 40)
                .map_err(|e| in_field(Error::Usage(format!("cannot read {e}"))))?;
            hasher.update(&bytes);
            let (mut positions, triangles) = obj::parse(&bytes, &file).map_err(in_field)?;
            let t = &m.transform;
            if !(t.scale.is_finite() && t.scale > 0.0) {
                return Err(Error::field(
                    path,
                    format!("mesh[{i}].transform.scale"),
                    "must be finite and positive",
                ));
            }
            let translate = v.vec3(&format!("mesh[{i}].transform.translate"), t.translate)?;
            let rot = Quat::from_rotation_y(
                v.finite(&format!("mesh[{i}].transform.rotate_y_deg"), t.rotate_y_deg)?
                    .to_radians(),
            );
            for p in &mut positions {
                *p = rot * (*p * t.scale) + translate;
            }
            meshes.push(Mesh {
                file,
                positions,
                triangles,
                material: material(format!("mesh[{i}].material"), &m.material)?,
                emission: v.emission(&format!("mesh[{i}].emission"), m.emission)?,
            });
        }

        let mut quads = Vec::new();
        for (i, q) in desc.quads.iter().enumerate() {
            let quad = Quad {
                corner: v.vec3(&format!("quad[{i}].corner"), q.corner)?,
                edge_u: v.vec3(&format!("quad[{i}].edge_u"), q.edge_u)?,
                edge_v: v.vec3(&format!("quad[{i}].edge_v"), q.edge_v)?,
                material: material(format!("quad[{i}].material"), &q.material)?,
                emission: v.emission(&format!("quad[{i}].emission"), q.emission)?,
            };
            if quad.edge_u.cross(quad.edge_v).length_squared() == 0.0 {
                return Err(Error::field(
                    path,
                    format!("quad[{i}]"),
                    "edge_u and edge_v are parallel or zero: the quad has no area",
                ));
            }
            quads.push(quad);
        }

        let mut spheres = Vec::new();
        for (i, s) in desc.spheres.iter().enumerate() {
            let radius = v.finite(&format!("sphere[{i}].radius"), s.radius)?;
            if radius <= 0.0 {
                return Err(Error::field(
                    path,
                    format!("sphere[{i}].radius"),
                    "must be positive",
                ));
            }
            spheres.push(SphereShape {
                center: v.vec3(&format!("sphere[{i}].center"), s.center)?,
                radius,
                material: material(format!("sphere[{i}].material"), &s.material)?,
                emission: v.emission(&format!("sphere[{i}].emission"), s.emission)?,
            });
        }

        let lights = parse_lights(path, desc.lights)?;
        let ao_distance = match &desc.ambient_occlusion {
            None => None,
            Some(ao) => {
                let d = v.finite("ambient_occlusion.distance", ao.distance)?;
                if d <= 0.0 {
                    return Err(Error::field(
                        path,
                        "ambient_occlusion.distance",
                        "must be positive",
                    ));
                }
                Some(d)
            }
        };

        let environment = match &desc.environment {
            None => None,
            Some(e) => Some(v.environment(e, base, &mut hasher)?),
        };

        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        // The name is a directory of the results: `..toml` would put them beside all others.
        if name.is_empty() || name == "." || name == ".." {
            return Err(Error::Parse {
                path: path.to_path_buf(),
                message: format!(
                    "the file name gives the scene the name `{name}`, which cannot name its \
                     results directory: rename the file"
                ),
            });
        }
        let mut scene = Scene {
            name,
            path: path.to_path_buf(),
            content_hash: format!("{:x}", hasher.finalize()),
            camera,
            width: desc.image.width,
            height: desc.image.height,
            materials,
            meshes,
            quads,
            spheres,
            lights,
            ao_distance,
            environment,
            light_power: 0.0,
        };
        for (field, power) in scene.light_powers() {
            // The selection weights are f32 (`Light::power`); half the range leaves room for
            // rounding differences between this f64 sum and theirs.
            if power.is_nan() || power > f32::MAX as f64 / 2.0 {
                return Err(Error::field(
                    path,
                    field,
                    format!(
                        "the light's power {power:.3e} W overflows the f32 range dibench renders \
                         in (at most {:.1e} W): scale its emission down",
                        f32::MAX as f64 / 2.0
                    ),
                ));
            }
            scene.light_power += power;
        }
        if !scene.has_emitters() && !scene.has_delta_lights() && !scene.has_environment() {
            return Err(Error::field(
                path,
                "light",
                "the scene has no light: add an `emission` to a shape, a [[point_light]] or an [environment]",
            ));
        }
        Ok(scene)
    }
}

impl Scene {
    /// Each light's power [W] in f64, luminance-weighted, by the formulas of `Light::power`:
    /// (scene field, power).
    pub fn light_powers(&self) -> Vec<(String, f64)> {
        use std::f64::consts::PI;
        let lum = |c: Vec3| 0.2126 * c.x as f64 + 0.7152 * c.y as f64 + 0.0722 * c.z as f64;
        let mut out = Vec::new();
        for (i, m) in self.meshes.iter().enumerate() {
            if let Some(l) = m.emission {
                let area: f64 = m
                    .triangles
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|k| m.positions[k as usize].as_dvec3());
                        0.5 * (b - a).cross(c - a).length()
                    })
                    .sum();
                out.push((format!("mesh[{i}].emission"), PI * area * lum(l)));
            }
        }
        for (i, q) in self.quads.iter().enumerate() {
            if let Some(l) = q.emission {
                let area = q.edge_u.as_dvec3().cross(q.edge_v.as_dvec3()).length();
                out.push((format!("quad[{i}].emission"), PI * area * lum(l)));
            }
        }
        for (i, s) in self.spheres.iter().enumerate() {
            if let Some(l) = s.emission {
                let r = s.radius as f64;
                out.push((
                    format!("sphere[{i}].emission"),
                    4.0 * PI * PI * r * r * lum(l),
                ));
            }
        }
        let r = self.bounding_radius();
        for l in &self.lights {
            out.push((l.field.clone(), l.spec.place(r as f32).power() as f64));
        }
        if let Some(e) = &self.environment {
            // ∫ L dω over the source: texel rows of the lat/long map span θ0..θ1 of 2π/W each.
            let integral = match &e.source {
                EnvSource::Constant(c) => 4.0 * PI * lum(*c),
                EnvSource::Image(img) => {
                    let (w, h) = (img.width as f64, img.height as f64);
                    img.pixels
                        .chunks(img.width)
                        .enumerate()
                        .map(|(y, row)| {
                            let band = (PI * y as f64 / h).cos() - (PI * (y + 1) as f64 / h).cos();
                            2.0 * PI / w * band * row.iter().map(|&p| lum(p)).sum::<f64>()
                        })
                        .sum()
                }
            };
            out.push(("environment".into(), PI * r * r * e.scale as f64 * integral));
        }
        out
    }

    /// Radius of a bounding sphere of the geometry, the camera and the point it looks at (as
    /// `prepare` bounds the scene for distant lights).
    fn bounding_radius(&self) -> f64 {
        let (eye, look_at) = (
            self.camera.eye.as_dvec3(),
            (self.camera.eye + self.camera.forward).as_dvec3(),
        );
        let (mut lo, mut hi) = (eye.min(look_at), eye.max(look_at));
        let mut add = |p: glam::DVec3| {
            lo = lo.min(p);
            hi = hi.max(p);
        };
        for m in &self.meshes {
            m.positions.iter().for_each(|p| add(p.as_dvec3()));
        }
        for q in &self.quads {
            let (c, u, v) = (
                q.corner.as_dvec3(),
                q.edge_u.as_dvec3(),
                q.edge_v.as_dvec3(),
            );
            [c, c + u, c + v, c + u + v].into_iter().for_each(&mut add);
        }
        for s in &self.spheres {
            let r = glam::DVec3::splat(s.radius as f64);
            add(s.center.as_dvec3() - r);
            add(s.center.as_dvec3() + r);
        }
        0.5 * (hi - lo).length()
    }

    /// An error naming the file and `light` when the lights have no power in total (zero
    /// emission, a mesh light without area, a black environment map): every image would be
    /// black, so there is nothing to compare and no reference to render.
    pub fn require_light_power(&self) -> Result<()> {
        if self.light_power > 0.0 {
            return Ok(());
        }
        let lights: Vec<String> = self.light_powers().into_iter().map(|(f, _)| f).collect();
        Err(Error::field(
            &self.path,
            "light",
            format!(
                "every light has zero power ({}): the image would be black, there is nothing \
                 to render or compare",
                lights.join(", ")
            ),
        ))
    }
}

/// The parser quotes the offending line: a line of a megabyte is cut to its start.
fn shorten_lines(message: &str) -> String {
    const LONGEST: usize = 200;
    let lines: Vec<String> = message
        .lines()
        .map(|l| match l.char_indices().nth(LONGEST) {
            Some((at, _)) => format!("{}…", &l[..at]),
            None => l.to_string(),
        })
        .collect();
    lines.join("\n")
}

/// `bytes` as UTF-8 text, or an error giving the line and column of the first byte that is not.
fn utf8<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|e| {
        let good = &bytes[..e.valid_up_to()];
        let line_start = good.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = String::from_utf8_lossy(&good[line_start..]).chars().count() + 1;
        Error::Parse {
            path: path.to_path_buf(),
            message: format!(
                "line {line}, column {column}: byte 0x{:02X} is not UTF-8 (scene files are UTF-8 text)",
                bytes[e.valid_up_to()]
            ),
        }
    })
}

struct Validator<'a> {
    path: &'a Path,
}

impl Validator<'_> {
    fn finite(&self, field: &str, x: f32) -> Result<f32> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(Error::field(
                self.path,
                field,
                format!("must be finite, got {x}"),
            ))
        }
    }

    fn vec3(&self, field: &str, a: file::Triple) -> Result<Vec3> {
        let a = a.0;
        if a.iter().all(|c| c.is_finite()) {
            Ok(Vec3::from_array(a))
        } else {
            Err(Error::field(
                self.path,
                field,
                format!("must be finite, got {a:?}"),
            ))
        }
    }

    fn emission(&self, field: &str, e: Option<file::Triple>) -> Result<Option<Vec3>> {
        let Some(e) = e else { return Ok(None) };
        let e = self.vec3(field, e)?;
        if e.min_element() < 0.0 {
            return Err(Error::field(
                self.path,
                field,
                format!("radiance must be non-negative, got {e}"),
            ));
        }
        Ok(Some(e))
    }

    fn environment(
        &self,
        e: &file::EnvironmentDesc,
        base: &Path,
        hasher: &mut Sha256,
    ) -> Result<EnvironmentSpec> {
        let source = match (&e.file, e.constant) {
            (Some(f), None) => {
                let file = base.join(f);
                let in_field = |e: Error| {
                    Error::field(self.path, "environment.file", format!("cannot read {e}"))
                };
                // The decoder checks the image's own size against memory.
                let bytes = bounded::read_file(&file, 0).map_err(in_field)?;
                hasher.update(&bytes);
                let img = LatLongImage::decode(&bytes, &file).map_err(in_field)?;
                EnvSource::Image(Arc::new(img))
            }
            (None, Some(c)) => {
                let c = self.vec3("environment.constant", c)?;
                if c.min_element() < 0.0 {
                    return Err(Error::field(
                        self.path,
                        "environment.constant",
                        format!("radiance must be non-negative, got {c}"),
                    ));
                }
                EnvSource::Constant(c)
            }
            _ => {
                return Err(Error::field(
                    self.path,
                    "environment",
                    "give exactly one of `file` and `constant`",
                ));
            }
        };
        let scale = self.finite("environment.scale", e.scale)?;
        if scale < 0.0 {
            return Err(Error::field(
                self.path,
                "environment.scale",
                "must be non-negative",
            ));
        }
        let brightest = match &source {
            EnvSource::Image(img) => img
                .pixels
                .iter()
                .map(|p| p.max_element())
                .fold(0.0, f32::max),
            EnvSource::Constant(c) => c.max_element(),
        };
        if !(scale * brightest).is_finite() {
            return Err(Error::field(
                self.path,
                "environment.scale",
                format!("{scale} times the brightest radiance {brightest} overflows f32"),
            ));
        }
        let angle = self.finite("environment.rotate_y_deg", e.rotate_y_deg)?;
        Ok(EnvironmentSpec {
            source,
            scale,
            rotation: Quat::from_rotation_y(angle.to_radians()),
        })
    }

    fn camera(&self, c: &file::CameraDesc) -> Result<Camera> {
        let eye = self.vec3("camera.eye", c.eye)?;
        let look_at = self.vec3("camera.look_at", c.look_at)?;
        let up = self.vec3("camera.up", c.up)?;
        let fov = self.finite("camera.fov_y_deg", c.fov_y_deg)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(Error::field(
                self.path,
                "camera.fov_y_deg",
                format!("must be in (0, 180), got {fov}"),
            ));
        }
        let forward = (look_at - eye).normalize_or_zero();
        if forward == Vec3::ZERO {
            return Err(Error::field(
                self.path,
                "camera.look_at",
                "equals camera.eye",
            ));
        }
        let right = forward.cross(up).normalize_or_zero();
        if right == Vec3::ZERO {
            return Err(Error::field(
                self.path,
                "camera.up",
                "is parallel to the viewing direction",
            ));
        }
        Ok(Camera {
            eye,
            forward,
            right,
            up: right.cross(forward),
            tan_half_fov_y: (0.5 * fov.to_radians()).tan(),
        })
    }
}
