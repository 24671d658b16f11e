//! Sample generators: where the uniform numbers of one sample come from (pbrt-v4's `Sampler`,
//! reduced to what an equal-time harness needs). A sample is a point u ∈ [0,1)^d whose
//! dimensions have fixed meanings: the camera's two first (the position in the pixel), then
//! the strategy's, in the order of its [`Layout`]. A generator fills the whole point at once
//! from its [`SampleKey`], so the renderer calls it once per pixel and pass, and a strategy reads
//! its dimensions in order through [`Dims`].

use crate::simd::{Mask, WIDTH};

/// Every sample's identity: one generator output per (seed, strategy, pixel, sample index),
/// so an image depends on the seed and never on thread scheduling or tile order. Pass k of a
/// render is sample index k of each pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SampleKey {
    pub seed: u64,
    /// A stable id of the strategy (`stream::name_id` of its name): two strategies never
    /// share numbers, whatever their order in the registry.
    pub strategy: u64,
    /// Scan-line pixel index y·width + x; `u64::MAX` for a sample not tied to a pixel (a
    /// single shading point, as the closed-form checks use).
    pub pixel: u64,
    pub index: u64,
}

/// A packet's sample keys as rows, one lane per sample: what [`SampleGenerator::fill_lanes`]
/// reads. Rows, not 16 [`SampleKey`]s, so a generator loads each field of all lanes as one
/// vector, and the renderer writes the pixels and passes it computed over lanes as rows:
/// building 16 keys and splitting them into rows again was 7–8 % of a sphere_light `light`
/// pass (docs/tracer.md, stop 44).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleKeys {
    pub seed: [u64; WIDTH],
    pub strategy: [u64; WIDTH],
    pub pixel: [u64; WIDTH],
    pub index: [u64; WIDTH],
}

impl SampleKeys {
    /// One render's lanes: its seed and strategy in every lane, with each lane's pixel and
    /// sample index.
    #[inline]
    pub fn of_render(seed: u64, strategy: u64, pixel: [u64; WIDTH], index: [u64; WIDTH]) -> Self {
        SampleKeys {
            seed: [seed; WIDTH],
            strategy: [strategy; WIDTH],
            pixel,
            index,
        }
    }

    /// Sixteen keys as rows.
    pub fn of(keys: &[SampleKey; WIDTH]) -> Self {
        SampleKeys {
            seed: keys.map(|k| k.seed),
            strategy: keys.map(|k| k.strategy),
            pixel: keys.map(|k| k.pixel),
            index: keys.map(|k| k.index),
        }
    }

    /// Lane `lane`'s key.
    #[inline]
    pub fn key(&self, lane: usize) -> SampleKey {
        SampleKey {
            seed: self.seed[lane],
            strategy: self.strategy[lane],
            pixel: self.pixel[lane],
            index: self.index[lane],
        }
    }
}

/// The most dimensions one sample may have (camera included); a strategy declaring more is
/// refused when it is bound to a scene.
pub const MAX_DIMENSIONS: usize = 32;

/// A packet's samples, dimension-major: `values[d][lane]` is dimension d of the lane's
/// sample, so a generator that computes 16 lanes at once stores each dimension as one vector
/// (lane-major rows cost 16 scattered stores per dimension: 2–3 % of a cornell `light`
/// profile, docs/tracer.md, stop 36). [`Dims::lane`] reads one lane's dimensions.
pub type LaneValues = [[f32; WIDTH]; MAX_DIMENSIONS];

/// Stores one sample's dimensions `values` (in order, from dimension 0) as lane `lane` of a
/// packet's dimension-major values.
pub fn set_lane(out: &mut LaneValues, lane: usize, values: &[f32]) {
    for (row, &v) in out.iter_mut().zip(values) {
        row[lane] = v;
    }
}

/// What a generator knows about the render it serves, fixed for the whole render: the full
/// layout (the camera's pair first, then the strategy's), the sample count per pixel when it
/// is known up front (a fixed `--spp`; None under a time budget), and the image size (a
/// single point, as the closed-form checks use, is a 1×1 image). Built once per render by the
/// renderer; a generator reads what it needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Setup {
    pub layout: Layout,
    pub spp: Option<u64>,
    pub width: u32,
    pub height: u32,
}

