//! A representation's texels (piecewise-constant radiance over its atlas) and the importance
//! map over them: texel weights luminance · J(centre), both samplers, and the shared pdf.

use super::cdf::MarginalConditional;
use super::hierarchical::HierarchicalWarp;
use super::latlong::{self, below_one};
use super::{EnvSampler, RecordLine, Repr};
use crate::math::luminance;
use crate::sampling::stream::ONE_MINUS_EPSILON;
use crate::simd::{self, Isa, Kernel, Lanes, Soa3, V3, Vector, WIDTH};
use glam::Vec3;
use rayon::prelude::*;

/// Supersamples per texel side when resampling from the source.
const SUPERSAMPLE: usize = 4;

#[derive(Clone, Debug)]
pub struct TexelMap {
    pub repr: Repr,
    /// Atlas size: `repr.tiles()` square tiles of side `height`.
    pub width: usize,
    pub height: usize,
    /// Row-major radiance.
    pub texels: Vec<Vec3>,
}

/// u·side clamped to [0, side − 1] (a function, not a closure: a closure is not always inlined
/// into the ISA's entry).
#[inline(always)]
fn texel_coordinate<V: Vector<N>, const N: usize>(u: V, side: usize) -> V {
    u.mul(V::splat(side as f32))
        .max(V::splat(0.0))
        .min(V::splat((side - 1) as f32))
}

impl TexelMap {
    /// Each texel is the solid-angle-weighted mean of `radiance` over it (a J-weighted
    /// 4×4 midpoint rule), so the map's integral over the sphere matches the source's.
    pub fn resample(repr: Repr, tile: usize, radiance: &(dyn Fn(Vec3) -> Vec3 + Sync)) -> Self {
        let (width, height) = (repr.tiles() * tile, tile);
        // Texel numbers over lanes are u32 (`index_lanes_u32`); every texel size a scene or
        // the χ² command can ask for is far below (12·512² at most).
        assert!(
            width < 1 << 24 && height < 1 << 24 && width * height <= u32::MAX as usize,
            "an atlas of {width}×{height} texels is past u32 texel numbers"
        );
        let texels = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % width, k / width);
                let (mut sum, mut jsum) = (Vec3::ZERO, 0.0f32);
                for i in 0..SUPERSAMPLE {
                    for j in 0..SUPERSAMPLE {
                        let s = SUPERSAMPLE as f32;
                        let uv = [
                            (x as f32 + (i as f32 + 0.5) / s) / width as f32,
                            (y as f32 + (j as f32 + 0.5) / s) / height as f32,
                        ];
                        let jac = repr.jacobian(uv);
                        sum += jac * radiance(repr.uv_to_dir(uv));
                        jsum += jac;
                    }
                }
                sum / jsum
            })
            .collect();
        TexelMap {
            repr,
            width,
            height,
            texels,
        }
    }

    /// Texel index of an atlas point.
    pub fn index(&self, uv: [f32; 2]) -> usize {
        self.index_lanes::<f32, 1>(uv[0], uv[1])[0]
    }

    /// [`Self::index`] of N lanes.
    #[inline(always)]
    pub fn index_lanes<V: Vector<N>, const N: usize>(&self, u: V, v: V) -> [usize; N] {
        self.index_lanes_u32::<V, N>(u, v).map(|k| k as usize)
    }

    /// [`Self::index_lanes`] as u32 (`resample` keeps atlases below 2³² texels), the form
    /// [`Vector::load_records_at`] reads records by.
    #[inline(always)]
    pub fn index_lanes_u32<V: Vector<N>, const N: usize>(&self, u: V, v: V) -> [u32; N] {
        // `(u·width as usize).min(width − 1)` and the same for v, over lanes: clamped in f32
        // to [0, side − 1], then truncated. The same integers for every input: the sides are
        // below 2²⁴ (so side − 1 is an f32), MAXPS takes NaN and −0 to 0 as `as` does, and a
        // value truncates to at most side − 1 exactly when it is clamped to it.
        debug_assert!(self.width < 1 << 24 && self.height < 1 << 24);
        debug_assert!(self.width * self.height <= u32::MAX as usize);
        let (mut x, mut y) = ([0u32; N], [0u32; N]);
        texel_coordinate(u, self.width).trunc_u32(&mut x);
        texel_coordinate(v, self.height).trunc_u32(&mut y);
        let mut k = [0u32; N];
        for i in 0..N {
            k[i] = y[i] * self.width as u32 + x[i];
        }
        k
    }

    pub fn lookup(&self, w: Vec3) -> Vec3 {
        self.texels[self.index(self.repr.dir_to_uv(w))]
    }

    /// Atlas centre of texel k.
    fn centre(&self, k: usize) -> [f32; 2] {
        [
            ((k % self.width) as f32 + 0.5) / self.width as f32,
            ((k / self.width) as f32 + 0.5) / self.height as f32,
        ]
    }
}

