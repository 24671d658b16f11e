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

/// The CPU model from /proc/cpuinfo, or `unknown` where there is none (non-Linux).
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, prefix: String, template: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len).with_prefix(prefix);
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}
