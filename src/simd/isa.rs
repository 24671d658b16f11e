//! Which instruction set the lane layer runs on: detected once, overridable by `--isa` or
//! the `DIBENCH_ISA` environment variable.

use crate::error::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    Avx512,
    Avx2,
    Portable,
}

impl Isa {
    pub const ALL: [Isa; 3] = [Isa::Avx512, Isa::Avx2, Isa::Portable];

    pub fn name(self) -> &'static str {
        match self {
            Isa::Avx512 => "avx512",
            Isa::Avx2 => "avx2",
            Isa::Portable => "portable",
        }
    }

    /// Whether this CPU can run the path (run-time detection; `std` caches the answer).
    pub fn supported(self) -> bool {
        match self {
            Isa::Portable => true,
            #[cfg(target_arch = "x86_64")]
            // The AVX-512 path uses F and DQ (`vpmullq`).
            Isa::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512dq")
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// Supported ISAs, best first.
    pub fn available() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.supported()).collect()
    }

    /// The best supported ISA (no allocation, no environment: for per-packet use where every
    /// ISA gives the same bits).
    pub fn best() -> Isa {
        Isa::ALL
            .into_iter()
            .find(|i| i.supported())
            .unwrap_or(Isa::Portable)
    }

    /// The best supported ISA, unless `DIBENCH_ISA` names one.
    pub fn detect() -> Result<Isa> {
        match std::env::var("DIBENCH_ISA") {
            Ok(s) if !s.is_empty() => Isa::parse(&s).map_err(|e| e.prefixed("DIBENCH_ISA")),
            _ => Ok(Isa::available()[0]),
        }
    }

    /// Parses a name and checks the CPU has it.
    pub fn parse(s: &str) -> Result<Isa> {
        let isa = Isa::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| {
                Error::Usage(format!("unknown ISA `{s}` (known: avx512, avx2, portable)"))
            })?;
        if !isa.supported() {
            let have: Vec<_> = Isa::available().iter().map(|i| i.name()).collect();
            let needs = match isa {
                Isa::Avx512 => " (it needs avx512f and avx512dq)",
                _ => "",
            };
            return Err(Error::Backend(format!(
                "ISA `{s}` is not supported by this CPU{needs} (available: {})",
                have.join(", ")
            )));
        }
        Ok(isa)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_rejects_unknown_and_accepts_portable() {
        assert!(Isa::parse("sse9").is_err());
        assert_eq!(Isa::parse("portable").unwrap(), Isa::Portable);
        for isa in Isa::ALL {
            assert_eq!(Isa::parse(isa.name()).is_ok(), isa.supported());
        }
    }
}
