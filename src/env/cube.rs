//! Cube map as an atlas of six square faces side by side: u ∈ [f/6, (f+1)/6) is face f in the
//! order +X, −X, +Y, −Y, +Z, −Z; face coordinates (a, b) = (12u − 2f − 1, 2v − 1) ∈ [−1, 1]².
//! A direction lies on the face of its largest component; ω = normalize(axis + a·s + b·t).
//! Jacobian dω/(du dv) = 12·2 / (1 + a² + b²)^{3/2} (the gnomonic projection's solid angle).

use super::latlong::below_one;
use glam::Vec3;

/// (axis, s, t) of each face; s × t = axis is not needed, only consistency.
const FACES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Z, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::Z, Vec3::NEG_Y),
    (Vec3::Y, Vec3::X, Vec3::Z),
    (Vec3::NEG_Y, Vec3::X, Vec3::NEG_Z),
    (Vec3::Z, Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_X, Vec3::NEG_Y),
];

pub fn dir_to_uv(w: Vec3) -> [f32; 2] {
    let a = w.abs();
    let face = if a.x >= a.y && a.x >= a.z {
        if w.x >= 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if w.y >= 0.0 { 2 } else { 3 }
    } else if w.z >= 0.0 {
        4
    } else {
        5
    };
    let (axis, s, t) = FACES[face];
    let m = w.dot(axis);
    let (fa, fb) = (w.dot(s) / m, w.dot(t) / m);
    // The in-face coordinate stays below 1, or an edge point would land on the next face.
    let x = below_one(0.5 * (fa.clamp(-1.0, 1.0) + 1.0));
    [
        below_one((face as f32 + x) / 6.0),
        below_one(0.5 * (fb.clamp(-1.0, 1.0) + 1.0)),
    ]
}

/// Face index and face coordinates (a, b) of an atlas point.
fn face_ab(uv: [f32; 2]) -> (usize, f32, f32) {
    let x = 6.0 * uv[0];
    let face = (x as usize).min(5);
    (face, 2.0 * (x - face as f32) - 1.0, 2.0 * uv[1] - 1.0)
}

pub fn uv_to_dir(uv: [f32; 2]) -> Vec3 {
    let (face, a, b) = face_ab(uv);
    let (axis, s, t) = FACES[face];
    (axis + a * s + b * t).normalize()
}

pub fn jacobian(uv: [f32; 2]) -> f32 {
    let (_, a, b) = face_ab(uv);
    let r2 = 1.0 + a * a + b * b;
    24.0 / (r2 * r2.sqrt())
}
