//! Hierarchical sample warping (Clarberg et al., "Wavelet Importance Sampling", SIGGRAPH 2005;
//! McCool & Harwood 1997): a mip pyramid of texel-weight sums per square tile, descended from
//! the root by splitting the unit square at each 2×2 node — first left/right by the column
//! sums with u₀, then top/bottom within the chosen column with u₁ — and rescaling u into the
//! chosen half. The leaf's texel is chosen with probability weight/total, exactly as the
//! marginal/conditional method, but neighbouring u land in neighbouring texels, so
//! stratification of u carries over. An atlas of several tiles (cube faces, HEALPix base
//! pixels, the two halves of a lat/long map) first picks a tile by its sum with u₀.
//!
//! In f32 and written once over lanes (`simd::Vector`, `f32` being one lane), as Mitsuba 3's
//! `Hierarchical2D` is f32 and templated over its value type: a sample over lanes is the
//! scalar one bit for bit. f32 costs nothing in what the sample can resolve: u is f32 on the
//! way in, and each level's split spends its bits either way. The texel's probability is the
//! product of the f32 splits, w/Σw to within a few ulps per level; the pdf the map states is
//! w/Σw of the texel the point lands in, which is what the χ² tests hold the samples to.

use super::{RecordLine, record_table};
use crate::sampling::stream::ONE_MINUS_EPSILON;
use crate::simd::Vector;

#[derive(Clone, Debug)]
pub struct HierarchicalWarp {
    /// Tile side (a power of two).
    n: usize,
    /// Cumulative tile sums, starting at 0 (tiles + 1 entries, non-decreasing).
    tile_cdf: Vec<f32>,
    /// Per tile, the levels of side 2, 4, …, n, coarsest first, each as the 2×2 quads of its
    /// parent level's nodes, a quad's texels as (x, y) = (0, 0), (1, 0), (0, 1), (1, 1). A
    /// level's quads are in Morton (Z) order, so the quads of a node's four children are
    /// one 64-byte line: a descent step reads one quad, and the line of the next step's
    /// quad is known (and prefetched) before the step's splits are computed. Each level
    /// starts on a line; tile t's levels start at line t·`block`.
    pyramid: Vec<RecordLine>,
    /// Lines per tile.
    block: usize,
}

/// The chosen atlas texels of N lanes, (column, row) as whole numbers in f32 (exact: see
/// [`HierarchicalWarp::new`]), and the offsets (du, dv) ∈ [0, 1)² inside them.
pub struct WarpLanes<V> {
    pub col: V,
    pub row: V,
    pub du: V,
    pub dv: V,
}

/// The most texels an atlas may have: the descent's indices are whole numbers in f32, exact
/// up to 2²⁴.
const EXACT_F32: usize = 1 << 24;