impl Setup {
    /// A render of `width`×`height` pixels with `strategy` (its layout after the camera's).
    pub fn image(strategy: Layout, spp: Option<u64>, width: u32, height: u32) -> Self {
        Setup {
            layout: Layout::camera().then(strategy),
            spp,
            width,
            height,
        }
    }

    /// Samples at one shading point (no camera dimensions, no pixel).
    pub fn point(strategy: Layout, spp: Option<u64>) -> Self {
        Setup {
            layout: strategy,
            spp,
            width: 1,
            height: 1,
        }
    }
}

pub trait SampleGenerator: Send + Sync {
    /// The name `--sampler` takes and result tables show.
    fn name(&self) -> &'static str;
    fn describe(&self) -> &'static str;
    /// Whether the samples of a pixel are independent draws (then the per-pixel variance
    /// across passes estimates the variance of the mean, and `predicted_rmse` applies). False
    /// by default: a stratified or low-discrepancy generator leaves those numbers out.
    fn independent_samples(&self) -> bool {
        false
    }
    /// Whether this generator can serve `setup`; Err says why (e.g. stratification needs
    /// `setup.spp`). The renderer calls it once, before any sample.
    fn check(&self, _setup: &Setup) -> Result<(), String> {
        Ok(())
    }
    /// Writes dimensions 0..out.len() of sample `key`, each in [0, 1); `out.len()` is at most
    /// `setup.layout.len()`. Must depend on (setup, key) alone.
    fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]);

    /// One packet's samples at once: `out[d][i]` for d < `dims` = dimension d of
    /// [`Self::fill`] of `keys.key(i)`, for every lane i whose bit is set in `lanes` (other
    /// lanes' values are unspecified). The default fills lane by lane; a generator whose lanes
    /// can be computed side by side overrides it, and must give the same numbers (the
    /// `lanes_fill_as_single_samples` test).
    fn fill_lanes(
        &self,
        setup: &Setup,
        keys: &SampleKeys,
        lanes: Mask,
        dims: usize,
        out: &mut LaneValues,
    ) {
        let mut row = [0.0f32; MAX_DIMENSIONS];
        for lane in 0..WIDTH {
            if lanes & (1 << lane) != 0 {
                self.fill(setup, keys.key(lane), &mut row[..dims]);
                set_lane(out, lane, &row[..dims]);
            }
        }
    }
}

/// One group of dimensions of a layout: one number, or a 2-D pair that a stratifying
/// generator should stratify jointly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dimension {
    /// What the dimensions feed, for documentation and tests (e.g. "light point").
    pub purpose: &'static str,
    /// 1 or 2.
    pub width: usize,
}

/// Which dimension feeds what, in the order a strategy reads them.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Layout(pub Vec<Dimension>);

impl Layout {
    /// The camera's position in the pixel: dimensions 0 and 1 of every rendered sample.
    pub fn camera() -> Self {
        Layout(vec![Dimension::pair("pixel position")])
    }

    pub fn of(dims: &[Dimension]) -> Self {
        Layout(dims.to_vec())
    }

    /// This layout followed by `other`.
    pub fn then(mut self, other: Layout) -> Self {
        self.0.extend(other.0);
        self
    }

