//! Analytic sphere intersection. A sphere light is traced as the exact sphere its sampler
//! samples, never a tessellation, or light and geometry would disagree.

use super::Ray;
use crate::simd::{V3, Vector, Vector64, WIDTH, dot3};
use crate::tracer::RayPacket;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// Nearest t in (0, ray.tmax) of a unit-direction ray. The discriminant is computed as
    /// r² - |f - (f·d)d|² and the roots as q/a, c/q (Haines et al., "Precision Improvements for
    /// Ray/Sphere Intersection", Ray Tracing Gems, ch. 7), in f64: for a near-tangent chord,
    /// such as a shadow ray from a point 1e-6 above a unit sphere to a sampled point 1e-3 away,
    /// the discriminant is ~1e-7 and f32 would bury it under the rounding of |perp|² (≈ 1.2e-7),
    /// reporting the light's own surface as an occluder. The inputs are f32, exact in f64.
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let f = ray.origin.as_dvec3() - self.center.as_dvec3();
        let dir = ray.dir.as_dvec3();
        let b = -f.dot(dir);
        let perp = f + dir * b;
        let r = self.radius as f64;
        let r2 = r * r;
        let disc = r2 - perp.length_squared();
        if disc < 0.0 {
            return None;
        }
        let tmax = ray.tmax as f64;
        // The segment's point nearest the centre, at t = min(b, tmax) when b ≥ 0: outside the
        // sphere, the whole segment is. This settles the shadow rays aimed at the sphere (their
        // tmax ends short of its near side, before b) without the square root and division of
        // the roots. (With b < 0 it is the line's nearest point, inside: no early answer.)
        let nearest = f + dir * b.min(tmax);
        if nearest.length_squared() > r2 {
            return None;
        }
        let c = f.length_squared() - r2;
        let q = b + b.signum() * disc.sqrt();
        if q == 0.0 {
            return None; // ray origin at the centre of a zero-radius sphere
        }
        let (t0, t1) = {
            let x = c / q;
            if x < q { (x, q) } else { (q, x) }
        };
        let t = if t0 > 0.0 && t0 < tmax {
            t0
        } else if t1 > 0.0 && t1 < tmax {
            t1
        } else {
            return None;
        };
        // Rounding to f32 must not carry a hit past tmax or down to 0.
        let t32 = t as f32;
        (t32 > 0.0 && t32 < ray.tmax).then_some(t32)
    }

    /// [`Self::intersect`] of the rays of `rays` in lanes `m` (their tmax `tmax`), over f64
    /// lanes, the same operations in the same order: the lanes that hit, and their t.
    #[inline(always)]
    pub fn intersect_lanes<D: Vector64<WIDTH>>(
        &self,
        rays: &RayPacket,
        tmax: &[f32; WIDTH],
        m: u32,
    ) -> (u32, [f32; WIDTH]) {
        let c = self.center.as_dvec3();
        let f = [
            D::from_f32(&rays.ox).sub(D::splat(c.x)),
            D::from_f32(&rays.oy).sub(D::splat(c.y)),
            D::from_f32(&rays.oz).sub(D::splat(c.z)),
        ];
        let dir = [
            D::from_f32(&rays.dx),
            D::from_f32(&rays.dy),
            D::from_f32(&rays.dz),
        ];
        let b = dot3(f, dir).neg();
        let perp = [
            f[0].add(dir[0].mul(b)),
            f[1].add(dir[1].mul(b)),
            f[2].add(dir[2].mul(b)),
        ];
        let r = self.radius as f64;
        let r2 = D::splat(r * r);
        let zero = D::splat(0.0);
        let disc = r2.sub(dot3(perp, perp));
        let mut hit = m & !disc.lt(zero);
        if hit == 0 {
            // Every lane misses (most shadow rays pass a sphere by): nothing more to compute.
            return (0, [0.0; WIDTH]);
        }
        // f32 → f64 is exact, so comparisons in f64 are the f32 ones.
        let tm = D::from_f32(tmax);
        let to = b.min(tm);
        let nearest = [
            f[0].add(dir[0].mul(to)),
            f[1].add(dir[1].mul(to)),
            f[2].add(dir[2].mul(to)),
        ];
        hit &= !r2.lt(dot3(nearest, nearest));
        if hit == 0 {
            // Every segment ends short of the sphere (shadow rays aimed at it).
            return (0, [0.0; WIDTH]);
        }
        let c = dot3(f, f).sub(r2);
        // b.signum(): −1 where the sign bit is set (−0.0 included).
        let sign = b.sign_select(D::splat(-1.0), D::splat(1.0));
        let q = b.add(sign.mul(D::select(hit, disc, zero).sqrt()));
        hit &= !q.eq(zero);
        let x = c.div(D::select(hit, q, D::splat(1.0)));
        let near = x.lt(q);
        let (t0, t1) = (D::select(near, x, q), D::select(near, q, x));
        let first = zero.lt(t0) & t0.lt(tm);
        let second = zero.lt(t1) & t1.lt(tm);
        hit &= first | second;
        let mut t = [0.0f32; WIDTH];
        D::select(first, t0, t1).to_f32(&mut t);
        // Rounding to f32 must not carry a hit past tmax or down to 0.
        let t32 = D::from_f32(&t);
        hit &= zero.lt(t32) & t32.lt(tm);
        (hit, t)
    }

    /// Outward unit normal at a point on (or near) the surface.
    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        (p - self.center) / self.radius
    }

    /// Projects a point computed from a ray back onto the surface, removing the error in t.
    pub fn project(&self, p: Vec3) -> Vec3 {
        self.center + (p - self.center).normalize() * self.radius
    }

    /// The hit point, its error bound and the normal of rays `o + t·d` that hit the sphere,
    /// over lanes: [`Self::project`] of [`Ray::at`], [`Self::point_error`] and
    /// [`Self::normal_at`] in the same operations and order, so bit for bit the scalar
    /// values (what `World::surface` gives a sphere hit).
    #[inline(always)]
    pub fn surface_lanes<V: Vector<WIDTH>>(&self, o: V3<V>, d: V3<V>, t: V) -> [V3<V>; 3] {
        use crate::math::gamma;
        let c = V3::splat(self.center);
        let r = V::splat(self.radius);
        let off = (o + d.scale(t)) - c;
        let p = c + off.scale(V::splat(1.0).div(off.dot(off).sqrt())).scale(r);
        let centre_error = V3::splat(gamma(1) * self.center.abs());
        let p_error = (p - c).abs().scale(V::splat(gamma(6))) + centre_error;
        [p, p_error, (p - c) / r]
    }

    /// Absolute error bound of a point on the surface computed as centre + r·n̂ (by
    /// [`Self::project`] or a sampler): γ₅ on the reprojected offset (pbrt-v4 §6.8.5), one more
    /// rounding for adding the centre.
    pub fn point_error(&self, p: Vec3) -> Vec3 {
        use crate::math::gamma;
        let local = (p - self.center).abs();
        gamma(6) * local + gamma(1) * self.center.abs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::SampleStream;
    use crate::sampling::warp::sample_uniform_sphere;
    use crate::simd::{Isa, Kernel, Lanes};

    struct Lanes16<'a>(&'a Sphere, &'a RayPacket, [f32; WIDTH]);

    impl Kernel for Lanes16<'_> {
        type Out = (u32, [f32; WIDTH]);
        #[inline(always)]
        fn run<L: Lanes>(self) -> Self::Out {
            self.0.intersect_lanes::<L::D>(self.1, &self.2, 0xffff)
        }
    }

    /// Sixteen rays at once hit as the scalar test does, with the same t bit for bit, on every
    /// ISA: rays from outside, inside, on the surface (1e-6 above and below), grazing, aimed
    /// away, with finite and infinite tmax, and perpendicular ones (f·d = 0, b = −0.0).
    #[test]
    fn lanes_are_the_scalar_test_on_every_isa() {
        let s = Sphere {
            center: Vec3::new(0.3, -0.2, 1.5),
            radius: 0.7,
        };
        let mut rng = SampleStream::new(5, 8, 1, 3);
        let (mut hits, mut total) = (0, 0);
        for round in 0..2000 {
            let mut rays = RayPacket::default();
            let mut tmax = [0.0f32; WIDTH];
            // Every tenth packet misses in every lane (lines passing the sphere by: from 1 or
            // more away from the centre, at right angles to it, radius 0.7), the kernel's early
            // exit.
            let away = round % 10 == 9;
            // Every tenth other packet holds shadow rays aimed at points of the sphere's side
            // facing them (within 30° of the origin's direction, inside the visible cap of at
            // least 45°), each ending 1e-3 short of its point: the second early exit.
            let short = round % 10 == 8;
            for (l, tmax_l) in tmax.iter_mut().enumerate() {
                let n = sample_uniform_sphere(rng.next_2d());
                if short {
                    let o = s.center + n * (1.0 + 4.0 * rng.next_1d());
                    let q = s.center
                        + (n + 0.5 * sample_uniform_sphere(rng.next_2d())).normalize() * s.radius;
                    let tm = (q - o).length() * (1.0 - 1e-3);
                    rays.set(l, &Ray::new(o, (q - o).normalize(), tm));
                    *tmax_l = tm;
                    continue;
                }
                let o = match (round + l) % 5 {
                    _ if away => s.center + n * (1.0 + 4.0 * rng.next_1d()),
                    0 => s.center + n * (s.radius + 1e-6),
                    1 => s.center + n * (s.radius - 1e-6),
                    2 => s.center + n * 0.3,
                    _ => s.center + n * (1.0 + 4.0 * rng.next_1d()),
                };
                let mut d = sample_uniform_sphere(rng.next_2d());
                if away {
                    d = n.any_orthonormal_vector();
                } else if l == 7 {
                    // Perpendicular to the centre direction: f·d = 0.
                    let f = (o - s.center).normalize();
                    d = f.any_orthonormal_vector();
                }
                let tm = if l % 3 == 0 {
                    f32::INFINITY
                } else {
                    3.0 * rng.next_1d()
                };
                rays.set(l, &Ray::new(o, d, tm));
                *tmax_l = tm;
            }
            for isa in Isa::available() {
                let (mask, t) = crate::simd::run(isa, Lanes16(&s, &rays, tmax));
                for (l, &t) in t.iter().enumerate() {
                    let want = s.intersect(&rays.get(l));
                    let got = (mask >> l & 1 != 0).then_some(t);
                    assert_eq!(
                        got.map(f32::to_bits),
                        want.map(f32::to_bits),
                        "{isa:?} round {round} lane {l}"
                    );
                    hits += want.is_some() as usize;
                    total += 1;
                }
            }
        }
        assert!(
            hits > total / 5 && hits < total * 4 / 5,
            "{hits} of {total}"
        );
    }

    /// Segments that end short of the sphere miss and chords through it hit, whatever their
    /// ends: shadow rays aimed at points of the sphere stopping just before them (the early
    /// answer from the segment's nearest point), chords whose both ends lie outside (the nearest
    /// point is then inside, t = b, not the end), and segments ending inside. The reference is
    /// the textbook geometry in f64: the nearest point of the segment to the centre.
    #[test]
    fn segments_short_of_the_sphere_miss_and_chords_hit() {
        let s = Sphere {
            center: Vec3::new(0.4, 1.0, -2.0),
            radius: 0.8,
        };
        let mut rng = SampleStream::new(9, 2, 7, 1);
        let (mut short, mut chords) = (0, 0);
        for k in 0..20_000 {
            let o = s.center + sample_uniform_sphere(rng.next_2d()) * (1.0 + 5.0 * rng.next_1d());
            let q = s.center + sample_uniform_sphere(rng.next_2d()) * s.radius;
            let (d, dist) = ((q - o).normalize(), (q - o).length());
            // Ends 1e-3 short of q (a shadow ray), or past it by up to a diameter (a chord when q
            // is on the near side), or anywhere before it.
            let tmax = match k % 3 {
                0 => dist * (1.0 - 1e-3),
                1 => dist + 2.0 * s.radius * rng.next_1d(),
                _ => dist * rng.next_1d(),
            };
            let (of, df, c) = (o.as_dvec3(), d.as_dvec3(), s.center.as_dvec3());
            let t_near = (c - of).dot(df).clamp(0.0, tmax as f64);
            let gap = (of + df * t_near - c).length() - s.radius as f64;
            if gap.abs() < 1e-4 {
                continue; // within rounding of grazing: either answer is right
            }
            let got = s.intersect(&Ray::new(o, d, tmax));
            assert_eq!(
                got.is_some(),
                gap < 0.0,
                "case {k}: gap {gap:e}, tmax {tmax}"
            );
            short += (gap > 0.0 && (c - of).dot(df) > tmax as f64) as usize;
            chords +=
                (gap < 0.0 && (of + df * tmax as f64 - c).length() > s.radius as f64) as usize;
        }
        // Both kinds are exercised: a segment ending short of the sphere and a chord with both
        // ends outside (which the end point alone would call a miss).
        assert!(
            short > 1000 && chords > 1000,
            "{short} short, {chords} chords"
        );
    }

    #[test]
    fn outside_inside_and_far_small_spheres() {
        let s = Sphere {
            center: Vec3::new(0.0, 0.0, -5.0),
            radius: 1.0,
        };
        let ray = Ray::new(Vec3::ZERO, -Vec3::Z, f32::INFINITY);
        assert!((s.intersect(&ray).unwrap() - 4.0).abs() < 1e-5);
        let inside = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::X, f32::INFINITY);
        assert!((s.intersect(&inside).unwrap() - 1.0).abs() < 1e-6);
        let behind = Ray::new(Vec3::ZERO, Vec3::Z, f32::INFINITY);
        assert!(s.intersect(&behind).is_none());
        // A 1e-3 sphere at distance 1e4: the textbook quadratic loses it entirely in f32.
        let tiny = Sphere {
            center: Vec3::new(0.0, 0.0, -1e4),
            radius: 1e-3,
        };
        let t = tiny.intersect(&ray).expect("tiny far sphere must be hit");
        assert!((t - (1e4 - 1e-3)).abs() / 1e4 < 1e-6);
    }
}