impl HierarchicalWarp {
    /// `weights` is the atlas (tiles·n wide, n high, row-major), non-negative; None when all
    /// are zero. Sums are formed in f64 and rounded once to f32, so a node is positive exactly
    /// when a texel under it is.
    pub fn new(weights: &[f32], tiles: usize, n: usize) -> Option<Self> {
        assert!(
            n.is_power_of_two(),
            "hierarchical warping needs a power-of-two tile"
        );
        // The descent does its index arithmetic in f32 lanes: quad numbers (below 4·block per
        // tile, at most n² for n ≥ 2) and texel numbers, both below the atlas's texel count.
        // The default atlases have at most 12·128² texels (HEALPix); the χ² command's `tile`
        // parameter allows sides up to 512, 12·512² ≈ 3.1 M: all below 2²⁴.
        assert!(
            tiles * n * n <= EXACT_F32,
            "hierarchical warping: an atlas of {tiles} tiles of side {n} is past f32's whole numbers"
        );
        let width = tiles * n;
        // One line for the root's quad (padded), then a quarter of each level's quads.
        let block = if n > 1 { 1 + (n * n / 4 - 1) / 3 } else { 0 };
        let mut pyramid = Vec::with_capacity(tiles * block);
        let mut tile_cdf = vec![0.0f32];
        let mut running = 0.0f64;
        for t in 0..tiles {
            // Finest first, in f64; then stored coarsest first.
            let mut finest = vec![0.0f64; n * n];
            for y in 0..n {
                for x in 0..n {
                    finest[y * n + x] = weights[y * width + t * n + x] as f64;
                }
            }
            let mut levels = vec![finest];
            let mut s = n;
            while s > 1 {
                let fine = levels.last().unwrap();
                let h = s / 2;
                let coarse: Vec<f64> = (0..h * h)
                    .map(|k| {
                        let (x, y) = (2 * (k % h), 2 * (k / h));
                        fine[y * s + x]
                            + fine[y * s + x + 1]
                            + fine[(y + 1) * s + x]
                            + fine[(y + 1) * s + x + 1]
                    })
                    .collect();
                levels.push(coarse);
                s = h;
            }
            running += levels.last().unwrap()[0];
            tile_cdf.push(running as f32);
            for level in levels.iter().rev().skip(1) {
                pyramid.extend(quads(level));
            }
        }
        (running > 0.0).then_some(HierarchicalWarp {
            n,
            tile_cdf,
            pyramid,
            block,
        })
    }

    /// (column, row) of the chosen atlas texel and the offsets (du, dv) ∈ [0, 1)² inside it.
    pub fn sample(&self, u: [f32; 2]) -> ((usize, usize), [f32; 2]) {
        let s = self.sample_lanes::<f32, 1>(u[0], u[1], |_, _| {});
        ((s.col as usize, s.row as usize), [s.du, s.dv])
    }