    /// Number of dimensions (a pair counts two).
    pub fn len(&self) -> usize {
        self.0.iter().map(|d| d.width).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The dimension index where each group starts, with the group.
    pub fn offsets(&self) -> impl Iterator<Item = (usize, &Dimension)> {
        self.0.iter().scan(0, |at, d| {
            let start = *at;
            *at += d.width;
            Some((start, d))
        })
    }

    /// `purpose: a..b` for each group, for listings and errors.
    pub fn describe(&self) -> String {
        self.offsets()
            .map(|(s, d)| match d.width {
                1 => format!("{s}: {}", d.purpose),
                w => format!("{s}..{}: {}", s + w, d.purpose),
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl Dimension {
    pub const fn one(purpose: &'static str) -> Self {
        Dimension { purpose, width: 1 }
    }

    pub const fn pair(purpose: &'static str) -> Self {
        Dimension { purpose, width: 2 }
    }
}

/// One sample's dimensions, read in layout order. Reading past the end is a strategy whose
/// `layout()` undercounts what it draws: a programming error, reported by name.
#[derive(Debug)]
pub struct Dims<'a> {
    /// Dimension k is `values[k * stride]`, for k < `len`.
    values: &'a [f32],
    stride: usize,
    len: usize,
    next: usize,
}

impl<'a> Dims<'a> {
    /// The dimensions of one sample stored in order.
    pub fn new(values: &'a [f32]) -> Self {
        Dims {
            values,
            stride: 1,
            len: values.len(),
            next: 0,
        }
    }

    /// Dimensions `from..to` of lane `lane` of a packet's samples.
    pub fn lane(values: &'a LaneValues, lane: usize, from: usize, to: usize) -> Self {
        assert!(
            lane < WIDTH && from <= to && to <= MAX_DIMENSIONS,
            "lane {lane}, dimensions {from}..{to} of a packet"
        );
        Dims {
            values: &values.as_flattened()[from * WIDTH + lane..],
            stride: WIDTH,
            len: to - from,
            next: 0,
        }
    }

    /// The next `N` dimensions.
    pub fn get<const N: usize>(&mut self) -> [f32; N] {
        if self.next + N > self.len {
            panic!(
                "a strategy read dimensions {}..{} of a sample laid out with {}: its layout() must declare every dimension it draws",
                self.next,
                self.next + N,
                self.len
            );
        }
        let (values, stride, next) = (self.values, self.stride, self.next);
        self.next += N;
        std::array::from_fn(|k| values[(next + k) * stride])
    }

    pub fn get_1d(&mut self) -> f32 {
        self.get::<1>()[0]
    }

    pub fn get_2d(&mut self) -> [f32; 2] {
        self.get()
    }

    pub fn get_3d(&mut self) -> [f32; 3] {
        self.get()
    }

    /// How many dimensions have been read.
    pub fn used(&self) -> usize {
        self.next
    }

    /// The dimensions not read yet (for a strategy that hands them to a part of its own).
    pub fn remaining(&self) -> usize {
        self.len - self.next
    }
}

/// A packet's dimensions, read in layout order for all 16 lanes at once: an estimator written
/// over lanes takes each dimension as one row (`values[d]`, lane l at `[l]`), where a
/// lane-by-lane estimator reads its own lane through [`Self::lane`]. Reading past the end is
/// the programming error [`Dims`] reports.
#[derive(Debug)]
pub struct PacketDims<'a> {
    values: &'a LaneValues,
    next: usize,
    end: usize,
}

impl<'a> PacketDims<'a> {
    /// Dimensions `from..to` of a packet's samples.
    pub fn new(values: &'a LaneValues, from: usize, to: usize) -> Self {
        assert!(
            from <= to && to <= MAX_DIMENSIONS,
            "dimensions {from}..{to} of a packet"
        );
        PacketDims {
            values,
            next: from,
            end: to,
        }
    }

    /// The next `N` dimensions of every lane, one row each.
    #[inline(always)]
    pub fn take<const N: usize>(&mut self) -> [&'a [f32; WIDTH]; N] {
        let (values, next) = (self.values, self.next);
        self.skip(N);
        std::array::from_fn(|k| &values[next + k])
    }

    /// Lane `lane`'s dimensions from here to the end, for a part that reads lane by lane;
    /// reading them does not move this cursor (see [`Self::skip`]).
    pub fn lane(&self, lane: usize) -> Dims<'a> {
        Dims::lane(self.values, lane, self.next, self.end)
    }

    /// Moves past `n` dimensions that the lanes read on their own ([`Self::lane`]).
    pub fn skip(&mut self, n: usize) {
        if self.next + n > self.end {
            panic!(
                "a strategy read {n} more dimensions of a packet with {} left: its layout() must declare every dimension it draws",
                self.end - self.next
            );
        }
        self.next += n;
    }

    /// How many dimensions are left.
    pub fn remaining(&self) -> usize {
        self.end - self.next
    }
}

/// Asserts that a generator's packet fill gives each lane its single-sample numbers on every
/// ISA, bit for bit: `fill(isa, out)` runs the packet kernel in that ISA's context.
#[cfg(test)]
pub(crate) fn assert_every_isa_fills_as_one_sample(
    g: &dyn SampleGenerator,
    setup: &Setup,
    keys: &[SampleKey; WIDTH],
    dims: usize,
    fill: impl Fn(crate::simd::Isa, &mut LaneValues),
    context: &str,
) {
    let mut want = [[0.0f32; WIDTH]; MAX_DIMENSIONS];
    for (lane, k) in keys.iter().enumerate() {
        let mut row = [0.0f32; MAX_DIMENSIONS];
        g.fill(setup, *k, &mut row[..dims]);
        set_lane(&mut want, lane, &row[..dims]);
    }
    let bits = |a: &LaneValues| {
        a[..dims]
            .iter()
            .map(|r| r.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    for isa in crate::simd::Isa::available() {
        let mut got = [[0.0f32; WIDTH]; MAX_DIMENSIONS];
        fill(isa, &mut got);
        assert_eq!(bits(&got), bits(&want), "{} {isa:?} {context}", g.name());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::GENERATORS;

    /// A lane's `Dims` over a packet's dimension-major values reads that lane's dimensions,
    /// in order, from the first asked for up to the last (the last lane's last dimension
    /// included), and refuses to read past them.
    #[test]
    fn a_lane_reads_its_own_dimensions_in_order() {
        let mut v: LaneValues = [[0.0; WIDTH]; MAX_DIMENSIONS];
        for (d, row) in v.iter_mut().enumerate() {
            for (lane, x) in row.iter_mut().enumerate() {
                *x = (d * 100 + lane) as f32;
            }
        }
        for lane in [0, 5, WIDTH - 1] {
            let at = |d: usize| (d * 100 + lane) as f32;
            let mut dims = Dims::lane(&v, lane, 2, 7);
            assert_eq!(dims.remaining(), 5);
            assert_eq!(dims.get_1d(), at(2));
            assert_eq!(dims.get_3d(), [at(3), at(4), at(5)]);
            assert_eq!(dims.get_1d(), at(6));
            assert_eq!((dims.used(), dims.remaining()), (5, 0));
            let past = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| dims.get_1d()));
            assert!(past.is_err(), "lane {lane} read past its layout");
            let mut all = Dims::lane(&v, lane, 0, MAX_DIMENSIONS);
            for d in 0..MAX_DIMENSIONS {
                assert_eq!(all.get_1d(), at(d));
            }
        }
    }

    /// A packet's cursor hands out rows in layout order from its first dimension, a lane's
    /// `Dims` from where the cursor stands, and refuses to move past its last dimension.
    #[test]
    fn a_packet_reads_its_dimensions_as_rows_in_order() {
        let mut v: LaneValues = [[0.0; WIDTH]; MAX_DIMENSIONS];
        for (d, row) in v.iter_mut().enumerate() {
            for (lane, x) in row.iter_mut().enumerate() {
                *x = (d * 100 + lane) as f32;
            }
        }
        let mut u = PacketDims::new(&v, 2, 8);
        assert_eq!(u.remaining(), 6);
        let [a] = u.take::<1>();
        assert_eq!(a, &v[2]);
        let [b, c] = u.take::<2>();
        assert_eq!((b, c), (&v[3], &v[4]));
        assert_eq!(
            u.lane(7).get_1d(),
            v[5][7],
            "a lane starts where the packet stands"
        );
        u.skip(2);
        assert_eq!(u.take::<1>()[0], &v[7]);
        assert_eq!(u.remaining(), 0);
        let past = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| u.skip(1)));
        assert!(past.is_err(), "a packet read past its layout");
    }

    /// Every generator's packet fill gives each active lane exactly its single-sample fill (the
    /// renderer fills packets, closed-form checks single samples: both must see the same
    /// numbers).
    #[test]
    fn lanes_fill_as_single_samples() {
        let layout = Layout::of(&[
            Dimension::pair("a"),
            Dimension::one("b"),
            Dimension::pair("c"),
            Dimension::one("d"),
        ]);
        let setup = Setup::image(layout, Some(16), 13, 7);
        let dims = setup.layout.len();
        for g in GENERATORS.iter() {
            for (lanes, index) in [(0xffffu16, 0u64), (0b1010_0110_0101_1001, 5), (1, 15)] {
                let keys: [SampleKey; WIDTH] = std::array::from_fn(|i| SampleKey {
                    // One lane of another stream family: a packet need not share one.
                    seed: if i == 7 { 4 } else { 3 },
                    strategy: 0xabcd,
                    pixel: (i as u64 * 5) % 91,
                    index,
                });
                let mut got = [[-1.0f32; WIDTH]; MAX_DIMENSIONS];
                g.fill_lanes(&setup, &SampleKeys::of(&keys), lanes, dims, &mut got);
                for lane in 0..WIDTH {
                    if lanes & (1 << lane) == 0 {
                        continue;
                    }
                    let mut want = [-1.0f32; MAX_DIMENSIONS];
                    g.fill(&setup, keys[lane], &mut want[..dims]);
                    assert_eq!(
                        got[..dims]
                            .iter()
                            .map(|d| d[lane].to_bits())
                            .collect::<Vec<_>>(),
                        want[..dims].iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                        "{} lane {lane}",
                        g.name()
                    );
                }
            }
        }
    }

    /// FNV-1a's xor-multiply step over each value's 32 bits, in order. Each step is a
    /// bijection of the running hash for a given value (xor, then a product with an odd
    /// number), so changing any one value always changes the digest.
    fn digest(values: &[f32]) -> u64 {
        values.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, x| {
            (h ^ x.to_bits() as u64).wrapping_mul(0x0000_0100_0000_01b3)
        })
    }

