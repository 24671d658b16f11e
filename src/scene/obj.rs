//! OBJ triangle meshes through `tobj`, checked so that bad geometry is an error naming the
//! file, not a NaN in the middle of a render.

use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

pub fn load(file: &Path) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(file, &opts).map_err(|e| Error::Parse {
        path: file.to_path_buf(),
        message: format!("not a readable OBJ mesh: {e}"),
    })?;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        let mesh = &m.mesh;
        for (k, p) in mesh.positions.chunks_exact(3).enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::Parse {
                    path: file.to_path_buf(),
                    message: format!(
                        "vertex {} of object `{}` is not finite: {p:?}",
                        k + 1,
                        m.name
                    ),
                });
            }
            positions.push(Vec3::new(p[0], p[1], p[2]));
        }
        let n = (mesh.positions.len() / 3) as u32;
        for (k, f) in mesh.indices.chunks_exact(3).enumerate() {
            if let Some(bad) = f.iter().find(|&&i| i >= n) {
                return Err(Error::Parse {
                    path: file.to_path_buf(),
                    message: format!(
                        "face {} of object `{}` uses vertex {} but there are {n}",
                        k + 1,
                        m.name,
                        bad + 1
                    ),
                });
            }
            triangles.push([base + f[0], base + f[1], base + f[2]]);
        }
    }
    if triangles.is_empty() {
        return Err(Error::Parse {
            path: file.to_path_buf(),
            message: "no triangles".into(),
        });
    }
    Ok((positions, triangles))
}