    /// [`Self::sample`] of N lanes at once, the same operations in the same order. Indices
    /// are whole numbers in f32 lanes (exact below 2²⁴, which `new` checks), so a level's step
    /// is a few vector operations; only the quads' addresses leave the lanes.
    /// `before_last_level` sees, before the last level's splits, the atlas (column, row) of
    /// each lane's 2×2 block of texels (both even), one of which the last level chooses: time
    /// to fetch what the caller will read of them. A tile of side 1 has no levels, and no call.
    #[inline(always)]
    pub fn sample_lanes<V: Vector<N>, const N: usize>(
        &self,
        u0: V,
        u1: V,
        mut before_last_level: impl FnMut(V, V),
    ) -> WarpLanes<V> {
        let (mut u0, mut u1) = (u0, u1);
        let tiles = self.tile_cdf.len() - 1;
        let (zero, one) = (V::splat(0.0), V::splat(1.0));
        let mut tile = zero;
        if tiles > 1 {
            // The tile whose cumulative interval holds u₀·total: tile_cdf[t] ≤ target <
            // tile_cdf[t + 1], so its width is positive (u₀ < 1 makes target < total). The
            // sums passed are a prefix of the sorted list: lo is the last of them, hi the
            // first sum not passed.
            let total = self.tile_cdf[tiles];
            let target = u0.mul(V::splat(total));
            let (mut lo, mut hi) = (zero, V::splat(total));
            for &c in &self.tile_cdf[1..tiles] {
                let c = V::splat(c);
                tile = tile.add(c.le_select(target, one, zero));
                lo = c.le_select(target, c, lo);
            }
            for &c in self.tile_cdf[1..tiles].iter().rev() {
                hi = V::splat(c).le_select(target, hi, V::splat(c));
            }
            u0 = target
                .sub(lo)
                .div(hi.sub(lo))
                .min(V::splat(ONE_MINUS_EPSILON));
        }
        // Quad q of the pyramid is quad q % 4 of line q / 4. `m` is the Morton index of the
        // node whose quad this step reads, among the nodes of side `half` (the parent
        // level's); `line` is its level's first line, so the quad is `q` = 4·(tile's first
        // line + line) + m. Its children's quads are `children` + (0…3), one line: their
        // address is known before this step's splits, and only the last add waits for them.
        let first = tile.mul(V::splat((4 * self.block) as f32));
        let (two, three, four) = (V::splat(2.0), V::splat(3.0), V::splat(4.0));
        let (mut x, mut y, mut m, mut q) = (zero, zero, zero, first);
        let (mut half, mut line) = (1usize, 0usize);
        let mut at = [0u32; N];
        while half < self.n {
            // The next level's line for this node's children (whichever the splits choose).
            let next = line + (half * half).div_ceil(4);
            let children = first.add(V::splat((4 * next) as f32)).add(m.mul(four));
            if 2 * half < self.n {
                children.trunc_u32(&mut at);
                for &c in &at {
                    crate::simd::prefetch(self.pyramid.as_ptr().wrapping_add(c as usize / 4));
                }
            }
            q.trunc_u32(&mut at);
            if 2 * half == self.n {
                before_last_level(
                    x.add(tile.mul(V::splat((self.n / 2) as f32))).mul(two),
                    y.mul(two),
                );
            }
            let [c00, c10, c01, c11] = gather::<V, N>(&self.pyramid, &at);
            let (left, right) = (c00.add(c01), c10.add(c11));
            let px = first_half(left, right);
            // Both columns' top/bottom splits, the chosen one picked after: they do not wait
            // for px (a division shorter per level's chain of dependent steps), and the chosen
            // one is the same division of the same sums as splitting the chosen column alone.
            let py = u0.lt_select(px, of_column(c00, left), of_column(c10, right));
            // The left column where u₀ < px, the top row where u₁ < py (as `rescale` chooses);
            // `off` is the chosen child's place in its quad, (0, 1, 2, 3) = (x, y) in
            // (0, 0), (1, 0), (0, 1), (1, 1).
            let (r, d) = (u0.lt_select(px, zero, one), u1.lt_select(py, zero, one));
            let off = u1.lt_select(py, r, u0.lt_select(px, two, three));
            (u0, u1) = (rescale(u0, px), rescale(u1, py));
            x = x.add(x).add(r);
            y = y.add(y).add(d);
            m = m.mul(four).add(off);
            q = children.add(off);
            line = next;
            half *= 2;
        }
        WarpLanes {
            col: x.add(tile.mul(V::splat(self.n as f32))),
            row: y,
            du: u0,
            dv: u1,
        }
    }
}

/// Lane i's quad `q[i]` (quad q % 4 of line q / 4, so quad q of the lines read as one flat
/// table), as four vectors, one per texel of the quad ([`Vector::load_records_at`]: each quad
/// read whole, transposed in registers).
#[inline(always)]
fn gather<V: Vector<N>, const N: usize>(lines: &[RecordLine], q: &[u32; N]) -> [V; 4] {
    V::load_records_at(record_table(lines), q)
}

/// A level of side s (row-major, f64 sums) as the 2×2 quads of its parent level's nodes, in
/// f32, the parent nodes in Morton order (bits of x at even positions, of y at odd ones),
/// four quads to a line (the last line padded).
fn quads(level: &[f64]) -> Vec<RecordLine> {
    let s = level.len().isqrt();
    let h = s / 2;
    let mut lines = vec![RecordLine::default(); (h * h).div_ceil(4)];
    for py in 0..h {
        for px in 0..h {
            let (x, y, m) = (2 * px, 2 * py, morton(px, py));
            lines[m / 4].0[m % 4] = [
                level[y * s + x] as f32,
                level[y * s + x + 1] as f32,
                level[(y + 1) * s + x] as f32,
                level[(y + 1) * s + x + 1] as f32,
            ];
        }
    }
    lines
}

/// The Morton index of (x, y): bit b of x at bit 2b, bit b of y at bit 2b + 1.
fn morton(x: usize, y: usize) -> usize {
    let mut m = 0;
    for b in 0..usize::BITS as usize / 2 {
        m |= (x >> b & 1) << (2 * b) | (y >> b & 1) << (2 * b + 1);
    }
    m
}

