//! The image being accumulated: per-pixel f64 sums in 4×4-tile-major order, so the tiles of
//! one pass can be written in parallel without locks.

use crate::simd::{self, Isa, Kernel, Lanes, Vector64, WIDTH};
use glam::Vec3;

pub const TILE: u32 = 4;

/// Where each pixel lives in tile-major order.
#[derive(Clone, Copy, Debug)]
pub struct TileLayout {
    pub width: u32,
    pub height: u32,
    tiles_x: u32,
}

impl TileLayout {
    pub fn new(width: u32, height: u32) -> Self {
        TileLayout {
            width,
            height,
            tiles_x: width.div_ceil(TILE),
        }
    }

    pub fn tile_count(&self) -> usize {
        (self.tiles_x * self.height.div_ceil(TILE)) as usize
    }

    /// Pixel coordinates of lane `lane` of tile `tile`, or None past the image edge.
    pub fn lane_pixel(&self, tile: usize, lane: usize) -> Option<(u32, u32)> {
        let (x0, y0) = self.tile_origin(tile);
        let (x, y) = (x0 + lane as u32 % TILE, y0 + lane as u32 / TILE);
        (x < self.width && y < self.height).then_some((x, y))
    }

    /// The pixel coordinates of tile `tile`'s top left pixel (lane 0).
    pub fn tile_origin(&self, tile: usize) -> (u32, u32) {
        let t = tile as u32;
        (t % self.tiles_x * TILE, t / self.tiles_x * TILE)
    }

    pub fn index(&self, x: u32, y: u32) -> usize {
        let tile = (y / TILE) * self.tiles_x + x / TILE;
        (tile * 16 + (y % TILE) * TILE + x % TILE) as usize
    }
}

#[derive(Clone, Debug)]
pub struct Film {
    pub layout: TileLayout,
    /// Sum of samples, tile-major: tile t owns `sum[16 t .. 16 t + 16]`, lane = 4·dy + dx.
    pub sum: Vec<[f64; 3]>,
    /// Per-pixel sum of squared deviations from the running mean (Welford's M2), same order:
    /// the per-pixel sample variance of the one-sample-per-pass estimator is m2 / (spp - 1).
    pub m2: Vec<[f64; 3]>,
    /// Samples per pixel accumulated so far (every pixel gets one per pass).
    pub spp: u64,
}

/// Adds sample `x` as the (n+1)-th to a pixel's running sum and M2 (Welford 1962, written
/// with the sum rather than the mean so the film's sums stay exact sums). The update is
/// M2 += d²·n/(n+1) with d = x − sum/n, a sum of non-negative terms: M2 is never negative,
/// so neither is any variance derived from it (the form M2 += (x − m_old)(x − m_new) can go
/// below zero by rounding when every sample is equal).
#[inline]
pub fn accumulate(sum: &mut [f64; 3], m2: &mut [f64; 3], n: u64, x: [f64; 3]) {
    Accumulation::of_count(n).add(sum, m2, x);
}

/// [`accumulate`] for every pixel that holds `n` samples — all of a film's pixels in one pass —
/// with its two divisions done once for them all, not per pixel (the tile loop with the update
/// went from 5.2 % to 2.5 % of a cornell `light` profile: docs/tracer.md, "The film's update",
/// stop 31). The same values, so the same bits.
#[derive(Clone, Copy, Debug)]
pub struct Accumulation {
    n: u64,
    inv: f64,
    w: f64,
}

impl Accumulation {
    pub fn of_count(n: u64) -> Self {
        // d² ≥ 0 whatever the rounding of the mean, so the reciprocal is safe here; `mean`
        // divides exactly. n = 0 has no mean: `add` stores the sample as the sum.
        let (inv, w) = if n == 0 {
            (0.0, 0.0)
        } else {
            (1.0 / n as f64, n as f64 / (n + 1) as f64)
        };
        Accumulation { n, inv, w }
    }

    /// Adds `x` as the (n+1)-th sample of a pixel's running sum and M2.
    #[inline]
    pub fn add(&self, sum: &mut [f64; 3], m2: &mut [f64; 3], x: [f64; 3]) {
        if self.n == 0 {
            *sum = x;
            return;
        }
        for c in 0..3 {
            let d = x[c] - sum[c] * self.inv;
            m2[c] += d * d * self.w;
            sum[c] += x[c];
        }
    }
}

/// A tile's pixels: what [`Accumulation::add_tile`] updates at once.
pub const TILE_PIXELS: usize = (TILE * TILE) as usize;

