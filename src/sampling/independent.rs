//! Independent uniform samples: each (seed, strategy, pixel, index) key seeds its own PCG32
//! stream (O'Neill 2014), whose outputs fill the dimensions in order. Every dimension of every
//! sample is independent of every other, so per-pixel sample variances are variances of i.i.d.
//! draws — the assumption the harness's error predictions make.

use super::generator::{SampleGenerator, SampleKey};
use super::stream::SampleStream;

pub struct Independent;

pub static INDEPENDENT: Independent = Independent;

impl SampleGenerator for Independent {
    fn name(&self) -> &'static str {
        "independent"
    }

    fn describe(&self) -> &'static str {
        "independent uniform numbers, one PCG32 stream per (seed, strategy, pixel, pass)"
    }

    fn fill(&self, key: SampleKey, out: &mut [f32]) {
        let mut s = SampleStream::new(key.seed, key.strategy, key.pixel, key.index);
        for x in out {
            *x = s.next_1d();
        }
    }
}
