//! OBJ triangle meshes through `tobj`, checked so that bad geometry is an error naming the
//! file, not a NaN in the middle of a render. Parsed from bytes already read (and hashed): the
//! parser opens no file, not even the `mtllib` materials, which dibench does not use.

use crate::error::{Error, Result};
use glam::Vec3;
use std::path::Path;

pub fn parse(bytes: &[u8], file: &Path) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let bad = |message: String| Error::Parse {
        path: file.to_path_buf(),
        message,
    };
    // Not triangulated by tobj, which would turn a one- or two-vertex face into a triangle
    // without area: faces are checked here, then fanned.
    let opts = tobj::LoadOptions {
        triangulate: false,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut &bytes[..], &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| bad(format!("not a readable OBJ mesh: {e}")))?;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for m in models {
        let base = positions.len() as u32;
        let mesh = &m.mesh;
        for (k, p) in mesh.positions.chunks_exact(3).enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(bad(format!(
                    "vertex {} of object `{}` is not finite: {p:?}",
                    k + 1,
                    m.name
                )));
            }
            positions.push(Vec3::new(p[0], p[1], p[2]));
        }
        let n = (mesh.positions.len() / 3) as u32;
        if let Some(bad_index) = mesh.indices.iter().find(|&&i| i >= n) {
            return Err(bad(format!(
                "object `{}` uses vertex index {} but there are {n} vertices",
                m.name,
                bad_index + 1
            )));
        }
        // Empty arities: every face is a triangle.
        let arities: Vec<u32> = if mesh.face_arities.is_empty() {
            vec![3; mesh.indices.len() / 3]
        } else {
            mesh.face_arities.clone()
        };
        let mut at = 0usize;
        for (k, &arity) in arities.iter().enumerate() {
            let face = &mesh.indices[at..at + arity as usize];
            at += arity as usize;
            if arity < 3 {
                return Err(bad(format!(
                    "face {} of object `{}` has {arity} vertices; a face needs at least 3",
                    k + 1,
                    m.name
                )));
            }
            for w in face[1..].windows(2) {
                triangles.push([base + face[0], base + w[0], base + w[1]]);
            }
        }
    }
    if triangles.is_empty() {
        return Err(bad("no triangles".into()));
    }
    Ok((positions, triangles))
}