/// A sampled direction with the radiance arriving along it and its solid-angle pdf.
#[derive(Clone, Copy, Debug)]
pub struct EnvSample {
    pub wi: Vec3,
    pub radiance: Vec3,
    pub pdf: f32,
}

#[derive(Clone, Debug)]
pub struct ImportanceMap {
    pub texels: TexelMap,
    /// Texel weights luminance · J(centre), scaled so the largest is 1 and rounded to f32:
    /// both samplers and the pdf use these same values, so a texel is sampled exactly when
    /// its stated pdf is positive.
    weights: Vec<f32>,
    /// Per texel its radiance and its density over the atlas, (w_k / Σw) · texel count (the
    /// sum in f64), in one 16-byte record: the sampler over lanes reads one cache line per
    /// lane instead of three (radiance, density, weight). The density is positive exactly
    /// where the weight is (it is at least the weight: Σw ≤ the count). Four to a 64-byte
    /// line, aligned, so the two records of a texel pair (even column) share a line (see
    /// [`Self::record`]).
    records: Vec<RecordLine>,
    /// ∫ luminance(L) dω over the sphere (≈ Σ weights / texel count, before scaling).
    pub luminance_integral: f64,
    /// None for a black map: nothing to sample.
    cdf: Option<MarginalConditional>,
    hier: Option<HierarchicalWarp>,
}

/// Environment samples of 16 lanes (structure of arrays); `valid` marks the lanes with one.
#[derive(Clone, Copy, Debug, Default)]
pub struct EnvLanes {
    pub valid: u32,
    pub wi: Soa3,
    pub radiance: Soa3,
    pub pdf: [f32; WIDTH],
}

impl ImportanceMap {
    pub fn new(texels: TexelMap) -> Self {
        let exact: Vec<f64> = (0..texels.texels.len())
            .map(|k| {
                luminance(texels.texels[k]) as f64 * texels.repr.jacobian(texels.centre(k)) as f64
            })
            .collect();
        let max = exact.iter().fold(0.0f64, |m, &w| m.max(w));
        let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
        let weights: Vec<f32> = exact.iter().map(|&w| (w * scale) as f32).collect();
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        let count = weights.len() as f64;
        let density: Vec<f32> = weights
            .iter()
            .map(|&w| {
                if total > 0.0 {
                    (w as f64 / total * count) as f32
                } else {
                    0.0
                }
            })
            .collect();
        let mut records = vec![RecordLine::default(); texels.texels.len().div_ceil(4)];
        for (k, (l, &d)) in texels.texels.iter().zip(&density).enumerate() {
            records[k / 4].0[k % 4] = [l.x, l.y, l.z, d];
        }
        let as_f64: Vec<f64> = weights.iter().map(|&w| w as f64).collect();
        let cdf = MarginalConditional::new(&as_f64, texels.width);
        let hier = HierarchicalWarp::new(&weights, texels.repr.tiles(), texels.height);
        ImportanceMap {
            luminance_integral: exact.iter().sum::<f64>() / count,
            weights,
            records,
            cdf,
            hier,
            texels,
        }
    }

    /// Texel k's record: its radiance and density (see `records`).
    #[inline(always)]
    fn record(&self, k: usize) -> &[f32; 4] {
        &self.record_table()[k]
    }

    /// Every texel's record, texel k at k (see `records`), for [`Vector::load_records_at`].
    #[inline(always)]
    fn record_table(&self) -> &[[f32; 4]] {
        super::record_table(&self.records)
    }

    /// Texel k's density over the atlas (see `records`).
    #[inline(always)]
    fn density(&self, k: usize) -> f32 {
        self.record(k)[3]
    }