/// Per lane, the probability p = a/(a + b) of the first half of a node of positive sum
/// a + b (the only nodes a descent splits).
#[inline(always)]
fn first_half<V: Vector<N>, const N: usize>(a: V, b: V) -> V {
    a.div(a.add(b))
}

/// The probability c/column of a column's top texel, where `column` is its sum: as
/// [`first_half`] (c, column − c) for a column of positive sum. A column of zero sum is
/// never chosen, and its lanes divide 0 by 1, not by 0: the pair is split before the column
/// is, and no lane's value is NaN.
#[inline(always)]
fn of_column<V: Vector<N>, const N: usize>(c: V, column: V) -> V {
    let one = V::splat(1.0);
    c.div(column.le_select(V::splat(0.0), one, column))
}

/// u rescaled into the half a split by p chooses: [0, p) → [0, 1) where u < p, [p, 1) →
/// [0, 1) otherwise. The divisor is never zero: the first half is chosen only when u < p, so
/// p > 0; the second only when u ≥ p, and p rounds to 1 when the second half's sum is 0 (a/a)
/// or below about 2⁻²⁴ of the first's, which no u < 1 reaches, so 1 − p > 0.
#[inline(always)]
fn rescale<V: Vector<N>, const N: usize>(u: V, p: V) -> V {
    let num = u.lt_select(p, u, u.sub(p));
    let den = u.lt_select(p, p, V::splat(1.0).sub(p));
    num.div(den).min(V::splat(ONE_MINUS_EPSILON))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::SampleStream;
    use crate::simd::{Isa, Kernel, Lanes, WIDTH};

    fn atlas(tiles: usize, n: usize) -> Vec<f32> {
        // Varied weights, a black quadrant in tile 0 and one black tile where there are three.
        (0..tiles * n * n)
            .map(|k| {
                let (x, y) = (k % (tiles * n), k / (tiles * n));
                let t = x / n;
                if (t == 0 && x < n / 2 && y < n / 2) || (tiles == 3 && t == 1) {
                    0.0
                } else {
                    1.0 + ((x * 7 + y * 13) % 17) as f32 * if x == 3 { 1e4 } else { 1.0 }
                }
            })
            .collect()
    }

    /// Where the frequencies with which `warp` chooses texels leave weight/Σweight (a 5σ
    /// binomial bound per texel), or chooses a black texel, or an offset leaves [0, 1).
    fn frequency_mismatch(warp: &HierarchicalWarp, w: &[f32]) -> Option<String> {
        let total: f64 = w.iter().map(|&x| x as f64).sum();
        let width = w.len() / warp.n;
        let mut counts = vec![0u64; w.len()];
        let mut rng = SampleStream::new(3, 1, 4, 1);
        let draws = 400_000;
        for _ in 0..draws {
            let ((c, r), [du, dv]) = warp.sample(rng.next_2d());
            if !((0.0..1.0).contains(&du) && (0.0..1.0).contains(&dv)) {
                return Some(format!("offsets ({du}, {dv})"));
            }
            counts[r * width + c] += 1;
        }
        counts.iter().enumerate().find_map(|(k, &c)| {
            let p = w[k] as f64 / total;
            let (mean, sd) = (p * draws as f64, (p * (1.0 - p) * draws as f64).sqrt());
            ((c as f64 - mean).abs() > 5.0 * sd + 1e-9)
                .then(|| format!("texel {k}: {c} against {mean:.1} ± {sd:.1}"))
        })
    }

    /// Texels are chosen by weight, black ones never, with offsets in [0, 1). Five tiles of
    /// different sums: a tile choice that took the last unpassed sum for the interval's end,
    /// not the first, passes with two tiles and with three whose middle one is black.
    #[test]
    fn texels_are_chosen_by_weight() {
        for (tiles, n) in [(1, 8), (2, 8), (3, 4), (5, 4), (4, 2), (3, 1)] {
            let w = atlas(tiles, n);
            let warp = HierarchicalWarp::new(&w, tiles, n).unwrap();
            assert_eq!(frequency_mismatch(&warp, &w), None, "tiles {tiles} n {n}");
        }
    }

    /// Controls for the test above: splits taken the wrong way round (every level mirrored
    /// left-right, the same as choosing the first half with probability b/(a + b)), and a
    /// tile choice off by one tile's sum, are caught.
    #[test]
    fn a_wrong_split_or_tile_choice_is_caught() {
        let (tiles, n) = (2, 4);
        let w = atlas(tiles, n);
        let warp = HierarchicalWarp::new(&w, tiles, n).unwrap();
        // Every level mirrored left-right within each tile: the warp of the mirrored atlas.
        let width = tiles * n;
        let flipped: Vec<f32> = (0..w.len())
            .map(|k| {
                let (x, y) = (k % width, k / width);
                let (t, xt) = (x / n, x % n);
                w[y * width + t * n + (n - 1 - xt)]
            })
            .collect();
        let mirrored = HierarchicalWarp::new(&flipped, tiles, n).unwrap();
        assert!(frequency_mismatch(&mirrored, &w).is_some());
        let mut tile_off = warp.clone();
        tile_off.tile_cdf[1] *= 0.9;
        assert!(frequency_mismatch(&tile_off, &w).is_some());
    }

    /// `atlas` with its even texel columns black: every quad of the finest level has a black
    /// left column.
    fn striped(tiles: usize, n: usize) -> Vec<f32> {
        atlas(tiles, n)
            .iter()
            .enumerate()
            .map(|(k, &x)| if k % 2 == 0 { 0.0 } else { x })
            .collect()
    }

    /// Where a 2×2 node has a black column (every quad of the finest level here), the texels
    /// are still chosen by weight, and the black column's top/bottom probability, computed
    /// beside the other column's and not chosen, is 0, not 0/0 (`of_column` dividing by the
    /// column's sum as it is fails the second assertion: NaN; the samples cannot show it, as
    /// the unchosen value is selected away bit for bit). Over lanes, on every ISA, the
    /// striped atlas is in `lanes_are_the_scalar_samples_on_every_isa`.
    #[test]
    fn a_black_column_splits_without_nan() {
        let (tiles, n) = (1, 8);
        let w = striped(tiles, n);
        let warp = HierarchicalWarp::new(&w, tiles, n).unwrap();
        assert_eq!(frequency_mismatch(&warp, &w), None);
        assert_eq!(of_column::<f32, 1>(0.0, 0.0), 0.0);
        assert_eq!(
            of_column::<f32, 1>(1.0, 4.0),
            first_half::<f32, 1>(1.0, 3.0)
        );
    }

    struct Lanes16<'a>(&'a HierarchicalWarp, [f32; WIDTH], [f32; WIDTH]);

    impl Kernel for Lanes16<'_> {
        /// (column, row, du, dv) of each lane, and the (column, row) `before_last_level` saw
        /// (None when it was not called; a second call fails).
        type Out = ([[f32; WIDTH]; 4], Option<[[f32; WIDTH]; 2]>);
        #[inline(always)]
        fn run<L: Lanes>(self) -> Self::Out {
            let mut block = None;
            let s = self.0.sample_lanes::<L::V, WIDTH>(
                L::V::load(&self.1),
                L::V::load(&self.2),
                |col, row| {
                    let mut b = [[0.0; WIDTH]; 2];
                    col.store(&mut b[0]);
                    row.store(&mut b[1]);
                    assert!(block.replace(b).is_none(), "called twice");
                },
            );
            let mut out = [[0.0; WIDTH]; 4];
            for (v, o) in [s.col, s.row, s.du, s.dv].into_iter().zip(&mut out) {
                v.store(o);
            }
            (out, block)
        }
    }

    /// `before_last_level` sees each lane's 2×2 block of texels, the chosen texel's column
    /// and row with their lowest bit cleared, on every ISA; a tile of side 1 (no levels) makes
    /// no call. Control: the samples include texels whose block differs from the level
    /// above's (column or row with bit 1 set), so a callback handed that block fails.
    #[test]
    fn the_last_levels_block_holds_the_chosen_texel() {
        let block_of = |c: usize, r: usize, bits: usize| [(c >> bits << bits), (r >> bits << bits)];
        let mut discriminating = 0;
        for (tiles, n) in [(1, 8), (2, 16), (12, 8), (4, 2), (3, 1)] {
            let warp = HierarchicalWarp::new(&atlas(tiles, n), tiles, n).unwrap();
            let mut rng = SampleStream::new(2, 7, 1, 8);
            for _ in 0..50 {
                let u: [[f32; WIDTH]; 2] = {
                    let pairs: [[f32; 2]; WIDTH] = std::array::from_fn(|_| rng.next_2d());
                    [pairs.map(|p| p[0]), pairs.map(|p| p[1])]
                };
                for isa in Isa::available() {
                    let ([col, row, _, _], block) =
                        crate::simd::run(isa, Lanes16(&warp, u[0], u[1]));
                    let Some([bc, br]) = block else {
                        assert_eq!(n, 1, "{isa:?} tiles {tiles} n {n}: no call");
                        continue;
                    };
                    assert!(n > 1, "{isa:?} tiles {tiles}: a call without levels");
                    for lane in 0..WIDTH {
                        let (c, r) = (col[lane] as usize, row[lane] as usize);
                        let got = [bc[lane] as usize, br[lane] as usize];
                        assert_eq!(got, block_of(c, r, 1), "{isa:?} tiles {tiles} n {n}");
                        discriminating += (block_of(c, r, 2) != got) as usize;
                    }
                }
            }
        }
        assert!(
            discriminating > 100,
            "{discriminating} lanes tell the levels apart"
        );
    }

    /// Sixteen lanes at once are the scalar samples, bit for bit, on every ISA, with u at 0,
    /// just below 1 and on the tiles' and texels' boundaries among them, also where nodes have
    /// a black column (`striped`).
    #[test]
    fn lanes_are_the_scalar_samples_on_every_isa() {
        let cases = [(1, 8), (2, 16), (3, 4), (12, 8)]
            .into_iter()
            .flat_map(|(tiles, n)| [(tiles, n, atlas(tiles, n)), (tiles, n, striped(tiles, n))]);
        for (tiles, n, w) in cases {
            let warp = HierarchicalWarp::new(&w, tiles, n).unwrap();
            let mut rng = SampleStream::new(9, 2, 6, 5);
            let special = [0.0, ONE_MINUS_EPSILON, 0.5, 0.25, 1.0 / 3.0, 0.75];
            for round in 0..200 {
                let mut u = [[0.0f32; WIDTH]; 2];
                for lane in 0..WIDTH {
                    let v = rng.next_2d();
                    u[0][lane] = if round % 4 == 0 {
                        special[lane % 6]
                    } else {
                        v[0]
                    };
                    u[1][lane] = if round % 5 == 0 {
                        special[(lane + 2) % 6]
                    } else {
                        v[1]
                    };
                }
                for isa in Isa::available() {
                    let ([col, row, du, dv], _) = crate::simd::run(isa, Lanes16(&warp, u[0], u[1]));
                    for lane in 0..WIDTH {
                        let ((c, r), [a, b]) = warp.sample([u[0][lane], u[1][lane]]);
                        assert_eq!(
                            (
                                col[lane].to_bits(),
                                row[lane].to_bits(),
                                du[lane].to_bits(),
                                dv[lane].to_bits()
                            ),
                            (
                                (c as f32).to_bits(),
                                (r as f32).to_bits(),
                                a.to_bits(),
                                b.to_bits()
                            ),
                            "{isa:?} tiles {tiles} n {n} lane {lane}"
                        );
                    }
                }
            }
        }
    }
}
