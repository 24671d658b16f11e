//! HEALPix (Górski et al. 2005) as an atlas of its 12 base pixels side by side: u ∈ [f/12,
//! (f+1)/12) is base pixel f, (x, y) = (12u − f, v) its continuous nested coordinates (the
//! resolution Nside is the atlas height). Formulas after healpix_cxx `xyf2loc` / `loc2pix`,
//! continuous. The HEALPix projection is equal-area and (x, y) are affine in it, so
//! dω/(du dv) = 4π everywhere, with +Y as HEALPix's z (pole) axis.

use super::latlong::below_one;
use glam::Vec3;
use std::f32::consts::{FRAC_PI_2, PI};

const JRLL: [f32; 12] = [2., 2., 2., 2., 3., 3., 3., 3., 4., 4., 4., 4.];
const JPLL: [f32; 12] = [1., 3., 5., 7., 0., 2., 4., 6., 1., 3., 5., 7.];

pub fn uv_to_dir(uv: [f32; 2]) -> Vec3 {
    let fx = 12.0 * uv[0];
    let face = (fx as usize).min(11);
    let (x, y) = (fx - face as f32, uv[1]);
    let jr = JRLL[face] - x - y;
    // z and sin θ; in the caps sin θ from nr directly, to keep precision at the poles.
    let (nr, z, sin_theta) = if jr < 1.0 {
        let nr = jr;
        let t = nr * nr / 3.0;
        (nr, 1.0 - t, (t * (2.0 - t)).max(0.0).sqrt())
    } else if jr > 3.0 {
        let nr = 4.0 - jr;
        let t = nr * nr / 3.0;
        (nr, t - 1.0, (t * (2.0 - t)).max(0.0).sqrt())
    } else {
        let z = (2.0 - jr) * 2.0 / 3.0;
        (1.0, z, ((1.0 - z) * (1.0 + z)).max(0.0).sqrt())
    };
    let mut t = JPLL[face] * nr + x - y;
    if t < 0.0 {
        t += 8.0;
    }
    if t >= 8.0 {
        t -= 8.0;
    }
    let phi = if nr > 0.0 { 0.25 * PI * t / nr } else { 0.0 };
    Vec3::new(sin_theta * phi.cos(), z, sin_theta * phi.sin())
}

pub fn dir_to_uv(w: Vec3) -> [f32; 2] {
    let z = w.y;
    let za = z.abs();
    let mut phi = crate::math::atan2(w.z, w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let tt = (phi / FRAC_PI_2).clamp(0.0, 4.0 - 4.0 * f32::EPSILON);
    let (face, x, y) = if za <= 2.0 / 3.0 {
        let t1 = 0.5 + tt;
        let t2 = 0.75 * z;
        let (jp, jm) = (t1 - t2, t1 + t2);
        let (ifp, ifm) = (jp.floor() as i32, jm.floor() as i32);
        let face = if ifp == ifm {
            (ifp | 4) as usize
        } else if ifp < ifm {
            ifp as usize
        } else {
            (ifm + 8) as usize
        };
        (face, jm - jm.floor(), 1.0 - (jp - jp.floor()))
    } else {
        let ntt = (tt as usize).min(3);
        let tp = tt - ntt as f32;
        // sqrt(3(1 - |z|)) with 1 - |z| = (x² + z²)/(1 + |z|).
        let s2 = w.x * w.x + w.z * w.z;
        let tmp = (3.0 * s2 / (1.0 + za)).sqrt();
        let (jp, jm) = ((tp * tmp).min(1.0), ((1.0 - tp) * tmp).min(1.0));
        if z > 0.0 {
            (ntt, 1.0 - jm, 1.0 - jp)
        } else {
            (ntt + 8, jp, jm)
        }
    };
    // The in-face coordinate stays below 1, or an edge point would land on the next face.
    let x = below_one(x);
    [below_one((face as f32 + x) / 12.0), below_one(y)]
}

pub fn jacobian(_uv: [f32; 2]) -> f32 {
    4.0 * PI
}