    /// The atlas points (u, v) ∈ [0, 1)² of N lanes' hierarchical samples, in f32. The two
    /// lines of records under each lane's last 2×2 block (a pair of texels in each of two
    /// rows, a pair sharing a line) are prefetched before the last level's splits (2 MB read
    /// at random: the read after the warp would otherwise wait for them).
    #[inline(always)]
    fn hier_uv<V: Vector<N>, const N: usize>(
        &self,
        hier: &HierarchicalWarp,
        u0: V,
        u1: V,
    ) -> (V, V) {
        let t = &self.texels;
        let s = hier.sample_lanes::<V, N>(u0, u1, |col, row| {
            // Texel numbers are whole f32s: the atlas has at most 2²⁴ texels (checked by
            // `HierarchicalWarp::new`).
            let mut k = [0u32; N];
            row.mul(V::splat(t.width as f32)).add(col).trunc_u32(&mut k);
            let p = self.records.as_ptr();
            for k in k.map(|k| k as usize) {
                crate::simd::prefetch(p.wrapping_add(k / 4));
                crate::simd::prefetch(p.wrapping_add((k + t.width) / 4));
            }
        });
        let below = V::splat(ONE_MINUS_EPSILON);
        (
            s.col.add(s.du).div(V::splat(t.width as f32)).min(below),
            s.row.add(s.dv).div(V::splat(t.height as f32)).min(below),
        )
    }

    /// The atlas point (u, v) ∈ [0, 1)² of the texel (col, row) at offsets (du, dv), rounded
    /// once from f64 to f32.
    #[inline(always)]
    fn cdf_uv(t: &TexelMap, col: usize, row: usize, du: f64, dv: f64) -> [f32; 2] {
        [
            below_one(((col as f64 + du) / t.width as f64) as f32),
            below_one(((row as f64 + dv) / t.height as f64) as f32),
        ]
    }

    /// The atlas points of N lanes' marginal/conditional samples, in lockstep; each lane's
    /// texel record is prefetched as soon as its search ends (2 MB, read at random).
    #[inline(always)]
    fn cdf_uv_lanes<V: Vector<N>, const N: usize>(
        &self,
        cdf: &MarginalConditional,
        u0: V,
        u1: V,
    ) -> (V, V) {
        let t = &self.texels;
        let (mut a, mut b) = ([0.0f32; N], [0.0f32; N]);
        u0.store(&mut a);
        u1.store(&mut b);
        let (col, row, du, dv) = cdf.sample_lanes([a, b]);
        for i in 0..N {
            crate::simd::prefetch(self.record(row[i] * t.width + col[i]));
        }
        for i in 0..N {
            [a[i], b[i]] = Self::cdf_uv(t, col[i], row[i], du[i], dv[i]);
        }
        (V::load(&a), V::load(&b))
    }

    /// None for a black map, and for the measure-zero atlas points where J = 0 (lat/long poles).
    pub fn sample(&self, sampler: EnvSampler, u: [f32; 2]) -> Option<EnvSample> {
        let t = &self.texels;
        let uv = match sampler {
            EnvSampler::Cdf => {
                let ((col, row), [du, dv]) = self.cdf.as_ref()?.sample(u);
                Self::cdf_uv(t, col, row, du, dv)
            }
            EnvSampler::Hierarchical => {
                let (u, v) = self.hier_uv::<f32, 1>(self.hier.as_ref()?, u[0], u[1]);
                [u, v]
            }
        };
        // The texel of the f32 point (rounding can move a point on an edge next door), so
        // radiance and pdf are those a lookup of the same point gives.
        let k = t.index(uv);
        let jac = t.repr.jacobian(uv);
        if self.weights[k] <= 0.0 || jac <= 0.0 {
            return None;
        }
        Some(EnvSample {
            wi: t.repr.uv_to_dir(uv),
            radiance: t.texels[k],
            pdf: self.density(k) / jac,
        })
    }

