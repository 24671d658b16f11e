use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    // First: quiet SIGPIPE, reopened standard descriptors, the Ctrl-C handler (`interrupt`).
    dibench::interrupt::install();
    let cli = match dibench::cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.kind() == clap::error::ErrorKind::InvalidUtf8 => {
            // clap does not say which argument; name it.
            dibench::interrupt::note(&format!("error: {}", dibench::cli::invalid_utf8_args()));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    match dibench::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            dibench::interrupt::note(&format!("error: {e}"));
            match e {
                // 128 + SIGINT, as a shell reports a command stopped by Ctrl-C.
                dibench::error::Error::Interrupted(_) => ExitCode::from(130),
                _ => ExitCode::FAILURE,
            }
        }
    }
}