    /// Every value a generator gives over a 13 × 7 image at 16 spp (the spp told, as `compare
    /// --spp` tells it) in `mis-power`'s layout (9 dimensions with the camera's), two seeds.
    fn all_fills(g: &dyn SampleGenerator) -> Vec<f32> {
        use crate::strategy::{direction::BSDF_DIMS, light_sampling::LIGHT_DIMS};
        let layout = Layout::of(&LIGHT_DIMS).then(Layout::of(&BSDF_DIMS));
        let setup = Setup::image(layout, Some(16), 13, 7);
        let dims = setup.layout.len();
        let mut out = Vec::new();
        for seed in [1, 2] {
            for pixel in 0..13 * 7 {
                for index in 0..16 {
                    let key = SampleKey {
                        seed,
                        strategy: 0x5eed,
                        pixel,
                        index,
                    };
                    let mut v = [0.0f32; MAX_DIMENSIONS];
                    g.fill(&setup, key, &mut v[..dims]);
                    out.extend_from_slice(&v[..dims]);
                }
            }
        }
        out
    }

    /// Every built-in generator gives the numbers it gave when this test was written
    /// (2026-12-03, 89e057d; the independent and stratified ones since stop 43's seeding of
    /// the random streams, docs/tracer.md), bit for bit: a rewrite of a generator for speed (over lanes, say)
    /// must not change a single value, or every stored result made with it would no longer be
    /// reproducible from its seed.
    #[test]
    fn pinned_fills_are_unchanged() {
        let got: Vec<(&str, u64)> = GENERATORS
            .iter()
            .map(|g| (g.name(), digest(&all_fills(*g))))
            .collect();
        assert_eq!(got, PINNED_FILLS.to_vec(), "a generator's numbers changed");
    }

    /// The independent generator with two of its dimensions in each other's place: the kind
    /// of slip a rewrite makes, with every value still a valid uniform number.
    struct SwappedDims;

    impl SampleGenerator for SwappedDims {
        fn name(&self) -> &'static str {
            "independent"
        }
        fn describe(&self) -> &'static str {
            "independent, dimensions 3 and 4 swapped"
        }
        fn independent_samples(&self) -> bool {
            true
        }
        fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]) {
            crate::sampling::independent::INDEPENDENT.fill(setup, key, out);
            out.swap(3, 4);
        }
    }

    #[test]
    fn pin_catches_swapped_dimensions() {
        let pinned = PINNED_FILLS
            .iter()
            .find(|(n, _)| *n == "independent")
            .unwrap()
            .1;
        assert_ne!(digest(&all_fills(&SwappedDims)), pinned);
    }

    const PINNED_FILLS: [(&str, u64); 4] = [
        ("independent", 15662110126227710957),
        ("stratified", 12991016582870998650),
        ("sobol", 12012633771765355247),
        ("zsobol", 5301747497836344599),
    ];
}