    /// [`Self::sample`] by either sampler for the lanes of `active`, over lanes, for the
    /// lat/long representation: lane i is [`Self::sample`] of lane i, bit for bit. None when
    /// this map is not lat/long (its maps are scalar) or black.
    #[inline(always)]
    pub fn sample_latlong_lanes<V: Vector<WIDTH>>(
        &self,
        sampler: EnvSampler,
        u0: V,
        u1: V,
        active: u32,
    ) -> Option<EnvLanes> {
        let t = &self.texels;
        if t.repr != Repr::LatLong {
            return None;
        }
        let (u, v) = match sampler {
            EnvSampler::Cdf => self.cdf_uv_lanes::<V, WIDTH>(self.cdf.as_ref()?, u0, u1),
            EnvSampler::Hierarchical => self.hier_uv::<V, WIDTH>(self.hier.as_ref()?, u0, u1),
        };
        let k = t.index_lanes_u32::<V, WIDTH>(u, v);
        let jac = latlong::jacobian_lanes(v);
        let (x, y, z) = latlong::uv_to_dir_lanes(u, v);
        let mut out = EnvLanes::default();
        V3 { x, y, z }.store(&mut out.wi);
        let [r, g, b, density] = V::load_records_at(self.record_table(), &k);
        V3 { x: r, y: g, z: b }.store(&mut out.radiance);
        let zero = V::splat(0.0);
        // As the scalar sampler's weight > 0 (see `records`).
        let positive = zero.lt(density);
        out.valid = active & positive & !jac.le(zero);
        density.div(jac).store(&mut out.pdf);
        Some(out)
    }

    /// [`TexelMap::lookup`] of the directions `w` of lanes `mask`, added to `out`: over lanes
    /// for lat/long maps (bit for bit), lane by lane for the others. Over lanes the radiance is
    /// read from the records, so a pdf of the same direction ([`Self::pdf_lanes`], the MIS
    /// weight of an escaped BSDF sample) finds its density in the line already read.
    /// `prefetched`: these directions' texels from [`Self::prefetch_lookups`], not worked out
    /// again.
    pub fn add_lookups(
        &self,
        isa: Isa,
        w: &Soa3,
        prefetched: Option<&PrefetchedTexels>,
        mask: u32,
        out: &mut [Vec3; WIDTH],
    ) {
        let t = &self.texels;
        if t.repr != Repr::LatLong {
            for (lane, o) in out.iter_mut().enumerate() {
                if mask >> lane & 1 != 0 {
                    *o += t.lookup(w.get(lane));
                }
            }
            return;
        }
        let k = match prefetched {
            Some(p) => p.0,
            None => simd::run(isa, LatLongIndex(t, w)),
        };
        for (lane, o) in out.iter_mut().enumerate() {
            if mask >> lane & 1 != 0 {
                let [r, g, b, _] = *self.record(k[lane]);
                *o += Vec3::new(r, g, b);
            }
        }
    }

    /// Starts the reads of the records [`Self::add_lookups`] and [`Self::pdf_lanes`] will read
    /// for the directions `w` of lanes `mask`, and returns their texels for `add_lookups`
    /// (lat/long maps; the others read texels lane by lane: None). Called before the rays are
    /// traced, so the reads land meanwhile (2 MB of records, read at random by escaped rays).
    pub fn prefetch_lookups(&self, isa: Isa, w: &Soa3, mask: u32) -> Option<PrefetchedTexels> {
        if self.texels.repr != Repr::LatLong {
            return None;
        }
        let k = simd::run(isa, LatLongIndex(&self.texels, w));
        let mut rest = mask;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            crate::simd::prefetch(self.record(k[lane]));
        }
        Some(PrefetchedTexels(k))
    }

    /// Solid-angle pdf of direction `w`: 0 for a black map, in black texels and at J = 0.
    pub fn pdf(&self, w: Vec3) -> f32 {
        let uv = self.texels.repr.dir_to_uv(w);
        let jac = self.texels.repr.jacobian(uv);
        if jac <= 0.0 {
            return 0.0;
        }
        self.density(self.texels.index(uv)) / jac
    }

    /// [`Self::pdf`] of the directions `w` of lanes `mask` (0 in the others): over lanes for
    /// lat/long maps (bit for bit), lane by lane for the others.
    pub fn pdf_lanes(&self, isa: Isa, w: &Soa3, mask: u32) -> [f32; WIDTH] {
        let mut out = [0.0f32; WIDTH];
        if self.texels.repr != Repr::LatLong {
            for (lane, o) in out.iter_mut().enumerate() {
                if mask >> lane & 1 != 0 {
                    *o = self.pdf(w.get(lane));
                }
            }
            return out;
        }
        struct Pdf<'a>(&'a ImportanceMap, &'a Soa3, u32);
        impl Kernel for Pdf<'_> {
            type Out = [f32; WIDTH];
            #[inline(always)]
            fn run<L: Lanes>(self) -> [f32; WIDTH] {
                let (map, mask) = (self.0, self.2);
                let w = V3::<L::V>::load(self.1);
                let (u, v) = latlong::dir_to_uv_lanes(w.x, w.y, w.z);
                let jac = latlong::jacobian_lanes(v);
                // Every lane reads a record, a lane outside `mask` texel 0's (its direction
                // may be anything, and its record would be a read at random in 2 MB that
                // nothing prefetched); their pdfs are zeroed after.
                let zero = L::V::splat(0.0);
                let (ku, kv) = (L::V::select(mask, u, zero), L::V::select(mask, v, zero));
                let k = map.texels.index_lanes_u32::<L::V, WIDTH>(ku, kv);
                let [_, _, _, density] = L::V::load_records_at(map.record_table(), &k);
                // J ≤ 0 (at the poles) has pdf 0, as in the scalar pdf; other lanes divide by 1.
                let positive = zero.lt(jac) & mask;
                let pdf = density.div(L::V::select(positive, jac, L::V::splat(1.0)));
                let mut out = [0.0f32; WIDTH];
                L::V::select(positive, pdf, zero).store(&mut out);
                out
            }
        }
        simd::run(isa, Pdf(self, w, mask))
    }
}

