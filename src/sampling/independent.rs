//! Independent uniform samples: each (seed, strategy, pixel, index) key seeds its own PCG32
//! stream (O'Neill 2014), whose outputs fill the dimensions in order. Every dimension of every
//! sample is independent of every other, so per-pixel sample variances are variances of i.i.d.
//! draws — the assumption the harness's error predictions make.

use super::generator::{LaneValues, SampleGenerator, SampleKey, SampleKeys, Setup};
use crate::simd::{Isa, Kernel, Lanes, Mask, VectorU64, WIDTH};
use super::stream::{SampleStream, next_1d_lanes};

pub struct Independent;

pub static INDEPENDENT: Independent = Independent;

impl SampleGenerator for Independent {
    fn name(&self) -> &'static str {
        "independent"
    }

    fn describe(&self) -> &'static str {
        "independent uniform numbers, one PCG32 stream per (seed, strategy, pixel, pass)"
    }

    fn independent_samples(&self) -> bool {
        true
    }

    fn fill(&self, _setup: &Setup, key: SampleKey, out: &mut [f32]) {
        let mut s = SampleStream::new(key.seed, key.strategy, key.pixel, key.index);
        for x in out {
            *x = s.next_1d();
        }
    }

    /// The packet's sixteen streams side by side, as 64-bit lanes compiled for the CPU's ISA
    /// (inactive lanes are computed too and their values are unspecified). The same numbers as
    /// [`Self::fill`] (`lanes_fill_as_single_samples`, `every_isa_fills_as_one_stream`).
    fn fill_lanes(
        &self,
        _setup: &Setup,
        keys: &SampleKeys,
        _lanes: Mask,
        dims: usize,
        out: &mut LaneValues,
    ) {
        crate::simd::run(Isa::best(), FillLanes { keys, dims, out });
    }
}

/// [`Independent::fill_lanes`]'s streams over the lane layer's u64 lanes, in the ISA's context.
struct FillLanes<'a> {
    keys: &'a SampleKeys,
    dims: usize,
    out: &'a mut LaneValues,
}

impl Kernel for FillLanes<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (load, k) = (L::U::load, self.keys);
        // What the lanes share is hashed once: the (seed, strategy) of a render's packets,
        // and the pixel too in a packet of one pixel's samples (passes in groups). (An or of
        // xors, not `all`: no early exit, so it vectorises.)
        let differ = |row: &[u64; WIDTH]| row.iter().fold(0, |a, &x| a | (x ^ row[0])) != 0;
        let stream = if differ(&k.seed) || differ(&k.strategy) {
            let base = SampleStream::base_lanes(load(&k.seed), load(&k.strategy));
            SampleStream::stream_word(base, load(&k.pixel))
        } else {
            let base = SampleStream::base(k.seed[0], k.strategy[0]);
            if differ(&k.pixel) {
                SampleStream::stream_word(L::U::splat(base), load(&k.pixel))
            } else {
                L::U::splat(SampleStream::stream_word(base, k.pixel[0]))
            }
        };
        let (mut state, increment) = SampleStream::streamed_lanes(stream, load(&k.index));
        for d in self.out.iter_mut().take(self.dims) {
            next_1d_lanes::<L::V, L::U>(&mut state, increment, d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Layout;

    /// The values a fixed key gives: the independent generator (and so every default render)
    /// stays bit-identical to what it was (pinned anew at stop 43, when the streams' seeding
    /// changed).
    #[test]
    fn pinned_values_are_unchanged() {
        let key = SampleKey {
            seed: 7,
            strategy: crate::sampling::stream::name_id("light"),
            pixel: 12,
            index: 3,
        };
        let mut out = [0.0f32; 6];
        INDEPENDENT.fill(&Setup::point(Layout::default(), None), key, &mut out);
        let bits: Vec<u32> = out.iter().map(|x| x.to_bits()).collect();
        assert_eq!(bits, PINNED, "{out:?}");
    }

    /// Computed by this generator at stop 43 (`SampleStream::key_words` and `Pcg32::new`).
    const PINNED: [u32; 6] = [
        1036713024, 1053072706, 1060797818, 1064916236, 1056848086, 1036926856,
    ];
}

#[cfg(test)]
mod lane_tests {
    use super::*;
    use crate::sampling::Layout;
    use crate::sampling::generator::{MAX_DIMENSIONS, set_lane};

    /// Every ISA's build of the packet fill gives the numbers of one stream at a time, for
    /// lanes of one render (their (seed, strategy) hashed once), of one pixel too (its stream
    /// word hashed once), and where one lane differs in seed, strategy or pixel (hashed lane
    /// by lane): integer lanes, so nothing may differ.
    #[test]
    fn every_isa_fills_as_one_stream() {
        let setup = Setup::point(Layout::default(), None);
        let dims = 11;
        // (seed, strategy, pixel) of lane i.
        type Family = fn(u64) -> (u64, u64, u64);
        let families: [Family; 5] = [
            |i| (9, 0x5eed, i * 1_000_003),
            |_| (9, 0x5eed, 77),
            |i| (9, 0x5eed + (i % 3), i * 1_000_003),
            |i| (if i == 13 { 10 } else { 9 }, 0x5eed, 77),
            |i| (9, 0x5eed, if i == 13 { 78 } else { 77 }),
        ];
        for family in families {
            let keys: [SampleKey; WIDTH] = std::array::from_fn(|i| SampleKey {
                seed: family(i as u64).0,
                strategy: family(i as u64).1,
                pixel: family(i as u64).2,
                index: u64::MAX - i as u64,
            });
            let mut want = [[0.0f32; WIDTH]; MAX_DIMENSIONS];
            for (lane, k) in keys.iter().enumerate() {
                let mut row = [0.0f32; MAX_DIMENSIONS];
                INDEPENDENT.fill(&setup, *k, &mut row[..dims]);
                set_lane(&mut want, lane, &row[..dims]);
            }
            for isa in Isa::available() {
                let mut got = [[0.0f32; WIDTH]; MAX_DIMENSIONS];
                crate::simd::run(
                    isa,
                    FillLanes {
                        keys: &SampleKeys::of(&keys),
                        dims,
                        out: &mut got,
                    },
                );
                let bits = |a: LaneValues| a.map(|r| r.map(f32::to_bits));
                assert_eq!(bits(got), bits(want), "{isa:?} {:?}", keys[13]);
            }
        }
    }
}