impl Accumulation {
    /// [`Self::add`] of a tile's 16 pixels (`sum` and `m2` hold their 16 entries in tile
    /// order) with their new samples `x`, over f64 lanes: the same operations in the same
    /// order, so the same bits on every ISA. The film's update was 4–6 % of a cornell `light`
    /// pass done pixel by pixel (docs/tracer.md, stop 37).
    pub fn add_tile(&self, isa: Isa, sum: &mut [[f64; 3]], m2: &mut [[f64; 3]], x: &[Vec3; 16]) {
        assert!(
            sum.len() == TILE_PIXELS && m2.len() == TILE_PIXELS,
            "a tile of {} and {} pixels",
            sum.len(),
            m2.len()
        );
        let x: [[f32; 3]; TILE_PIXELS] = x.map(|v| v.to_array());
        simd::run(
            isa,
            AddTile {
                acc: self,
                sum: sum.as_flattened_mut(),
                m2: m2.as_flattened_mut(),
                x: x.as_flattened(),
            },
        );
    }
}

/// [`Accumulation::add_tile`]'s kernel: the 48 numbers of 16 pixels as three rows of 16.
struct AddTile<'a> {
    acc: &'a Accumulation,
    sum: &'a mut [f64],
    m2: &'a mut [f64],
    x: &'a [f32],
}

impl Kernel for AddTile<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (inv, w) = (L::D::splat(self.acc.inv), L::D::splat(self.acc.w));
        let rows = self
            .sum
            .chunks_exact_mut(WIDTH)
            .zip(self.m2.chunks_exact_mut(WIDTH))
            .zip(self.x.chunks_exact(WIDTH));
        for ((sum, m2), x) in rows {
            let (sum, m2): (&mut [f64; WIDTH], &mut [f64; WIDTH]) =
                (sum.try_into().unwrap(), m2.try_into().unwrap());
            let x = L::D::from_f32(x.try_into().unwrap());
            if self.acc.n == 0 {
                x.to_f64(sum);
                continue;
            }
            let s = L::D::from_f64(sum);
            let d = x.sub(s.mul(inv));
            L::D::from_f64(m2).add(d.mul(d).mul(w)).to_f64(m2);
            s.add(x).to_f64(sum);
        }
    }
}

impl Film {
    /// Adds another film's samples of the same pixels (Chan, Golub & LeVeque 1979 on each
    /// pixel's sum and M2): exact up to roundoff, in any order.
    pub fn merge(&mut self, other: &Film) {
        let (na, nb) = (self.spp as f64, other.spp as f64);
        let n = na + nb;
        if nb == 0.0 {
            return;
        }
        for k in 0..self.sum.len() {
            for c in 0..3 {
                if na > 0.0 {
                    let d = other.sum[k][c] / nb - self.sum[k][c] / na;
                    self.m2[k][c] += other.m2[k][c] + d * d * na * nb / n;
                } else {
                    self.m2[k][c] = other.m2[k][c];
                }
                self.sum[k][c] += other.sum[k][c];
            }
        }
        self.spp += other.spp;
    }

    pub fn new(width: u32, height: u32) -> Self {
        let layout = TileLayout::new(width, height);
        Film {
            layout,
            sum: vec![[0.0; 3]; layout.tile_count() * 16],
            m2: vec![[0.0; 3]; layout.tile_count() * 16],
            spp: 0,
        }
    }

    /// The mean image in scan-line order.
    pub fn mean(&self) -> Image {
        // sum / n, not sum · (1/n): the rounded reciprocal moves a constant pixel off its value.
        let n = self.spp.max(1) as f64;
        self.scan_lines(&self.sum, |s| s / n)
    }

    /// Per-pixel variance of the mean image (sample variance / spp), in scan-line order: the
    /// expected squared error of each pixel against the converged image. Zero below 2 spp.
    pub fn variance_of_mean(&self) -> Image {
        let n = self.spp as f64;
        let scale = if self.spp < 2 {
            0.0
        } else {
            1.0 / ((n - 1.0) * n)
        };
        self.scan_lines(&self.m2, |m| m * scale)
    }

    /// Mean over pixels and channels of the per-sample variance: σ² of the 1-spp estimator,
    /// so a render of N spp has expected MSE σ²/N against the converged image.
    pub fn mean_sample_variance(&self) -> f64 {
        if self.spp < 2 {
            return 0.0;
        }
        let sum: f64 = self.m2.iter().map(|m| m[0] + m[1] + m[2]).sum();
        sum / (3 * self.layout.width as usize * self.layout.height as usize) as f64
            / (self.spp - 1) as f64
    }