/// The lat/long texels of a packet's directions, their records on their way
/// ([`ImportanceMap::prefetch_lookups`]).
pub struct PrefetchedTexels([usize; WIDTH]);

/// The lat/long texel of each lane's direction.
struct LatLongIndex<'a>(&'a TexelMap, &'a Soa3);

impl Kernel for LatLongIndex<'_> {
    type Out = [usize; WIDTH];
    #[inline(always)]
    fn run<L: Lanes>(self) -> [usize; WIDTH] {
        let w = V3::<L::V>::load(self.1);
        let (u, v) = latlong::dir_to_uv_lanes(w.x, w.y, w.z);
        self.0.index_lanes::<L::V, WIDTH>(u, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::SampleStream;

    /// The texel index over lanes is `(u·side as usize).min(side − 1)` per axis, for every
    /// input a warp or a direction could give and the ones it should not (NaN, −0, below 0,
    /// 1 and past it, huge), on every ISA. Control: the lower clamp dropped (a negative
    /// coordinate then wraps around as an integer).
    #[test]
    fn texel_index_over_lanes_is_the_scalar_formula() {
        let m = TexelMap::resample(Repr::LatLong, 8, &|_| Vec3::ZERO);
        let odd = [
            f32::NAN,
            -0.0,
            0.0,
            -1.5,
            -1e30,
            f32::MIN_POSITIVE,
            0.5,
            1.0 - f32::EPSILON / 2.0,
            1.0,
            1.0 + f32::EPSILON,
            7.9,
            1e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0625,
            0.999,
        ];
        let want = |u: f32, v: f32| {
            let x = ((u * m.width as f32) as usize).min(m.width - 1);
            let y = ((v * m.height as f32) as usize).min(m.height - 1);
            y * m.width + x
        };
        for isa in Isa::available() {
            for shift in 0..WIDTH {
                let u: [f32; WIDTH] = std::array::from_fn(|i| odd[i]);
                let v: [f32; WIDTH] = std::array::from_fn(|i| odd[(i + shift) % WIDTH]);
                struct Index<'a>(&'a TexelMap, [f32; WIDTH], [f32; WIDTH]);
                impl Kernel for Index<'_> {
                    type Out = [usize; WIDTH];
                    #[inline(always)]
                    fn run<L: Lanes>(self) -> [usize; WIDTH] {
                        self.0
                            .index_lanes::<L::V, WIDTH>(L::V::load(&self.1), L::V::load(&self.2))
                    }
                }
                let got = simd::run(isa, Index(&m, u, v));
                for i in 0..WIDTH {
                    assert_eq!(got[i], want(u[i], v[i]), "{isa:?} u {} v {}", u[i], v[i]);
                    assert_eq!(m.index([u[i], v[i]]), want(u[i], v[i]));
                }
            }
        }
    }

    /// Radiance that differs in every texel, so a lookup one texel off shows.
    fn map(repr: Repr) -> TexelMap {
        let mut m = TexelMap::resample(repr, 8, &|_| Vec3::ZERO);
        for (k, t) in m.texels.iter_mut().enumerate() {
            *t = Vec3::new(k as f32 + 1.0, 0.5 * k as f32, 1.0);
        }
        m
    }

    /// Directions where lookups are delicate: the poles, the axes, both sides of the seam.
    fn special() -> [Vec3; 11] {
        [
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            -Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(-1.0, 0.0, -0.0),
            Vec3::new(-1.0, 0.0, 1e-8).normalize(),
            Vec3::new(-1.0, 0.0, -1e-8).normalize(),
            Vec3::new(1e-7, 1.0, 0.0).normalize(),
            Vec3::new(0.0, -1.0, 1e-7).normalize(),
        ]
    }

    /// Round `round`'s sixteen directions (every third round the special ones) and lane mask
    /// (every other round all lanes, else a random subset).
    fn directions(rng: &mut SampleStream, round: usize) -> (Soa3, u32) {
        let special = special();
        let mut w = Soa3::default();
        for lane in 0..WIDTH {
            let d = if round.is_multiple_of(3) {
                special[(lane + round) % special.len()]
            } else {
                crate::sampling::warp::sample_uniform_sphere(rng.next_2d())
            };
            w.set(lane, d);
        }
        let mask = if round.is_multiple_of(2) {
            u32::MAX >> (32 - WIDTH)
        } else {
            (rng.next_2d()[0] * (1u32 << WIDTH) as f32) as u32
        };
        (w, mask)
    }

    /// Sixteen pdfs at once are the scalar ones, bit for bit, on every ISA and for every
    /// representation (poles, axes, the seam, black texels among them), 0 outside the mask.
    #[test]
    fn pdfs_over_lanes_are_the_scalar_ones_on_every_isa() {
        let mut rng = SampleStream::new(5, 1, 2, 3);
        for repr in Repr::ALL {
            let mut texels = map(repr);
            for (k, t) in texels.texels.iter_mut().enumerate() {
                if k % 7 == 3 {
                    *t = Vec3::ZERO;
                }
            }
            let m = ImportanceMap::new(texels);
            for round in 0..300 {
                let (w, mask) = directions(&mut rng, round);
                for isa in Isa::available() {
                    let got = m.pdf_lanes(isa, &w, mask);
                    for (lane, g) in got.iter().enumerate() {
                        let want = if mask >> lane & 1 != 0 {
                            m.pdf(w.get(lane))
                        } else {
                            0.0
                        };
                        assert_eq!(
                            g.to_bits(),
                            want.to_bits(),
                            "{isa:?} {repr:?} lane {lane} w {:?}",
                            w.get(lane)
                        );
                    }
                }
            }
        }
    }

    /// Sixteen lookups at once are the scalar ones, bit for bit, on every ISA and for every
    /// representation, with the poles, the axes and both sides of the lat/long seam among the
    /// directions, and only the masked lanes added.
    #[test]
    fn lookups_over_lanes_are_the_scalar_ones_on_every_isa() {
        let mut rng = SampleStream::new(4, 1, 2, 3);
        for repr in Repr::ALL {
            let m = ImportanceMap::new(map(repr));
            for round in 0..300 {
                let (w, mask) = directions(&mut rng, round);
                for isa in Isa::available() {
                    // Worked out here, and from the texels the prefetch found (lat/long).
                    let prefetched = m.prefetch_lookups(isa, &w, mask);
                    assert_eq!(prefetched.is_some(), repr == Repr::LatLong, "{repr:?}");
                    for given in [None, prefetched.as_ref()] {
                        let mut out = [Vec3::splat(0.25); WIDTH];
                        m.add_lookups(isa, &w, given, mask, &mut out);
                        for (lane, o) in out.iter().enumerate() {
                            let want = if mask >> lane & 1 != 0 {
                                Vec3::splat(0.25) + m.texels.lookup(w.get(lane))
                            } else {
                                Vec3::splat(0.25)
                            };
                            assert_eq!(
                                o.to_array().map(f32::to_bits),
                                want.to_array().map(f32::to_bits),
                                "{isa:?} {repr:?} lane {lane} prefetched {} w {:?}",
                                given.is_some(),
                                w.get(lane)
                            );
                        }
                    }
                }
            }
        }
    }
}
