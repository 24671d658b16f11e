//! Small numeric helpers shared by geometry, samplers and the renderer.

use glam::Vec3;

/// An orthonormal frame around a unit normal (Duff et al., "Building an Orthonormal Basis,
/// Revisited", JCGT 2017): branch-free apart from the sign, no normalisation needed.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// Offsets a surface point along its geometric normal so that a ray leaving it on the side of
/// `n` cannot re-hit the surface it starts on. Integer-ULP offset far from the origin, a tiny
/// absolute offset near it (Wächter & Binder, "A Fast and Robust Method for Avoiding
/// Self-Intersection", Ray Tracing Gems, ch. 6). Scale-invariant, so no scene-size epsilon.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let of_i = (n * INT_SCALE).to_array().map(|c| c as i32);
    let pa = p.to_array();
    let mut out = [0.0f32; 3];
    for k in 0..3 {
        let bits = pa[k].to_bits() as i32;
        let moved = if pa[k] < 0.0 {
            bits - of_i[k]
        } else {
            bits + of_i[k]
        };
        let p_i = f32::from_bits(moved as u32);
        out[k] = if pa[k].abs() < ORIGIN {
            pa[k] + FLOAT_SCALE * n.to_array()[k]
        } else {
            p_i
        };
    }
    Vec3::from_array(out)
}

/// Luminance with Rec. 709 weights: the scalar that light selection and relMSE use.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// SplitMix64 finaliser: turns (seed, pixel, pass) tuples into independent stream seeds.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_all_octants() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.0, -1.0, 1e-7).normalize(),
            Vec3::new(-0.3, 0.5, -0.8).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5 && (f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            let v = Vec3::new(0.2, -0.7, 0.4);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn offset_moves_to_the_normal_side_at_every_scale() {
        for scale in [0.0f32, 1e-3, 1.0, 1e3, 1e5] {
            let p = Vec3::new(scale, -scale, 0.5 * scale);
            let n = Vec3::new(0.3, -0.2, 0.9).normalize();
            let q = offset_ray_origin(p, n);
            assert!(
                (q - p).dot(n) > 0.0,
                "scale {scale}: offset not on the normal side"
            );
        }
    }
}