    fn scan_lines(&self, data: &[[f64; 3]], f: impl Fn(f64) -> f64) -> Image {
        let TileLayout { width, height, .. } = self.layout;
        let mut pixels = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for x in 0..width {
                let s = data[self.layout.index(x, y)];
                pixels.push([f(s[0]), f(s[1]), f(s[2])]);
            }
        }
        Image {
            width,
            height,
            pixels,
        }
    }
}

/// An RGB image in scan-line order, f64 per channel: what metrics and outputs consume.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f64; 3]>,
}

impl Image {
    pub fn pixel(&self, x: u32, y: u32) -> Vec3 {
        let p = self.pixels[(y * self.width + x) as usize];
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::Welford;

    /// A tile's update over lanes gives each pixel the bits of [`Accumulation::add`], on every
    /// ISA, for the first sample (which only stores) and later ones, with values from 0 to
    /// 1e6 and a pixel whose mean is far from its sample.
    #[test]
    fn a_tiles_update_is_each_pixels() {
        for n in [0u64, 1, 2, 7, 1000] {
            let acc = Accumulation::of_count(n);
            let x: [Vec3; 16] = std::array::from_fn(|p| {
                let f = p as f32;
                Vec3::new(
                    f * 0.37,
                    1e6 / (f + 1.0),
                    if p == 3 { 0.0 } else { 1.0 / 3.0 + f },
                )
            });
            let start: Vec<[f64; 3]> = (0..16)
                .map(|p| {
                    let f = p as f64;
                    [f * 1.1 * n as f64, 0.3 + f, 7e5 * n as f64]
                })
                .collect();
            let (mut want_sum, mut want_m2) = (start.clone(), vec![[0.25, 0.5, 1.0]; 16]);
            for p in 0..16 {
                let v = x[p];
                acc.add(
                    &mut want_sum[p],
                    &mut want_m2[p],
                    [v.x as f64, v.y as f64, v.z as f64],
                );
            }
            for isa in Isa::available() {
                let (mut sum, mut m2) = (start.clone(), vec![[0.25, 0.5, 1.0]; 16]);
                acc.add_tile(isa, &mut sum, &mut m2, &x);
                let bits = |v: &Vec<[f64; 3]>| -> Vec<u64> {
                    v.as_flattened().iter().map(|f| f.to_bits()).collect()
                };
                assert_eq!(bits(&sum), bits(&want_sum), "n {n} {isa:?}: sums");
                assert_eq!(bits(&m2), bits(&want_m2), "n {n} {isa:?}: M2");
            }
        }
    }

    #[test]
    fn per_pixel_moments_match_welford() {
        let xs = [0.5, 2.0, 1e3, 3.25, 0.0, 7.0];
        let (mut sum, mut m2) = ([0.0; 3], [0.0; 3]);
        let mut w = Welford::default();
        for (n, &x) in xs.iter().enumerate() {
            accumulate(&mut sum, &mut m2, n as u64, [x, 2.0 * x, 0.0]);
            w.add(x);
        }
        assert!((sum[0] / xs.len() as f64 - w.mean).abs() < 1e-12);
        assert!((m2[0] - w.m2()).abs() < 1e-9 * w.m2());
        assert!((m2[1] - 4.0 * w.m2()).abs() < 1e-9 * w.m2());
        assert_eq!(m2[2], 0.0);
    }

    /// Constant samples give a variance of zero or more, never below (the update
    /// (x − m_old)(x − m_new) with rounded reciprocals goes negative on 12.0 repeated 8192
    /// times, as on cornell's emitter, and gave a NaN noise floor); and a pixel whose sum is
    /// exact has exactly its value as the mean (sum / n, not sum · (1/n): 12·49 · (1/49) ≠ 12).
    #[test]
    fn constant_pixels_have_non_negative_variance_and_exact_mean() {
        for &x in &[
            12.0f64,
            17.0,
            0.5,
            1.75,
            0.1,
            1.0 / 3.0,
            1.7,
            123.456,
            1e-30,
        ] {
            let mut film = Film::new(1, 1);
            let i = film.layout.index(0, 0);
            for n in 0..8192u64 {
                let (s, m) = (&mut film.sum[i], &mut film.m2[i]);
                accumulate(s, m, n, [x, x, x]);
                assert!(m.iter().all(|&v| v >= 0.0), "x = {x}, n = {n}: M2 {m:?}");
                // Whole numbers sum exactly in f64 (far below 2^53).
                let exact = x.fract() == 0.0;
                if exact && n < 200 {
                    film.spp = n + 1;
                    assert_eq!(film.mean().pixels[0][0], x, "x = {x}, n = {}", n + 1);
                }
            }
            film.spp = 8192;
            assert!(film.variance_of_mean().pixels[0].iter().all(|&v| v >= 0.0));
            assert!(film.mean_sample_variance() >= 0.0);
        }
    }
}
