//! The benchmark commands: high-sample references and equal-time comparisons.

pub mod compare;
pub mod crosscheck;
pub mod options;
pub mod pilot;
pub mod rays;
pub mod raysets;
pub mod reference;
pub mod shard;
pub mod summary;

/// Build provenance written into every metadata file.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
pub const COMMIT: &str = env!("DIBENCH_COMMIT");
pub const RUSTC: &str = env!("DIBENCH_RUSTC");

/// The CPU as /proc/cpuinfo describes it, with its family, model and stepping, and the widest
/// ISA the packet tracer runs on it, e.g. `AMD EPYC (family 25, model 1, stepping 1; avx2)`:
/// a virtual machine's name can be as bare as "AMD EPYC", which covers Zen 2 to Zen 5, with and
/// without AVX-512, and timings differ between them by 2× and more. `unknown` (and the ISA)
/// where there is no /proc/cpuinfo.
pub fn cpu_model() -> String {
    let isa = crate::simd::Isa::best().name();
    match std::fs::read_to_string("/proc/cpuinfo") {
        Ok(text) => describe_cpu(&text, isa),
        Err(_) => format!("unknown ({isa})"),
    }
}

/// [`cpu_model`] of a /proc/cpuinfo text (its first processor's fields) and an ISA name.
fn describe_cpu(cpuinfo: &str, isa: &str) -> String {
    let field = |name: &str| {
        cpuinfo
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .filter_map(|l| l.split_once(':'))
            .find(|(k, _)| k.trim() == name)
            .map(|(_, v)| v.trim().to_string())
    };
    let name = field("model name").unwrap_or_else(|| "unknown".into());
    let ids: Vec<String> = [
        ("family", "cpu family"),
        ("model", "model"),
        ("stepping", "stepping"),
    ]
    .iter()
    .filter_map(|(label, key)| field(key).map(|v| format!("{label} {v}")))
    .collect();
    if ids.is_empty() {
        format!("{name} ({isa})")
    } else {
        format!("{name} ({}; {isa})", ids.join(", "))
    }
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, prefix: String, template: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len).with_prefix(prefix);
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::describe_cpu;

    /// The family, model and stepping are the first processor's, read by exact field name
    /// (`model` is not `model name`); a bare name without them still names the ISA.
    #[test]
    fn the_cpu_is_described_by_family_model_and_stepping() {
        // `model name` before `model`, so a prefix match would read the name as the model.
        let info = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\n\
                    model name\t: AMD EPYC\nmodel\t\t: 1\nstepping\t: 1\n\n\
                    processor\t: 1\ncpu family\t: 26\nmodel\t\t: 2\nmodel name\t: other\n";
        assert_eq!(
            describe_cpu(info, "avx2"),
            "AMD EPYC (family 25, model 1, stepping 1; avx2)"
        );
        assert_eq!(
            describe_cpu("model name\t: Some CPU\n", "portable"),
            "Some CPU (portable)"
        );
        assert_eq!(describe_cpu("", "avx512"), "unknown (avx512)");
    }
}
