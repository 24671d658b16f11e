//! The lane layer: a 16-lane f32 vector that runs as 1×16 on AVX-512, 2×8 on AVX2 and as a
//! plain array elsewhere. This module is the only place that touches `std::arch`; kernels are
//! written once, generic over [`Lanes`], and monomorphised inside one `#[target_feature]`
//! entry per ISA ([`run`]), so every intrinsic inlines into the whole kernel.
//!
//! All paths perform the same IEEE operations in the same order (no FMA anywhere, min/max
//! with MINPS/MAXPS semantics), so results are bit-identical across ISAs.

mod avx2;
mod avx512;
mod isa;
mod portable;

pub use isa::Isa;

/// Lane count of a packet.
pub const WIDTH: usize = 16;

/// Bit i = lane i.
pub type Mask = u16;

/// 16 f32 lanes. Static functions on a zero-sized type, so a kernel names its ISA once.
pub trait Lanes: Copy {
    type V: Copy;
    fn splat(x: f32) -> Self::V;
    fn load(a: &[f32; WIDTH]) -> Self::V;
    fn store(v: Self::V, a: &mut [f32; WIDTH]);
    fn add(a: Self::V, b: Self::V) -> Self::V;
    fn sub(a: Self::V, b: Self::V) -> Self::V;
    fn mul(a: Self::V, b: Self::V) -> Self::V;
    fn div(a: Self::V, b: Self::V) -> Self::V;
    /// `if a < b { a } else { b }` per lane (MINPS semantics).
    fn min(a: Self::V, b: Self::V) -> Self::V;
    /// `if a > b { a } else { b }` per lane (MAXPS semantics).
    fn max(a: Self::V, b: Self::V) -> Self::V;
    fn abs(a: Self::V) -> Self::V;
    /// Ordered comparisons (false on NaN), one bit per lane.
    fn lt(a: Self::V, b: Self::V) -> Mask;
    fn le(a: Self::V, b: Self::V) -> Mask;
    fn eq(a: Self::V, b: Self::V) -> Mask;
    /// Lane i = `a` where bit i of `m` is set, else `b`.
    fn select(m: Mask, a: Self::V, b: Self::V) -> Self::V;
}

/// A computation generic over the lane type; [`run`] instantiates it for one ISA.
pub trait Kernel {
    type Out;
    fn run<L: Lanes>(self) -> Self::Out;
}

/// Runs a kernel on an ISA. `Isa` values only come from [`Isa::detect`] / [`Isa::parse`],
/// which check the CPU, so the unsafe calls below never execute unsupported instructions.
#[inline]
pub fn run<K: Kernel>(isa: Isa, k: K) -> K::Out {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 if isa.supported() => {
            // SAFETY: the CPU reports avx512f.
            unsafe { avx512::entry(k) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if isa.supported() => {
            // SAFETY: the CPU reports avx2.
            unsafe { avx2::entry(k) }
        }
        _ => k.run::<portable::Portable>(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Probe([f32; WIDTH], [f32; WIDTH]);

    impl Kernel for Probe {
        type Out = (Vec<[f32; WIDTH]>, Vec<Mask>);
        fn run<L: Lanes>(self) -> Self::Out {
            let (a, b) = (L::load(&self.0), L::load(&self.1));
            let vs = [
                L::add(a, b),
                L::sub(a, b),
                L::mul(a, b),
                L::div(a, b),
                L::min(a, b),
                L::max(a, b),
                L::abs(a),
                L::select(0b1010_0101_1100_0011, a, b),
            ];
            let out = vs
                .iter()
                .map(|&v| {
                    let mut o = [0.0; WIDTH];
                    L::store(v, &mut o);
                    o
                })
                .collect();
            (out, vec![L::lt(a, b), L::le(a, b), L::eq(a, b)])
        }
    }

    /// Every available ISA gives bit-identical results to the portable path.
    #[test]
    fn isas_agree_bit_for_bit() {
        let a: [f32; WIDTH] = std::array::from_fn(|i| (i as f32 - 7.5) * 0.37);
        let b: [f32; WIDTH] = std::array::from_fn(|i| {
            if i % 3 == 0 {
                a[i]
            } else {
                1.0 + i as f32 * -0.21
            }
        });
        let want = run(Isa::Portable, Probe(a, b));
        assert_eq!(want.1[2].count_ones(), 6);
        for isa in Isa::available() {
            let got = run(isa, Probe(a, b));
            for (x, y) in got.0.iter().zip(&want.0) {
                let (x, y): (Vec<u32>, Vec<u32>) = (
                    x.iter().map(|f| f.to_bits()).collect(),
                    y.iter().map(|f| f.to_bits()).collect(),
                );
                assert_eq!(x, y, "{isa:?}");
            }
            assert_eq!(got.1, want.1, "{isa:?}");
        }
    }
}
